// The per-face loops: face normals and areas, the vertex normals' weighted sums, the corners'
// weights, the bounds of a mesh's points, the checks' index and coordinate ranges, and the
// comparison of a file's stored normals with ours.
//
// A face [a, b, c] has the corners A, B, C (each coordinate times `factor`, a power of two, so
// exact) and the edges e0 = B - A, e1 = C - B, e2 = A - C: corner k lies between edges k - 1
// and k. Every product and sum is written in the order mesh_normal's documentation gives (and
// -ffp-contract=off keeps it unfused), so the bits do not depend on the compiler or on the
// number of threads: each row of an output is written by one thread, from its own inputs.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <mutex>
#include <tuple>
#include <vector>

#include <nanobind/stl/tuple.h>

#include "core.hpp"

namespace mesh_normal {

namespace {

using Faces = In<std::int64_t, nb::shape<-1, 3>>;
using Points = In<double, nb::shape<-1, 3>>;
using Values = In<double, nb::shape<-1>>;
using Marks = In<bool, nb::shape<-1>>;
using Rows = Out<double, nb::shape<-1, 3>>;
using Column = Out<double, nb::shape<-1>>;
using Flags = Out<bool, nb::shape<-1>>;

// mesh_normal/tolerances.py: MESH_RECOMPUTE_SINE, MESH_DEGENERATE_SINE, MESH_CANCELLED_SUM
// (exposed to Python, where a test holds them equal).
constexpr double kRecomputeSine = 0x1p-10;
constexpr double kDegenerateSine = 0x1p-37;
constexpr double kCancelledSum = 0x1p-32;
constexpr double kRecompute = kRecomputeSine * kRecomputeSine;
constexpr double kDegenerate = kDegenerateSine * kDegenerateSine;

// The weightings, as mesh_normal.mesh.vertices.WEIGHTINGS orders them.
enum Weighting : int { kUniform = 0, kArea = 1, kAngle = 2, kMax = 3 };

// Faces (or rows) a thread takes at least: fewer run on the calling thread.
constexpr std::int64_t kGrain = 4096;

struct Vec {
  double x, y, z;
};

double dot(const Vec& p, const Vec& q) { return p.x * q.x + p.y * q.y + p.z * q.z; }

Vec cross(const Vec& p, const Vec& q) {
  return {p.y * q.z - p.z * q.y, p.z * q.x - p.x * q.z, p.x * q.y - p.y * q.x};
}

Vec minus(const Vec& p, const Vec& q) { return {p.x - q.x, p.y - q.y, p.z - q.z}; }

struct Edges {
  Vec e0, e1, e2;
};

// What face_cross found: the product at corner A is good, it was taken again at the largest
// corner, or the face is degenerate.
enum Found { kAtFirstCorner, kAtLargestCorner, kDegenerateFace };

struct Cross {
  Vec normal;
  double square;
  Found found;
};

// Faces whose corners a kernel copies at a time before it works on them.
constexpr std::int64_t kBlock = 512;
// How many faces ahead the gather asks for the points it will read.
constexpr std::int64_t kAhead = 16;

// The points as a kernel reads them: each index checked against the rows before it is read.
struct Mesh {
  const double* points;
  std::uint64_t count;
  double factor;
  const std::int64_t* faces;

  // Copies the corners of faces first to stop (at most kBlock), each coordinate times
  // factor, into `corners` (9 a face): one simple loop of independent loads, whose cache misses
  // overlap (a face's corners are rows far apart in a large mesh). False at the first index
  // that is not a row of the points.
  bool gather(std::int64_t first, std::int64_t stop, std::int64_t end, double* corners) const {
    for (std::int64_t face = first; face < stop; ++face) {
      if (face + kAhead < end) {
        prefetch_face(face + kAhead);
      }
      for (int k = 0; k < 3; ++k) {
        const std::int64_t vertex = faces[3 * face + k];
        if (static_cast<std::uint64_t>(vertex) >= count) {
          return false;
        }
        const double* row = points + 3 * vertex;
        double* corner = corners + 9 * (face - first) + 3 * k;
        corner[0] = row[0] * factor;
        corner[1] = row[1] * factor;
        corner[2] = row[2] * factor;
      }
    }
    return true;
  }

