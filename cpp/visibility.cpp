// Visibility from outside: rays cast from sample faces through a bounding-volume hierarchy of
// every face (mesh_normal/mesh/visibility.py holds the method and its constants). The faces are
// ordered along a Morton curve of their centroids, the order split where the codes' highest
// differing bit turns, and each ray searches the boxes depth first, the nearer child first,
// until any hit ends it.
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <tuple>
#include <utility>

#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

#include "core.hpp"

namespace mesh_normal {

namespace {

using Int = std::int64_t;
using Points = In<double, nb::shape<-1, 3>>;
using Faces = In<Int, nb::shape<-1, 3>>;
using Codes = In<Int, nb::shape<-1>>;
template <typename T>
using Array = nb::ndarray<nb::numpy, T>;

constexpr double kInf = std::numeric_limits<double>::infinity();
// What a ray meets (see blocked()).
enum Met { kClear, kHit, kUnsure };
// A hit this close (in barycentric coordinates, or in the sine of the angle to the face's
// plane) to a face's edge or plane is unsure: another position, turn or scale of the mesh may
// round it the other way. Far above rounding (about 1e-15 here), far below a real edge.
constexpr double kUnsureBand = 0x1p-30;
// Each box is larger than its faces' by this: more than an unsure hit can lie outside a face
// (2 kUnsureBand times its longest edge, at most 4 in the unit box).
constexpr double kPad = 0x1p-26;
// Morton codes sorted per pass of the radix sort: three passes of 10 bits (1024 buckets each,
// whose write positions stay in the cache).
constexpr int kDigit = 10;
// Faces per chunk of the parallel loops over faces and nodes.
constexpr Int kGrain = 4096;

// The vertices (scaled into the unit box) and the faces, as read by every kernel here.
struct Mesh {
  const double* unit;
  Int vertices;
  const Int* faces;
  Int count;
  // The vertex number at a face's corner. One that is not a row of the points sets `bad`
  // and reads row 0 instead: each kernel's first pass over the faces checks them so, and the
  // kernel refuses them once that pass is done.
  Int vertex(Int face, int corner, bool& bad) const {
    const Int number = faces[3 * face + corner];
    const bool outside = static_cast<std::uint64_t>(number) >= static_cast<std::uint64_t>(vertices);
    bad = bad || outside;
    return outside ? 0 : number;
  }
  // A coordinate of a face's corner, once vertex() has passed every face.
  double at(Int face, int corner, int axis) const {
    return unit[3 * faces[3 * face + corner] + axis];
  }
};

constexpr const char* kBadVertex = "a face names a vertex that the points do not have";

Mesh mesh_of(const Points& unit, const Faces& faces) {
  const Mesh mesh{unit.data(), static_cast<Int>(unit.shape(0)), faces.data(),
                  static_cast<Int>(faces.shape(0))};
  if (mesh.count > 0 && mesh.vertices == 0) {
    throw nb::index_error(kBadVertex);
  }
  return mesh;
}

// The Morton code of a face's centroid on a 1024**3 grid over [-1, 1]**3: each axis's 10-bit
// cell spread to every third bit (bit b to bit 3 b + axis).
Int morton(const Mesh& mesh, Int face, bool& bad) {
  const double* a = mesh.unit + 3 * mesh.vertex(face, 0, bad);
  const double* b = mesh.unit + 3 * mesh.vertex(face, 1, bad);
  const double* c = mesh.unit + 3 * mesh.vertex(face, 2, bad);
  Int value = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double total = a[axis] + b[axis];
    total += c[axis];
    const double scaled = (total / 3 + 1.0) * 512.0;
    // Truncated towards zero, then clamped to [0, 1023]; NaN in cell 0.
    Int cell = scaled >= 1023.0 ? 1023 : (scaled >= 1.0 ? static_cast<Int>(scaled) : 0);
    cell = (cell | (cell << 16)) & 0x30000FF;
    cell = (cell | (cell << 8)) & 0x300F00F;
    cell = (cell | (cell << 4)) & 0x30C30C3;
    cell = (cell | (cell << 2)) & 0x9249249;
    value |= cell << axis;
  }
  return value;
}

// The stable order of `codes` (30-bit, non-negative) and the codes in that order, by a
// least-significant-digit radix sort: each pass is stable, so equal codes keep their faces in
// file order. `codes` is used as scratch space.
void radix_order(Int* codes, Int count, Int* order, Int* ordered) {
  constexpr Int buckets = Int{1} << kDigit;
  constexpr Int mask = buckets - 1;
  std::vector<std::array<Int, buckets>> starts(3, std::array<Int, buckets>{});
  for (Int face = 0; face < count; ++face) {
    for (int digit = 0; digit < 3; ++digit) {
      ++starts[digit][(codes[face] >> (kDigit * digit)) & mask];
    }
  }
  for (auto& digit : starts) {
    Int total = 0;
    for (auto& start : digit) {
      total += std::exchange(start, total);
    }
  }
  // Pass 1 reads the codes in file order and writes them and their faces into ordered and
  // order; pass 2 moves them back into codes and a scratch order; pass 3 into the results.
  std::vector<Int> scratch(static_cast<std::size_t>(count));
  for (Int face = 0; face < count; ++face) {
    const Int at = starts[0][codes[face] & mask]++;
    ordered[at] = codes[face];
    order[at] = face;
  }
  for (Int k = 0; k < count; ++k) {
    const Int at = starts[1][(ordered[k] >> kDigit) & mask]++;
    codes[at] = ordered[k];
    scratch[at] = order[k];
  }
  for (Int k = 0; k < count; ++k) {
    const Int at = starts[2][(codes[k] >> (2 * kDigit)) & mask]++;
    ordered[at] = codes[k];
    order[at] = scratch[k];
  }
}

// The hierarchy: per node its box (low x, y, z, high x, y, z), children (-1, -1 for a leaf)
// and span of `order`; the faces' corners in that order where the rays read them so (nine
// values a face, so that a leaf's faces lie side by side in memory), else none.
struct Hierarchy {
  const Int* order = nullptr;
  Int nodes = 0;
  Int depth = 0;  // the most edges from the root to a leaf
  std::unique_ptr<double[]> boxes;
  std::unique_ptr<Int[]> children;
  std::unique_ptr<Int[]> spans;
  std::unique_ptr<double[]> corners;
  Int corner_rows = 0;
  bool bad_vertex = false;  // a face names a vertex that the points do not have
};

// Splits each span where the highest bit that differs in its sorted Morton codes turns (the
// halves of an octree cell; in the middle where the codes are all equal) down to leaves of at
// most `leaf` faces. Nodes are made in breadth order: children after their parent.
void split(const Int* codes, Int count, Int leaf, Hierarchy& tree) {
  std::vector<std::array<Int, 2>> children;
  std::vector<std::array<Int, 2>> spans{{0, count}};
  Int level_end = 1;
  for (Int node = 0; node < static_cast<Int>(spans.size()); ++node) {
    if (node == level_end) {
      ++tree.depth;
      level_end = static_cast<Int>(spans.size());
    }
    const Int lo = spans[node][0];
    const Int hi = spans[node][1];
    if (hi - lo <= leaf) {
      children.push_back({-1, -1});
      continue;
    }
    const auto differ = static_cast<std::uint64_t>(codes[lo] ^ codes[hi - 1]);
    Int mid = (lo + hi) / 2;
    if (differ != 0) {
      int bit = 0;
      while (differ >> (bit + 1)) {
        ++bit;
      }
      // The codes of the span share every bit above `bit`: the first with it set.
      const Int first = static_cast<Int>((static_cast<std::uint64_t>(codes[hi - 1]) >> bit) << bit);
      mid = std::lower_bound(codes + lo, codes + hi, first) - codes;
    }
    const auto used = static_cast<Int>(spans.size());
    children.push_back({used, used + 1});
    spans.push_back({lo, mid});
    spans.push_back({mid, hi});
  }
  tree.nodes = static_cast<Int>(spans.size());
  tree.children.reset(new Int[2 * tree.nodes]);
  tree.spans.reset(new Int[2 * tree.nodes]);
  std::memcpy(tree.children.get(), children.data(), sizeof(Int) * 2 * tree.nodes);
  std::memcpy(tree.spans.get(), spans.data(), sizeof(Int) * 2 * tree.nodes);
}

// corners[k] = the three corners of face order[k], one after the other.
void gather_corners(const Mesh& mesh, Hierarchy& tree) {
  tree.corner_rows = mesh.count;
  tree.corners.reset(new double[9 * mesh.count]);
  double* corners = tree.corners.get();
  std::atomic<bool> refused{false};
  parallel_for(mesh.count, kGrain, [&](Int begin, Int end) {
    bool bad = false;
    for (Int k = begin; k < end; ++k) {
      for (int corner = 0; corner < 3; ++corner) {
        const double* point = mesh.unit + 3 * mesh.vertex(tree.order[k], corner, bad);
        std::copy(point, point + 3, corners + 9 * k + 3 * corner);
      }
    }
    if (bad) {
      refused.store(true);
    }
  });
  tree.bad_vertex = refused.load();
}

// Widens `box` (low x, y, z, high x, y, z) to `count` faces' corners (nine values a face),
// each padded by kPad.
void widen(std::array<double, 6>& box, const double* values, Int count) {
  for (Int k = 0; k < 9 * count; k += 3) {
    for (int axis = 0; axis < 3; ++axis) {
      box[axis] = std::min(box[axis], values[k + axis] - kPad);
      box[axis + 3] = std::max(box[axis + 3], values[k + axis] + kPad);
    }
  }
}

// Each node's box, padded by kPad: the leaves' on every core, then the others from the leaves
// up (children come after their parent). Without gathered corners a leaf's faces are read in
// batches, their vertex numbers first and then their points: loads that do not wait on each
// other, so that many of them are in flight at once (the faces lie far apart in memory).
void make_boxes(const Mesh& mesh, Hierarchy& tree) {
  constexpr Int batch = 64;
  tree.boxes.reset(new double[6 * tree.nodes]);
  double* boxes = tree.boxes.get();
  const Int* children = tree.children.get();
  const Int* spans = tree.spans.get();
  const double* corners = tree.corners.get();
  std::atomic<bool> refused{false};
  parallel_for(tree.nodes, kGrain, [&](Int begin, Int end) {
    bool bad = false;
    std::array<Int, 3 * batch> numbers;
    std::array<double, 9 * batch> values;
    for (Int node = begin; node < end; ++node) {
      if (children[2 * node] >= 0) {
        continue;
      }
      std::array<double, 6> box{kInf, kInf, kInf, -kInf, -kInf, -kInf};
      for (Int k = spans[2 * node]; k < spans[2 * node + 1]; k += batch) {
        const Int count = std::min(batch, spans[2 * node + 1] - k);
        if (corners != nullptr) {
          widen(box, corners + 9 * k, count);
          continue;
        }
        for (Int i = 0; i < 3 * count; ++i) {
          numbers[i] = mesh.vertex(tree.order[k + i / 3], static_cast<int>(i % 3), bad);
        }
        for (Int i = 0; i < 9 * count; ++i) {
          values[i] = mesh.unit[3 * numbers[i / 3] + i % 3];
        }
        widen(box, values.data(), count);
      }
      std::copy(box.begin(), box.end(), boxes + 6 * node);
    }
    if (bad) {
      refused.store(true);
    }
  });
  tree.bad_vertex = tree.bad_vertex || refused.load();
  for (Int node = tree.nodes - 1; node >= 0; --node) {
    const Int left = children[2 * node];
    const Int right = children[2 * node + 1];
    if (left >= 0) {
      for (int axis = 0; axis < 3; ++axis) {
        const double* one = boxes + 6 * left;
        const double* other = boxes + 6 * right;
        boxes[6 * node + axis] = std::min(one[axis], other[axis]);
        boxes[6 * node + axis + 3] = std::max(one[axis + 3], other[axis + 3]);
      }
    }
  }
}

// Refuses Morton codes and an order that do not belong to the faces: the split needs the codes
// sorted (else a span may not shrink), and the order names faces.
void check_order(const Mesh& mesh, const Codes& codes, const Codes& order, Int leaf) {
  const Int count = mesh.count;
  if (static_cast<Int>(codes.shape(0)) != count || static_cast<Int>(order.shape(0)) != count) {
    throw nb::value_error("the Morton codes and order must have one value for each face");
  }
  if (leaf < 1) {
    throw nb::value_error("a leaf of the hierarchy holds at least one face");
  }
  const Int* code = codes.data();
  if (!std::is_sorted(code, code + count)) {
    throw nb::value_error("the Morton codes must be in increasing order");
  }
  for (Int k = 0; k < count; ++k) {
    if (static_cast<std::uint64_t>(order.data()[k]) >= static_cast<std::uint64_t>(count)) {
      throw nb::index_error("the Morton order names a face that there is not");
    }
  }
}

Hierarchy build(const Mesh& mesh, const Int* codes, const Int* order, Int leaf, bool gather) {
  Hierarchy tree;
  tree.order = order;
  split(codes, mesh.count, leaf, tree);
  if (gather) {
    gather_corners(mesh, tree);
  }
  make_boxes(mesh, tree);
  return tree;
}

// A ray: its origin, direction and 1 / direction (infinite where the direction is zero).
struct Ray {
  std::array<double, 3> origin;
  std::array<double, 3> direction;
  std::array<double, 3> inverse;
};

// Where the ray enters the box (infinity if it misses it), at t_min or later. Where the
// direction is zero along an axis the slab test is made on the origin alone (0 * inf is NaN).
double entry(const double* box, const Ray& ray, double t_min) {
  double near = t_min;
  double far = kInf;
  for (int axis = 0; axis < 3; ++axis) {
    const double o = ray.origin[axis];
    const double inv = ray.inverse[axis];
    const double lo = box[axis];
    const double hi = box[axis + 3];
    if (std::isinf(inv)) {
      if (o < lo || o > hi) {
        return kInf;
      }
      continue;
    }
    double t1 = (lo - o) * inv;
    double t2 = (hi - o) * inv;
    if (t1 > t2) {
      std::swap(t1, t2);
    }
    near = std::max(near, t1);
    far = std::min(far, t2);
  }
  return near <= far ? near : kInf;
}

// What the ray meets in face k of the hierarchy's order, whose corners are a, b, c.
Met meet(const Ray& ray, const double* a, const double* b, const double* c, double t_min) {
  const double band = kUnsureBand;
  const double dx = ray.direction[0], dy = ray.direction[1], dz = ray.direction[2];
  const double e1x = b[0] - a[0], e1y = b[1] - a[1], e1z = b[2] - a[2];
  const double e2x = c[0] - a[0], e2y = c[1] - a[1], e2z = c[2] - a[2];
  const double px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
  // det = -d . (e1 x e2): the sine of the angle between the ray and the face's plane, times
  // twice the face's area.
  const double det = e1x * px + e1y * py + e1z * pz;
  const double nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
  const double twice = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (twice == 0.0) {
    return kClear;
  }
  const double sx = ray.origin[0] - a[0], sy = ray.origin[1] - a[1], sz = ray.origin[2] - a[2];
  if (std::abs(det) <= band * twice) {  // along the face's plane: it may just touch it
    return std::abs(sx * nx + sy * ny + sz * nz) <= band * twice * 4.0 ? kUnsure : kClear;
  }
  const double inverse_det = 1.0 / det;
  const double u = (sx * px + sy * py + sz * pz) * inverse_det;
  if (u < -band || u > 1.0 + band) {
    return kClear;
  }
  const double qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
  const double v = (dx * qx + dy * qy + dz * qz) * inverse_det;
  if (v < -band || u + v > 1.0 + band) {
    return kClear;
  }
  const double t = (e2x * qx + e2y * qy + e2z * qz) * inverse_det;
  if (t < t_min * 0.5) {
    return kClear;
  }
  if (u < band || v < band || u + v > 1.0 - band || t < t_min * 2.0) {
    return kUnsure;  // on an edge or a corner, or near t_min: rounding decides
  }
  return kHit;
}

// Whether the ray hits a face other than `own` farther than t_min: kClear (no), kHit (yes) or
// kUnsure (only within kUnsureBand of a face's edge, of its plane or of t_min). Depth first,
// the nearer child first, so that a hit is found early and ends the search. `stack` holds
// depth + 2 nodes: each level keeps at most the sibling it has not entered yet.
Met blocked(const Mesh& mesh, const Hierarchy& tree, Int own, const Ray& ray, double t_min,
            Int* stack) {
  const double* boxes = tree.boxes.get();
  if (std::isinf(entry(boxes, ray, t_min))) {
    return kClear;
  }
  const Int* children = tree.children.get();
  const Int* spans = tree.spans.get();
  const double* corners = tree.corners.get();
  bool unsure = false;
  Int top = 0;
  stack[0] = 0;
  while (top >= 0) {
    const Int node = stack[top--];
    Int left = children[2 * node];
    Int right = children[2 * node + 1];
    if (left >= 0) {
      double near = entry(boxes + 6 * left, ray, t_min);
      double far = entry(boxes + 6 * right, ray, t_min);
      if (near > far) {
        std::swap(left, right);
        std::swap(near, far);
      }
      if (!std::isinf(far)) {
        stack[++top] = right;
      }
      if (!std::isinf(near)) {
        stack[++top] = left;
      }
      continue;
    }
    for (Int k = spans[2 * node]; k < spans[2 * node + 1]; ++k) {
      const Int face = tree.order[k];
      if (face == own) {
        continue;
      }
      std::array<double, 9> read;
      const double* corner = corners + 9 * k;
      if (corners == nullptr) {  // the same values, from the points
        for (int c = 0; c < 9; ++c) {
          read[c] = mesh.at(face, c / 3, c % 3);
        }
        corner = read.data();
      }
      const Met met = meet(ray, corner, corner + 3, corner + 6, t_min);
      if (met == kHit) {
        return kHit;
      }
      unsure = unsure || met == kUnsure;
    }
  }
  return unsure ? kUnsure : kClear;
}

// The rays of each sample face: what they met, per side.
struct Cast {
  double* escaped;  // (s, 2): share of rays that surely escape, + side then - side
  double* unsure;   // (s, 2): share of rays that may escape or not
  double* weights;  // (s,): the face's area
  bool* against;    // (s,): whether the face is wound against its vertices' increasing order
};

// For one sample face: the share of its rays that surely escape, and of those unsure, on each
// side of its plane (+ and - of the normal of its vertices in increasing order), its area, and
// whether it is wound against that order. A face of no area or no first edge casts nothing.
void cast_one(const Mesh& mesh, const Hierarchy& tree, Int s, Int face, const double* pattern,
              Int directions, double t_min, const Cast& out, Int* stack) {
  Int i = mesh.faces[3 * face], j = mesh.faces[3 * face + 1], k = mesh.faces[3 * face + 2];
  // Sort the vertex numbers; each swap reverses the winding.
  bool odd = false;
  const auto order = [&odd](Int& low, Int& high) {
    if (low > high) {
      std::swap(low, high);
      odd = !odd;
    }
  };
  order(i, j);
  order(j, k);
  order(i, j);
  out.against[s] = odd;
  const double* pi = mesh.unit + 3 * i;
  const double* pj = mesh.unit + 3 * j;
  const double* pk = mesh.unit + 3 * k;
  double ux = pj[0] - pi[0], uy = pj[1] - pi[1], uz = pj[2] - pi[2];
  const double vx = pk[0] - pi[0], vy = pk[1] - pi[1], vz = pk[2] - pi[2];
  double mx = uy * vz - uz * vy, my = uz * vx - ux * vz, mz = ux * vy - uy * vx;
  const double twice = std::sqrt(mx * mx + my * my + mz * mz);
  const double along = std::sqrt(ux * ux + uy * uy + uz * uz);
  if (twice == 0.0 || along == 0.0) {
    return;
  }
  out.weights[s] = twice / 2;
  mx = mx / twice, my = my / twice, mz = mz / twice;
  ux = ux / along, uy = uy / along, uz = uz / along;
  const double wx = my * uz - mz * uy, wy = mz * ux - mx * uz, wz = mx * uy - my * ux;
  Ray ray{};
  for (int axis = 0; axis < 3; ++axis) {
    ray.origin[axis] = (pi[axis] + pj[axis] + pk[axis]) / 3;
  }
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? 1.0 : -1.0;
    Int free = 0, maybe = 0;
    for (Int r = 0; r < directions; ++r) {
      const double a = pattern[3 * r], b = pattern[3 * r + 1], c = sign * pattern[3 * r + 2];
      ray.direction = {a * ux + b * wx + c * mx, a * uy + b * wy + c * my,
                       a * uz + b * wz + c * mz};
      for (int axis = 0; axis < 3; ++axis) {
        ray.inverse[axis] = ray.direction[axis] != 0.0 ? 1.0 / ray.direction[axis] : kInf;
      }
      const Met met = blocked(mesh, tree, face, ray, t_min, stack);
      free += met == kClear;
      maybe += met == kUnsure;
    }
    out.escaped[2 * s + side] = static_cast<double>(free) / static_cast<double>(directions);
    out.unsure[2 * s + side] = static_cast<double>(maybe) / static_cast<double>(directions);
  }
}

