#include "core.hpp"

namespace mesh_normal {

void bind_topology(nb::module_& m) { (void)m; }

}  // namespace mesh_normal