  // Copies the corners of the faces `list` names (their indices checked already), as gather.
  void gather_list(const std::int64_t* list, std::int64_t size, double* corners) const {
    for (std::int64_t at = 0; at < size; ++at) {
      if (at + kAhead < size) {
        prefetch_face(list[at + kAhead]);
      }
      const std::int64_t* face = faces + 3 * list[at];
      for (int k = 0; k < 3; ++k) {
        const double* row = points + 3 * face[k];
        double* corner = corners + 9 * at + 3 * k;
        corner[0] = row[0] * factor;
        corner[1] = row[1] * factor;
        corner[2] = row[2] * factor;
      }
    }
  }

  // Asks for the rows of a face's corners (a row spans two cache lines once in about three).
  MESH_NORMAL_INLINE void prefetch_face(std::int64_t face) const {
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t vertex = static_cast<std::uint64_t>(faces[3 * face + k]);
      if (vertex < count) {
        prefetch(points + 3 * vertex);
        prefetch(points + 3 * vertex + 2);
      }
    }
  }

  // Calls body(face, edges) for faces begin to end, a block at a time; false if a face has an
  // index out of range (its block is left).
  template <typename Body>
  bool each_face(std::int64_t begin, std::int64_t end, const Body& body) const {
    double corners[kBlock * 9];
    bool good = true;
    for (std::int64_t first = begin; first < end; first += kBlock) {
      const std::int64_t stop = std::min(first + kBlock, end);
      if (!gather(first, stop, end, corners)) {
        good = false;
        continue;
      }
      for (std::int64_t face = first; face < stop; ++face) {
        body(face, edges_of(corners + 9 * (face - first)));
      }
    }
    return good;
  }

  // each_face over faces 0 .. count - 1 on every thread (parallel_for); false if a block held
  // an index out of range.
  template <typename Body>
  bool each_face_in_parallel(std::int64_t count, const Body& body) const {
    std::atomic<bool> bad{false};
    parallel_for(count, kGrain, [&](std::int64_t begin, std::int64_t end) {
      if (!each_face(begin, end, body)) {
        bad.store(true, std::memory_order_relaxed);
      }
    });
    return !bad.load();
  }

