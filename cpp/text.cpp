#include "core.hpp"

namespace mesh_normal {

void bind_text(nb::module_& m) { (void)m; }

}  // namespace mesh_normal