template <typename T>
T* zeros(std::size_t count) {
  return new T[count]();
}

std::pair<Array<Int>, Array<Int>> face_morton_order(const Points& unit, const Faces& faces) {
  const Mesh mesh = mesh_of(unit, faces);
  const auto count = static_cast<std::size_t>(mesh.count);
  std::unique_ptr<Int[]> ordered_buffer(new Int[count]);
  std::unique_ptr<Int[]> order_buffer(new Int[count]);
  Int* ordered = ordered_buffer.get();
  Int* order = order_buffer.get();
  auto ordered_array = owned(std::move(ordered_buffer), count);
  auto order_array = owned(std::move(order_buffer), count);
  std::atomic<bool> refused{false};
  {
    nb::gil_scoped_release release;
    std::vector<Int> codes(count);
    parallel_for(mesh.count, kGrain, [&](Int begin, Int end) {
      bool bad = false;
      for (Int face = begin; face < end; ++face) {
        codes[face] = morton(mesh, face, bad);
      }
      if (bad) {
        refused.store(true);
      }
    });
    radix_order(codes.data(), mesh.count, order, ordered);
  }
  if (refused.load()) {
    throw nb::index_error(kBadVertex);
  }
  return {ordered_array, order_array};
}

// The hierarchy's boxes, children, spans and gathered corners (none where not `gather`).
using Built = std::tuple<Array<double>, Array<Int>, Array<Int>, Array<double>>;
// Per sample: the shares that escape and that are unsure per side, its area, its winding.
using Casts = std::tuple<Array<double>, Array<double>, Array<double>, Array<bool>>;