  // The edges B - A, C - B, A - C of a face's gathered corners.
  static Edges edges_of(const double* c) {
    const Vec a{c[0], c[1], c[2]}, b{c[3], c[4], c[5]}, d{c[6], c[7], c[8]};
    return {minus(b, a), minus(d, b), minus(a, d)};
  }
};

Mesh mesh_of(Points points, double factor, Faces faces) {
  return {points.data(), static_cast<std::uint64_t>(points.shape(0)), factor, faces.data()};
}

// (B - A) x (C - A) from its most accurate corner, its squared length, and where from. At
// corner A, (A - C) x (B - A) has the same bits (negating a difference is exact). Where the
// sine there is small, the product is taken again at the largest corner (opposite the longest
// edge, edge k being opposite corner k + 2), between the two edges after the longest; a sine
// of at most MESH_DEGENERATE_SINE there makes the face degenerate: a zero normal.
MESH_NORMAL_INLINE Cross face_cross(const Edges& e) {
  Vec normal = cross(e.e2, e.e0);
  double square = dot(normal, normal);
  if (square > kRecompute * dot(e.e2, e.e2) * dot(e.e0, e.e0)) {
    return {normal, square, kAtFirstCorner};
  }
  const double s0 = dot(e.e0, e.e0), s1 = dot(e.e1, e.e1), s2 = dot(e.e2, e.e2);
  const Vec *p, *q;
  double sp, sq;
  if (s0 >= s1 && s0 >= s2) {
    p = &e.e1, q = &e.e2, sp = s1, sq = s2;
  } else if (s1 >= s2) {
    p = &e.e2, q = &e.e0, sp = s2, sq = s0;
  } else {
    p = &e.e0, q = &e.e1, sp = s0, sq = s1;
  }
  normal = cross(*p, *q);
  square = dot(normal, normal);
  if (square <= kDegenerate * sp * sq) {
    return {{0.0, 0.0, 0.0}, 0.0, kDegenerateFace};
  }
  return {normal, square, kAtLargestCorner};
}

// The weights at corners 0, 1, 2 of a usable face whose |cross| is `length`.
MESH_NORMAL_INLINE Vec face_weights(int code, const Edges& e, double length) {
  if (code == kUniform) {
    return {1.0, 1.0, 1.0};
  }
  if (code == kArea) {
    return {length, length, length};
  }
  if (code == kAngle) {  // atan2(|n|, p . q) for the corner's edges p, q
    return {std::atan2(length, -dot(e.e2, e.e0)), std::atan2(length, -dot(e.e0, e.e1)),
            std::atan2(length, -dot(e.e1, e.e2))};
  }
  const double s0 = dot(e.e0, e.e0), s1 = dot(e.e1, e.e1), s2 = dot(e.e2, e.e2);
  return {length / (s2 * s0), length / (s0 * s1), length / (s1 * s2)};  // Max: |n| / (|p|² |q|²)
}

void require(bool condition, const char* sentence) {
  if (!condition) {
    throw nb::value_error(sentence);
  }
}

void require_rows(std::size_t rows, std::size_t wanted, const char* sentence) {
  require(rows == wanted, sentence);
}

void require_code(int code) {
  require(code >= kUniform && code <= kMax, "the weighting code must be from 0 to 3.");
}

// --- face normals and the face geometry ---------------------------------------------------

bool face_normals(Points points, double factor, Faces faces, int exponent,
                  Rows normals, Column areas, Flags degenerate) {
  const std::int64_t count = static_cast<std::int64_t>(faces.shape(0));
  require_rows(normals.shape(0), faces.shape(0), "the normals must have a row for each face.");
  require_rows(areas.shape(0), faces.shape(0), "the areas must have one for each face.");
  require_rows(degenerate.shape(0), faces.shape(0), "the flags must have one for each face.");
  const Mesh mesh = mesh_of(points, factor, faces);
  double* normal = normals.data();
  double* area = areas.data();
  bool* flag = degenerate.data();
  // 2**exponent where it is a normal double (one rounding, as ldexp's); ldexp beyond.
  const double power = exponent >= -1022 && exponent <= 1023 ? std::ldexp(1.0, exponent) : 0.0;
  nb::gil_scoped_release release;
  return mesh.each_face_in_parallel(count, [&](std::int64_t face, const Edges& edges) {
    const Cross made = face_cross(edges);
    const double length = std::sqrt(made.square);
    const double divisor = made.found == kDegenerateFace ? 1.0 : length;
    normal[3 * face] = made.normal.x / divisor + 0.0;  // -0.0 becomes 0.0
    normal[3 * face + 1] = made.normal.y / divisor + 0.0;
    normal[3 * face + 2] = made.normal.z / divisor + 0.0;
    area[face] = power != 0.0 ? length * power : std::ldexp(length, exponent);
    flag[face] = made.found == kDegenerateFace;
  });
}

bool face_geometry(Points points, double factor, Faces faces, Rows crosses,
                   Column lengths, Flags degenerate, Flags recomputed) {
  const std::int64_t count = static_cast<std::int64_t>(faces.shape(0));
  require_rows(crosses.shape(0), faces.shape(0), "the crosses must have a row for each face.");
  require_rows(lengths.shape(0), faces.shape(0), "the lengths must have one for each face.");
  require_rows(degenerate.shape(0), faces.shape(0), "the flags must have one for each face.");
  require_rows(recomputed.shape(0), faces.shape(0), "the flags must have one for each face.");
  const Mesh mesh = mesh_of(points, factor, faces);
  double* product = crosses.data();
  double* length = lengths.data();
  bool* flat = degenerate.data();
  bool* again = recomputed.data();
  nb::gil_scoped_release release;
  return mesh.each_face_in_parallel(count, [&](std::int64_t face, const Edges& edges) {
    const Cross made = face_cross(edges);
    product[3 * face] = made.normal.x;
    product[3 * face + 1] = made.normal.y;
    product[3 * face + 2] = made.normal.z;
    length[face] = std::sqrt(made.square);
    flat[face] = made.found == kDegenerateFace;
    again[face] = made.found != kAtFirstCorner;
  });
}

void unit_normals(Points crosses, Values lengths, Marks degenerate,
                  Rows out) {
  const std::int64_t count = static_cast<std::int64_t>(crosses.shape(0));
  require_rows(lengths.shape(0), crosses.shape(0), "the lengths must have one for each face.");
  require_rows(degenerate.shape(0), crosses.shape(0), "the flags must have one for each face.");
  require_rows(out.shape(0), crosses.shape(0), "the output must have a row for each face.");
  const double* product = crosses.data();
  const double* length = lengths.data();
  const bool* flat = degenerate.data();
  double* unit = out.data();  // may be `crosses` itself: each row is read before it is written
  nb::gil_scoped_release release;
  parallel_for(count, kGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t face = begin; face < end; ++face) {
      const double divisor = flat[face] ? 1.0 : length[face];
      const double x = product[3 * face], y = product[3 * face + 1], z = product[3 * face + 2];
      unit[3 * face] = x / divisor + 0.0;  // -0.0 becomes 0.0
      unit[3 * face + 1] = y / divisor + 0.0;
      unit[3 * face + 2] = z / divisor + 0.0;
    }
  });
}

