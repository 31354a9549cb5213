#include "core.hpp"

namespace mesh_normal {

void bind_weld(nb::module_& m) { (void)m; }

}  // namespace mesh_normal
