#include "core.hpp"

namespace mesh_normal {

void bind_visibility(nb::module_& m) { (void)m; }

}  // namespace mesh_normal