// --- vertex normals -------------------------------------------------------------------------

// The vertex normals' sums. Each thread owns a range of vertices and goes through every face
// in order: a face with a corner in its range gives its term (a vector, then its weight, or
// its corners' weights), which the thread adds into the sums of those corners. So each
// vertex's sum is added in face order, by one thread, whatever the number of threads: the same
// bits. A face whose corners lie in two ranges has its term taken twice, the same way; a mesh's
// faces mostly join vertices of nearby numbers, so this is rare. A degenerate face's term is
// zeros, which change no sum.
class VertexSums {
 public:
  VertexSums(int code, const Mesh& mesh, std::int64_t faces, const double* crosses,
             const double* lengths, const bool* degenerate, bool fused, double* sums)
      : code_(code),
        mesh_(mesh),
        faces_(faces),
        crosses_(crosses),
        lengths_(lengths),
        degenerate_(degenerate),
        fused_(fused),
        gathered_(fused || code >= kAngle),
        sums_(sums) {}

  // False (and the sums not to be used) if a face has an index out of range.
  bool run() const {
    const std::int64_t parts = std::max(1, thread_count.load(std::memory_order_relaxed));
    const std::uint64_t count = mesh_.count;
    std::atomic<bool> bad{false};
    parallel_for(parts, 1, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t part = begin; part < end; ++part) {
        const std::uint64_t low = count * static_cast<std::uint64_t>(part) / parts;
        const std::uint64_t high = count * static_cast<std::uint64_t>(part + 1) / parts;
        if (!add_range(low, high)) {
          bad.store(true, std::memory_order_relaxed);
        }
      }
    });
    return !bad.load();
  }

 private:
  // Adds every term into the sums of the vertices low to high, a block of faces at a time.
  bool add_range(std::uint64_t low, std::uint64_t high) const {
    const std::uint64_t span = high - low;
    std::int64_t chosen[kBlock];
    double corners[kBlock * 9];
    double terms[kBlock * 6];
    double scratch[4] = {0.0, 0.0, 0.0, 0.0};
    for (std::int64_t first = 0; first < faces_; first += kBlock) {
      const std::int64_t stop = std::min(first + kBlock, faces_);
      std::int64_t count = 0;
      for (std::int64_t face = first; face < stop; ++face) {
        const std::int64_t* f = mesh_.faces + 3 * face;
        const std::uint64_t a = static_cast<std::uint64_t>(f[0]);
        const std::uint64_t b = static_cast<std::uint64_t>(f[1]);
        const std::uint64_t c = static_cast<std::uint64_t>(f[2]);
        if (a >= mesh_.count || b >= mesh_.count || c >= mesh_.count) {
          return false;
        }
        chosen[count] = face;  // kept where a corner is in range (no branch to mispredict)
        count += (a - low < span) | (b - low < span) | (c - low < span);
      }
      if (gathered_) {
        mesh_.gather_list(chosen, count, corners);
      }
      for (std::int64_t at = 0; at < count; ++at) {
        term(chosen[at], corners + 9 * at, terms + 6 * at);
      }
      for (std::int64_t at = 0; at < count; ++at) {
        if (at + kAhead < count) {  // each row is a cache miss on a large mesh
          prefetch_rows(chosen[at + kAhead], low, span);
        }
        add(chosen[at], terms + 6 * at, low, span, scratch);
      }
    }
    return true;
  }

  // The term of one face: "area": the cross product and its length; "uniform": the unit normal
  // and 1.0; the others: the unit normal and each corner's weight.
  void term(std::int64_t face, const double* corners, double* out) const {
    Edges edges{};
    if (gathered_) {
      edges = Mesh::edges_of(corners);
    }
    Vec n;
    double length;
    bool usable;
    if (fused_) {
      const Cross made = face_cross(edges);
      n = made.normal;
      usable = made.found != kDegenerateFace;
      length = std::sqrt(made.square);
    } else {
      n = {crosses_[3 * face], crosses_[3 * face + 1], crosses_[3 * face + 2]};
      usable = !degenerate_[face];
      length = lengths_[face];
    }
    if (!usable) {
      std::fill(out, out + 6, 0.0);
    } else if (code_ == kArea) {  // n itself, not weight * n / |n|, which rounds twice more
      out[0] = n.x, out[1] = n.y, out[2] = n.z, out[3] = length;
    } else {
      out[0] = n.x / length, out[1] = n.y / length, out[2] = n.z / length;
      const Vec w = face_weights(code_, edges, length);  // uniform: 1.0 each
      out[3] = w.x, out[4] = w.y, out[5] = w.z;
    }
  }

  MESH_NORMAL_INLINE void prefetch_rows(std::int64_t face, std::uint64_t low,
                                       std::uint64_t span) const {
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t vertex = static_cast<std::uint64_t>(mesh_.faces[3 * face + k]);
      if (vertex - low < span) {
        prefetch_for_write(sums_ + 4 * vertex);
      }
    }
  }

  // Adds a face's term into the rows of its corners in range (a corner out of range adds into
  // `scratch` instead: no branch to mispredict). Area and uniform add the vector and the weight
  // as they are (the unit normal times 1.0 is itself); the others each corner's own weight
  // times the unit normal.
  void add(std::int64_t face, const double* term, std::uint64_t low, std::uint64_t span,
           double* scratch) const {
    const bool shared = code_ <= kArea;
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t vertex = static_cast<std::uint64_t>(mesh_.faces[3 * face + k]);
      double* row = vertex - low < span ? sums_ + 4 * vertex : scratch;
      if (shared) {
        row[0] += term[0];
        row[1] += term[1];
        row[2] += term[2];
        row[3] += term[3];
      } else {
        const double w = term[3 + k];
        row[0] += w * term[0];
        row[1] += w * term[1];
        row[2] += w * term[2];
        row[3] += w;
      }
    }
  }

  int code_;
  Mesh mesh_;
  std::int64_t faces_;
  const double* crosses_;
  const double* lengths_;
  const bool* degenerate_;
  bool fused_;
  bool gathered_;
  double* sums_;
};

