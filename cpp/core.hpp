// What every topic of the compiled core shares: the array types at the boundary, the
// parallel loop, and each topic's binding function (called from module.cpp).
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

namespace mesh_normal {

namespace nb = nanobind;

// Arrays from Python: C-contiguous NumPy arrays on the CPU. `const` element types accept
// read-only arrays. Arguments are bound with .noconvert(), so a wrong dtype, order or shape is a
// TypeError instead of a silent copy.
template <typename T, typename... Shape>
using In = nb::ndarray<const T, nb::numpy, nb::c_contig, nb::device::cpu, Shape...>;
// Arrays written in place (the caller allocates them).
template <typename T, typename... Shape>
using Out = nb::ndarray<T, nb::numpy, nb::c_contig, nb::device::cpu, Shape...>;

// A new NumPy array of `count` rows of `columns` values that owns `data` (allocated with new[]).
template <typename T>
nb::ndarray<nb::numpy, T> owned(T* data, std::size_t count, std::size_t columns = 0) {
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
  if (columns == 0) {
    return nb::ndarray<nb::numpy, T>(data, {count}, owner);
  }
  return nb::ndarray<nb::numpy, T>(data, {count, columns}, owner);
}

// The same from a buffer still held by a unique_ptr, so that a throw between allocating the
// buffers of a kernel's results and handing them over frees them: the capsule is made first.
template <typename T>
nb::ndarray<nb::numpy, T> owned(std::unique_ptr<T[]> data, std::size_t count,
                                std::size_t columns = 0) {
  nb::capsule owner(data.get(), [](void* p) noexcept { delete[] static_cast<T*>(p); });
  T* held = data.release();
  if (columns == 0) {
    return nb::ndarray<nb::numpy, T>(held, {count}, owner);
  }
  return nb::ndarray<nb::numpy, T>(held, {count, columns}, owner);
}

// Forced inline: a per-element helper called through memory costs a kernel about a fifth of
// its time, and GCC drops a call to a function that only prefetches (it finds no effect).
#if defined(__GNUC__) || defined(__clang__)
#define MESH_NORMAL_INLINE inline __attribute__((always_inline))
#else
#define MESH_NORMAL_INLINE inline
#endif

// Asks the CPU to bring `address` into its cache ahead of a scattered access (a loop over faces
// reads points far apart in a large, shuffled mesh; a hash table's slots are random). Only a
// hint, never a fault: the results do not depend on it; where the compiler has no such
// builtin, nothing.
MESH_NORMAL_INLINE void prefetch(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(address, 0, 3);
#else
  (void)address;
#endif
}

// The same, for memory about to be written.
MESH_NORMAL_INLINE void prefetch_for_write(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(address, 1, 3);
#else
  (void)address;
#endif
}

// How many threads a parallel kernel uses: MESH_NORMAL_THREADS when the module is loaded, else
// every core; set_threads() changes it (module.cpp).
extern std::atomic<int> thread_count;

// Runs body(begin, end) over [0, count) in contiguous chunks, one per thread, each chunk at least
// `grain` long. Each chunk writes its own rows, so the results are the same bits for any number
// of threads. Small inputs run on the calling thread.
template <typename Body>
void parallel_for(std::int64_t count, std::int64_t grain, const Body& body) {
  const std::int64_t most = std::max(1, thread_count.load(std::memory_order_relaxed));
  const std::int64_t chunks = std::min(most, std::max<std::int64_t>(1, count / grain));
  if (chunks <= 1) {
    body(std::int64_t{0}, count);
    return;
  }
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(chunks - 1));
  const std::int64_t step = (count + chunks - 1) / chunks;
  for (std::int64_t c = 1; c < chunks; ++c) {
    const std::int64_t begin = std::min(count, c * step);
    const std::int64_t end = std::min(count, begin + step);
    threads.emplace_back([&body, begin, end] { body(begin, end); });
  }
  body(std::int64_t{0}, std::min(count, step));
  for (auto& thread : threads) {
    thread.join();
  }
}

void bind_faces(nb::module_& m);       // faces.cpp: face normals, vertex and corner sums, bounds
void bind_topology(nb::module_& m);    // topology.cpp: edges, patches, orientation
void bind_visibility(nb::module_& m);  // visibility.cpp: rays and boxes
void bind_weld(nb::module_& m);        // weld.cpp: welding and hashing, polygon shapes
void bind_text(nb::module_& m);        // text.cpp: text and binary parsing
void bind_points(nb::module_& m);      // points.cpp: point neighbourhoods, PCD's LZF
void bind_orient(nb::module_& m);      // orient.cpp: signs of point normals along a tree
void bind_nearest(nb::module_& m);     // nearest.cpp: a k-d tree's k nearest neighbours

}  // namespace mesh_normal
