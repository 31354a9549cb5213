#include "core.hpp"

namespace mesh_normal {

void bind_faces(nb::module_& m) { (void)m; }

}  // namespace mesh_normal