Built bvh_build(const Points& unit, const Faces& faces, const Codes& codes, const Codes& order,
                Int leaf, bool gather) {
  const Mesh mesh = mesh_of(unit, faces);
  check_order(mesh, codes, order, leaf);
  Hierarchy tree;
  {
    nb::gil_scoped_release release;
    tree = build(mesh, codes.data(), order.data(), leaf, gather);
  }
  if (tree.bad_vertex) {
    throw nb::index_error(kBadVertex);
  }
  const auto nodes = static_cast<std::size_t>(tree.nodes);
  double* corners = tree.corners ? tree.corners.release() : new double[0];
  return {owned(tree.boxes.release(), nodes, 6), owned(tree.children.release(), nodes, 2),
          owned(tree.spans.release(), nodes, 2),
          owned(corners, static_cast<std::size_t>(tree.corner_rows), 9)};
}

Casts cast_rays(const Points& unit, const Faces& faces, const Codes& codes, const Codes& order,
                Int leaf, bool gather, const Codes& samples, const Points& pattern, double t_min) {
  const Mesh mesh = mesh_of(unit, faces);
  check_order(mesh, codes, order, leaf);
  const auto count = static_cast<std::size_t>(samples.shape(0));
  for (std::size_t s = 0; s < count; ++s) {
    if (static_cast<std::uint64_t>(samples.data()[s]) >= static_cast<std::uint64_t>(mesh.count)) {
      throw nb::index_error("a sample names a face that there is not");
    }
  }
  const Cast out{zeros<double>(2 * count), zeros<double>(2 * count), zeros<double>(count),
                 zeros<bool>(count)};
  bool refused = false;
  Casts result{
      owned(out.escaped, count, 2), owned(out.unsure, count, 2), owned(out.weights, count),
      owned(out.against, count)};
  {
    nb::gil_scoped_release release;
    const Hierarchy tree = build(mesh, codes.data(), order.data(), leaf, gather);
    refused = tree.bad_vertex;
    const auto directions = static_cast<Int>(pattern.shape(0));
    // The build read every face: the rays read only faces that it passed.
    parallel_for(refused ? 0 : static_cast<Int>(count), 1, [&](Int begin, Int end) {
      std::vector<Int> stack(static_cast<std::size_t>(tree.depth + 2));
      for (Int s = begin; s < end; ++s) {
        cast_one(mesh, tree, s, samples.data()[s], pattern.data(), directions, t_min, out,
                 stack.data());
      }
    });
  }
  if (refused) {
    throw nb::index_error(kBadVertex);
  }
  return result;
}

