// mesh_normal._core: the compiled kernels. Python keeps the API, the checks at the edge, the
// reports and the words (mesh_normal/); each kernel here takes checked arrays, releases the GIL
// while it runs, and returns arrays.
#include <cstdlib>
#include <string>

#include "core.hpp"

namespace mesh_normal {

namespace {

int threads_from_environment() {
  const char* text = std::getenv("MESH_NORMAL_THREADS");
  if (text != nullptr) {
    char* end = nullptr;
    const long value = std::strtol(text, &end, 10);
    if (end != text && *end == '\0' && value >= 1 && value <= 1024) {
      return static_cast<int>(value);
    }
  }
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace

std::atomic<int> thread_count{threads_from_environment()};

}  // namespace mesh_normal

NB_MODULE(_core, m) {
  namespace nb = nanobind;
  m.doc() = "The compiled kernels of mesh_normal (C++17, nanobind).";
  m.def(
      "threads", [] { return mesh_normal::thread_count.load(); },
      "How many threads a parallel kernel uses (MESH_NORMAL_THREADS, else every core).");
  m.def(
      "set_threads",
      [](int count) {
        if (count < 1 || count > 1024) {
          throw nb::value_error("the number of threads must be from 1 to 1024");
        }
        mesh_normal::thread_count.store(count);
      },
      nb::arg("count"), "Set how many threads a parallel kernel uses.");
  mesh_normal::bind_faces(m);
  mesh_normal::bind_topology(m);
  mesh_normal::bind_visibility(m);
  mesh_normal::bind_weld(m);
  mesh_normal::bind_text(m);
  mesh_normal::bind_points(m);
  mesh_normal::bind_orient(m);
  mesh_normal::bind_nearest(m);
}