bool vertex_sums(int code, Points points, double factor, Faces faces, Points crosses,
                 Values lengths, Marks degenerate, bool fused, Out<double, nb::shape<-1, 4>> sums) {
  require_code(code);
  require_rows(sums.shape(0), points.shape(0), "the sums must have a row for each point.");
  if (!fused) {
    require_rows(crosses.shape(0), faces.shape(0), "the crosses must have a row for each face.");
    require_rows(lengths.shape(0), faces.shape(0), "the lengths must have one for each face.");
    require_rows(degenerate.shape(0), faces.shape(0), "the flags must have one for each face.");
  }
  const VertexSums work(code, mesh_of(points, factor, faces),
                        static_cast<std::int64_t>(faces.shape(0)), crosses.data(), lengths.data(),
                        degenerate.data(), fused, sums.data());
  nb::gil_scoped_release release;
  return work.run();
}

// Each row of `sums`, (n, 4), normalised: its unit vector (zero where it cancels against its
// total weight, at most MESH_CANCELLED_SUM of it) and whether it is missing; the unit rows are
// then packed into the first 3 n doubles of the same memory, as an (n, 3) array.
void normalise_sums(Out<double, nb::shape<-1, 4>> sums, Flags missing) {
  const std::int64_t count = static_cast<std::int64_t>(sums.shape(0));
  require_rows(missing.shape(0), sums.shape(0), "the mask must have one for each row.");
  double* data = sums.data();
  bool* gone = missing.data();
  nb::gil_scoped_release release;
  parallel_for(count, kGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t row = begin; row < end; ++row) {
      double* sum = data + 4 * row;
      const double x = sum[0], y = sum[1], z = sum[2], total = sum[3];
      const double square = x * x + y * y + z * z;
      const double cancel = kCancelledSum * total;
      const bool cancelled = square <= cancel * cancel;
      // x / inf is an exact zero
      const double length = cancelled ? std::numeric_limits<double>::infinity() : std::sqrt(square);
      sum[0] = x / length + 0.0;  // -0.0 becomes 0.0
      sum[1] = y / length + 0.0;
      sum[2] = z / length + 0.0;
      gone[row] = cancelled;
    }
  });
  // Packed row i (bytes 24 i on) lies over sums rows up to i: one thread, in order, each row
  // read before it is written.
  for (std::int64_t row = 1; row < count; ++row) {
    std::memmove(data + 3 * row, data + 4 * row, 3 * sizeof(double));
  }
}