// samples[offsets[i] + r]: member (r counts[i]) // take[i] of chosen patch i, in file order, for
// r < take[i]; slot[g] is the chosen patch i of group g, or -1 (a group past slot's end, or a
// negative one, is no chosen patch).
void pick_samples(const Codes& group, const Codes& slot, const Codes& counts, const Codes& take,
                  const Codes& offsets, const Out<Int, nb::shape<-1>>& samples) {
  const auto patches = static_cast<Int>(counts.shape(0));
  if (static_cast<Int>(take.shape(0)) != patches || static_cast<Int>(offsets.shape(0)) != patches) {
    throw nb::value_error("counts, take and offsets must have one value for each chosen patch");
  }
  for (Int g = 0; g < static_cast<Int>(slot.shape(0)); ++g) {
    if (slot.data()[g] < -1 || slot.data()[g] >= patches) {
      throw nb::index_error("a slot names a chosen patch that there is not");
    }
  }
  for (Int i = 0; i < patches; ++i) {
    const Int first = offsets.data()[i], most = take.data()[i];
    if (first < 0 || most < 0 || counts.data()[i] < 0 ||
        first > static_cast<Int>(samples.shape(0)) - most) {
      throw nb::index_error("a patch's samples do not fit in the samples given");
    }
  }
  nb::gil_scoped_release release;
  std::vector<Int> seen(static_cast<std::size_t>(patches));
  std::vector<Int> ranks(static_cast<std::size_t>(patches));
  const auto groups = static_cast<Int>(slot.shape(0));
  for (Int face = 0; face < static_cast<Int>(group.shape(0)); ++face) {
    const Int patch = group.data()[face];
    if (patch < 0 || patch >= groups || slot.data()[patch] < 0) {
      continue;
    }
    const Int i = slot.data()[patch];
    const Int rank = ranks[i];
    // Unsigned: no overflow for any counts (they are checked to be non-negative).
    const auto pick = static_cast<std::uint64_t>(rank) *
                      static_cast<std::uint64_t>(counts.data()[i]) /
                      static_cast<std::uint64_t>(std::max<Int>(1, take.data()[i]));
    if (rank < take.data()[i] && static_cast<std::uint64_t>(seen[i]) == pick) {
      samples.data()[offsets.data()[i] + rank] = face;
      ranks[i] = rank + 1;
    }
    ++seen[i];
  }
}

}  // namespace

