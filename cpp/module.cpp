// mesh_normal._core: the compiled kernels. Python keeps the API, the checks at the edge, the
// reports and the words (mesh_normal/); each kernel here takes checked arrays, releases the GIL
// while it runs, and returns arrays.
#include "core.hpp"

NB_MODULE(_core, m) {
  m.doc() = "The compiled kernels of mesh_normal (C++17, nanobind).";
  mesh_normal::bind_faces(m);
  mesh_normal::bind_topology(m);
  mesh_normal::bind_visibility(m);
  mesh_normal::bind_weld(m);
  mesh_normal::bind_text(m);
  mesh_normal::bind_points(m);
}