// --- corner weights -------------------------------------------------------------------------

bool corner_weights(int code, Points points, double factor, Faces faces,
                    Values lengths, Marks degenerate,
                    Out<double, nb::shape<3, -1>> weights) {
  require_code(code);
  const std::int64_t count = static_cast<std::int64_t>(faces.shape(0));
  require_rows(lengths.shape(0), faces.shape(0), "the lengths must have one for each face.");
  require_rows(degenerate.shape(0), faces.shape(0), "the flags must have one for each face.");
  require_rows(weights.shape(1), faces.shape(0), "the weights must have a column for each face.");
  const Mesh mesh = mesh_of(points, factor, faces);
  const double* length = lengths.data();
  const bool* flat = degenerate.data();
  double* weight = weights.data();
  nb::gil_scoped_release release;
  return mesh.each_face_in_parallel(count, [&](std::int64_t face, const Edges& edges) {
    const Vec w = flat[face] ? Vec{0.0, 0.0, 0.0} : face_weights(code, edges, length[face]);
    weight[face] = w.x;
    weight[count + face] = w.y;
    weight[2 * count + face] = w.z;
  });
}

// --- bounds and ranges ----------------------------------------------------------------------

// Widens low, high to hold `row` (finite): a zero's sign stays the first one's.
void widen(const double* row, double* low, double* high) {
  for (int axis = 0; axis < 3; ++axis) {
    const double value = row[axis];
    if (value < low[axis]) {
      low[axis] = value;
    } else if (value > high[axis]) {
      high[axis] = value;
    }
  }
}

void column_bounds(Points points, Out<double, nb::shape<3>> low,
                   Out<double, nb::shape<3>> high) {
  const std::size_t count = points.shape(0);
  require(count > 0, "there are no points to bound.");
  const double* data = points.data();
  double* lows = low.data();
  double* highs = high.data();
  nb::gil_scoped_release release;
  std::copy(data, data + 3, lows);
  std::copy(data, data + 3, highs);
  for (std::size_t row = 1; row < count; ++row) {
    widen(data + 3 * row, lows, highs);
  }
}

void used_column_bounds(Points points, Marks used, Out<double, nb::shape<3>> low,
                        Out<double, nb::shape<3>> high) {
  const std::size_t count = points.shape(0);
  require_rows(used.shape(0), count, "the mask must have one for each point.");
  const bool* mark = used.data();
  const std::size_t first = static_cast<std::size_t>(std::find(mark, mark + count, true) - mark);
  require(first < count, "no point is used: there is nothing to bound.");
  const double* data = points.data();
  double* lows = low.data();
  double* highs = high.data();
  nb::gil_scoped_release release;
  std::copy(data + 3 * first, data + 3 * first + 3, lows);
  std::copy(data + 3 * first, data + 3 * first + 3, highs);
  for (std::size_t row = first + 1; row < count; ++row) {
    if (mark[row]) {
      widen(data + 3 * row, lows, highs);
    }
  }
}