void bind_visibility(nb::module_& m) {
  m.def("face_morton_order", &face_morton_order, nb::arg("unit").noconvert(),
        nb::arg("faces").noconvert(),
        "The Morton codes of the faces' centroids (a 1024**3 grid over [-1, 1]**3) in increasing "
        "order, and that order (stable: equal codes keep file order).");
  m.def("bvh_build", &bvh_build, nb::arg("unit").noconvert(), nb::arg("faces").noconvert(),
        nb::arg("codes").noconvert(), nb::arg("order").noconvert(), nb::arg("leaf"),
        nb::arg("gather"),
        "The rays' hierarchy over the faces in Morton order: per node its padded box (low xyz, "
        "high xyz), children (-1 for a leaf) and span of the order; and the faces' corners in "
        "that order where `gather`, else an empty (0, 9) array.");
  m.def("cast_rays", &cast_rays, nb::arg("unit").noconvert(), nb::arg("faces").noconvert(),
        nb::arg("codes").noconvert(), nb::arg("order").noconvert(), nb::arg("leaf"),
        nb::arg("gather"),
        nb::arg("samples").noconvert(), nb::arg("pattern").noconvert(), nb::arg("t_min"),
        "For each sample face, its rays in the pattern on each side through the hierarchy of "
        "bvh_build: the shares that surely escape and that are unsure (each (s, 2): + side, - "
        "side), its area, and whether it is wound against its vertices' increasing order.");
  m.def("pick_samples", &pick_samples, nb::arg("group").noconvert(), nb::arg("slot").noconvert(),
        nb::arg("counts").noconvert(), nb::arg("take").noconvert(), nb::arg("offsets").noconvert(),
        nb::arg("samples").noconvert(),
        "samples[offsets[i] + r] = member (r counts[i]) // take[i] of chosen patch i in file "
        "order, for r < take[i]; slot[g] is the chosen patch of group g, or -1.");
}

}  // namespace mesh_normal