// The smallest and largest of the indices and 0.
std::tuple<std::int64_t, std::int64_t> index_range(In<std::int64_t, nb::shape<-1>> flat) {
  const std::int64_t* data = flat.data();
  std::int64_t low = 0, high = 0;
  std::mutex merge;
  nb::gil_scoped_release release;
  parallel_for(static_cast<std::int64_t>(flat.shape(0)), 1 << 16,
               [&](std::int64_t begin, std::int64_t end) {
                 std::int64_t lo = 0, hi = 0;
                 for (std::int64_t at = begin; at < end; ++at) {
                   lo = std::min(lo, data[at]);
                   hi = std::max(hi, data[at]);
                 }
                 const std::lock_guard<std::mutex> lock(merge);
                 low = std::min(low, lo);
                 high = std::max(high, hi);
               });
  return {low, high};
}

// The smallest and largest coordinate and 0; NaN for both where one is not finite.
std::tuple<double, double> coordinate_range(Values flat) {
  const double* data = flat.data();
  double low = 0.0, high = 0.0;
  bool finite = true;
  std::mutex merge;
  nb::gil_scoped_release release;
  parallel_for(static_cast<std::int64_t>(flat.shape(0)), 1 << 16,
               [&](std::int64_t begin, std::int64_t end) {
                 double lo = 0.0, hi = 0.0, probe = 0.0;
                 for (std::int64_t at = begin; at < end; ++at) {
                   const double value = data[at];
                   lo = value < lo ? value : lo;
                   hi = value > hi ? value : hi;
                   probe += value * 0.0;  // NaN once a value is not finite
                 }
                 const std::lock_guard<std::mutex> lock(merge);
                 low = lo < low ? lo : low;
                 high = hi > high ? hi : high;
                 finite = finite && probe == 0.0;
               });
  if (!finite) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
  }
  return {low, high};
}

// --- stored normals -------------------------------------------------------------------------

// Each row over its largest |component| first (so that its length can neither overflow nor
// underflow), then over its length; whether it is finite and not zero (a row that is not is
// divided by 1.0 twice).
void unit_rows(Points stored, Rows unit, Flags usable) {
  const std::int64_t count = static_cast<std::int64_t>(stored.shape(0));
  require_rows(unit.shape(0), stored.shape(0), "the unit rows must have one for each row.");
  require_rows(usable.shape(0), stored.shape(0), "the mask must have one for each row.");
  const double* in = stored.data();
  double* out = unit.data();
  bool* ok = usable.data();
  nb::gil_scoped_release release;
  parallel_for(count, kGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t row = begin; row < end; ++row) {
      double x = in[3 * row], y = in[3 * row + 1], z = in[3 * row + 2];
      const double largest = std::max(std::fabs(x), std::max(std::fabs(y), std::fabs(z)));
      const bool good = std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && largest > 0;
      const double scale = good ? largest : 1.0;
      x = x / scale, y = y / scale, z = z / scale;
      const double length = good ? std::sqrt(x * x + y * y + z * z) : 1.0;
      out[3 * row] = x / length;
      out[3 * row + 1] = y / length;
      out[3 * row + 2] = z / length;
      ok[row] = good;
    }
  });
}

// |a - b| and |a + b| for the file's unit normal a and ours b at each compared row: every
// row, or the rows `rows` names.
void half_angle_sides(Points unit, Points ours, bool every,
                      In<std::int64_t, nb::shape<-1>> rows, Column differences,
                      Column totals) {
  const std::int64_t count = static_cast<std::int64_t>(differences.shape(0));
  require_rows(totals.shape(0), differences.shape(0), "the outputs must be as long as each other.");
  require_rows(ours.shape(0), unit.shape(0), "both normals must have the same rows.");
  const std::uint64_t limit = unit.shape(0);
  if (every) {
    require(static_cast<std::uint64_t>(count) <= limit, "there are more outputs than rows.");
  } else {
    require_rows(rows.shape(0), differences.shape(0), "the rows must have one for each output.");
  }
  const double* a = unit.data();
  const double* b = ours.data();
  const std::int64_t* which = rows.data();
  double* difference = differences.data();
  double* total = totals.data();
  std::atomic<bool> bad{false};
  {
    nb::gil_scoped_release release;
    parallel_for(count, kGrain, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t at = begin; at < end; ++at) {
        const std::int64_t row = every ? at : which[at];
        if (static_cast<std::uint64_t>(row) >= limit) {
          bad.store(true, std::memory_order_relaxed);
          continue;
        }
        const double ax = a[3 * row], ay = a[3 * row + 1], az = a[3 * row + 2];
        const double bx = b[3 * row], by = b[3 * row + 1], bz = b[3 * row + 2];
        const double dx = ax - bx, dy = ay - by, dz = az - bz;
        const double sx = ax + bx, sy = ay + by, sz = az + bz;
        difference[at] = std::sqrt(dx * dx + dy * dy + dz * dz);
        total[at] = std::sqrt(sx * sx + sy * sy + sz * sz);
      }
    });
  }
  if (bad.load()) {
    throw nb::index_error("a compared row is not a row of the normals.");
  }
}

}  // namespace

void bind_faces(nb::module_& m) {
  using nb::arg;
  m.attr("RECOMPUTE_SINE") = kRecomputeSine;
  m.attr("DEGENERATE_SINE") = kDegenerateSine;
  m.attr("CANCELLED_SUM") = kCancelledSum;
  m.def("face_normals", &face_normals, arg("points").noconvert(), arg("factor"),
        arg("faces").noconvert(), arg("exponent"), arg("normals").noconvert(),
        arg("areas").noconvert(), arg("degenerate").noconvert(),
        "Each face's unit normal, area (|cross| times 2**exponent) and degenerate flag; False "
        "if a face has an index out of range.");
  m.def("face_geometry", &face_geometry, arg("points").noconvert(), arg("factor"),
        arg("faces").noconvert(), arg("crosses").noconvert(), arg("lengths").noconvert(),
        arg("degenerate").noconvert(), arg("recomputed").noconvert(),
        "Each face's cross product, its length and flags; False if a face has an index out of "
        "range.");
  m.def("unit_normals", &unit_normals, arg("crosses").noconvert(), arg("lengths").noconvert(),
        arg("degenerate").noconvert(), arg("out").noconvert(),
        "Each cross product over its length (over 1 where degenerate) plus 0.0, into out (which "
        "may be crosses).");
  m.def("vertex_sums", &vertex_sums, arg("code"), arg("points").noconvert(), arg("factor"),
        arg("faces").noconvert(), arg("crosses").noconvert(), arg("lengths").noconvert(),
        arg("degenerate").noconvert(), arg("fused"), arg("sums").noconvert(),
        "Add each face's weighted normal and weight into its vertices' rows of sums, (n, 4), in "
        "face order; the cross products taken here where fused, else read from crosses and "
        "lengths. False if a face has an index out of range.");
  m.def("normalise_sums", &normalise_sums, arg("sums").noconvert(), arg("missing").noconvert(),
        "Unit rows of sums[:, :3] (zero where they cancel against sums[:, 3]), packed into the "
        "first 3 n doubles of the same memory, and where they cancel.");
  m.def("corner_weights", &corner_weights, arg("code"), arg("points").noconvert(), arg("factor"),
        arg("faces").noconvert(), arg("lengths").noconvert(), arg("degenerate").noconvert(),
        arg("weights").noconvert(),
        "weights[k, f]: the weight of face f's normal at its corner k (zero where degenerate); "
        "False if a face has an index out of range.");
  m.def("column_bounds", &column_bounds, arg("points").noconvert(), arg("low").noconvert(),
        arg("high").noconvert(), "The smallest and largest of each column of the points.");
  m.def("used_column_bounds", &used_column_bounds, arg("points").noconvert(),
        arg("used").noconvert(), arg("low").noconvert(), arg("high").noconvert(),
        "The smallest and largest of each column of the points that are used.");
  m.def("index_range", &index_range, arg("flat").noconvert(),
        "The smallest and largest of the indices and 0.");
  m.def("coordinate_range", &coordinate_range, arg("flat").noconvert(),
        "The smallest and largest coordinate and 0; NaN for both where one is not finite.");
  m.def("unit_rows", &unit_rows, arg("stored").noconvert(), arg("unit").noconvert(),
        arg("usable").noconvert(),
        "Each row scaled to unit length, and whether it is finite and not zero.");
  m.def("half_angle_sides", &half_angle_sides, arg("unit").noconvert(), arg("ours").noconvert(),
        arg("every"), arg("rows").noconvert(), arg("differences").noconvert(),
        arg("totals").noconvert(), "|a - b| and |a + b| at each compared row.");
}

}  // namespace mesh_normal
