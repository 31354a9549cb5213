// Orientation: sums by patch, the cone terms of the volume and their error bounds, generalized
// winding numbers, and the faces twinned back to back. mesh_normal/mesh/orientation.py says what
// they decide. Included once, by topology.cpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core.hpp"

namespace mesh_normal {

namespace {

using Rows = In<double, nb::shape<-1, 3>>;
using Triangles = In<std::int64_t, nb::shape<-1, 3>>;
using Groups = In<std::int64_t, nb::shape<-1>>;

// Faces per chunk of cone_sums: their shares stay in the cache between being taken and added.
constexpr std::int64_t cone_chunk = std::int64_t{1} << 16;
constexpr std::int64_t cone_grain = 4096;
// Points per piece of the parallel comparison of twinned faces; groups up to this many faces
// compare each pair, larger ones look the twin up in a sorted copy.
constexpr std::int64_t twin_grain = 4096;
constexpr std::int64_t few_twins = 32;
// (sample, face) visits per thread of winding_numbers.
constexpr std::int64_t winding_grain = std::int64_t{1} << 16;
// math.pi: the double nearest pi.
constexpr double pi = 3.141592653589793;

// How many faces ahead a loop over faces asks for their corners' points.
constexpr std::int64_t ahead = 16;

// The point rows of face `face`'s corners: a row of three doubles may span two cache lines, so
// its first and last value.
MESH_NORMAL_INLINE void prefetch_corners(const double* points, const std::int64_t* faces, std::int64_t face) {
  for (int k = 0; k < 3; ++k) {
    const double* row = points + 3 * faces[3 * face + k];
    prefetch(row);
    prefetch(row + 2);
  }
}

// Throws unless every index of `faces` is below `limit` (with the GIL held).
void check_triangles(const Triangles& faces, std::int64_t limit) {
  const std::int64_t* f = faces.data();
  const std::int64_t size = 3 * static_cast<std::int64_t>(faces.shape(0));
  for (std::int64_t i = 0; i < size; ++i) {
    if (f[i] < 0 || f[i] >= limit) {
      throw nb::index_error("a face refers to a vertex that does not exist.");
    }
  }
}

// Throws unless every group is below `groups` and there is one a face.
void check_groups(const Groups& group, std::int64_t faces, std::int64_t groups) {
  if (static_cast<std::int64_t>(group.shape(0)) != faces) {
    throw nb::value_error("group must have one value a face.");
  }
  const std::int64_t* g = group.data();
  for (std::int64_t i = 0; i < faces; ++i) {
    if (g[i] < 0 || g[i] >= groups) {
      throw nb::index_error("a face's group is out of range.");
    }
  }
}

// sums[g] += the weights of the faces of group g, in face order.
template <typename Weight>
void sum_by_group(Groups group, In<Weight, nb::shape<-1>> weights,
                  Out<double, nb::shape<-1>> sums) {
  const std::int64_t count = static_cast<std::int64_t>(weights.shape(0));
  check_groups(group, count, static_cast<std::int64_t>(sums.shape(0)));
  const std::int64_t* g = group.data();
  const Weight* w = weights.data();
  double* s = sums.data();
  nb::gil_scoped_release release;
  for (std::int64_t face = 0; face < count; ++face) {
    s[g[face]] += static_cast<double>(w[face]);
  }
}

// counts[g]: how many faces group g has (added to what counts holds).
void count_by_group(Groups group, Out<double, nb::shape<-1>> counts) {
  const std::int64_t count = static_cast<std::int64_t>(group.shape(0));
  check_groups(group, count, static_cast<std::int64_t>(counts.shape(0)));
  const std::int64_t* g = group.data();
  double* c = counts.data();
  nb::gil_scoped_release release;
  for (std::int64_t face = 0; face < count; ++face) {
    c[g[face]] += 1.0;
  }
}

// One face as the cone terms read it: A, the edges u = B - A and v = C - A, the cross product
// n = u x v (the geometry's, or taken at A where the geometry retook it elsewhere), all scaled
// by `factor`, and the largest |coordinate| of the face.
struct ConeFace {
  double ax, ay, az, ux, uy, uz, vx, vy, vz, nx, ny, nz, largest;
};

struct ConeInput {
  const double* points;
  double factor;
  const std::int64_t* faces;
  const double* crosses;
  const bool* recomputed;
  const std::int64_t* group;
};

ConeFace cone_face(const ConeInput& in, std::int64_t face) {
  const double* a = in.points + 3 * in.faces[3 * face];
  const double* b = in.points + 3 * in.faces[3 * face + 1];
  const double* c = in.points + 3 * in.faces[3 * face + 2];
  const double f = in.factor;
  ConeFace r{};
  r.ax = a[0] * f;
  r.ay = a[1] * f;
  r.az = a[2] * f;
  const double bx = b[0] * f, by = b[1] * f, bz = b[2] * f;
  const double cx = c[0] * f, cy = c[1] * f, cz = c[2] * f;
  r.ux = bx - r.ax;
  r.uy = by - r.ay;
  r.uz = bz - r.az;
  r.vx = cx - r.ax;
  r.vy = cy - r.ay;
  r.vz = cz - r.az;
  if (in.recomputed[face]) {
    r.nx = r.uy * r.vz - r.uz * r.vy;
    r.ny = r.uz * r.vx - r.ux * r.vz;
    r.nz = r.ux * r.vy - r.uy * r.vx;
  } else {
    r.nx = in.crosses[3 * face];
    r.ny = in.crosses[3 * face + 1];
    r.nz = in.crosses[3 * face + 2];
  }
  r.largest = std::max({std::fabs(r.ax), std::fabs(r.ay), std::fabs(r.az), std::fabs(bx),
                        std::fabs(by), std::fabs(bz), std::fabs(cx), std::fabs(cy),
                        std::fabs(cz)});
  return r;
}

// First pass: the face's area times its centroid (x, y, z), its area and its largest
// |coordinate|.
void centroid_share(const ConeInput& in, std::int64_t face, double* share) {
  const ConeFace f = cone_face(in, face);
  const double area = std::sqrt(f.nx * f.nx + f.ny * f.ny + f.nz * f.nz);
  share[0] = area * ((f.ux + f.vx) / 3 + f.ax);
  share[1] = area * ((f.uy + f.vy) / 3 + f.ay);
  share[2] = area * ((f.uz + f.vz) / 3 + f.az);
  share[3] = area;
  share[4] = f.largest;
}

// Second pass (the centroids in sums): the face's term, and its bound |n| |A - c| and its
// sensitivity (see orientation._cone_terms).
void term_share(const ConeInput& in, const double* sums, std::int64_t face, double* terms,
                double* share) {
  const ConeFace f = cone_face(in, face);
  const double* centre = sums + 7 * in.group[face];
  const double dx = f.ax - centre[0], dy = f.ay - centre[1], dz = f.az - centre[2];
  terms[face] = f.nx * dx + f.ny * dy + f.nz * dz;
  const double normal = std::sqrt(f.nx * f.nx + f.ny * f.ny + f.nz * f.nz);
  const double to_a = std::sqrt(dx * dx + dy * dy + dz * dz);
  const double bx = dx + f.ux, by = dy + f.uy, bz = dz + f.uz;
  const double cx = dx + f.vx, cy = dy + f.vy, cz = dz + f.vz;
  const double ex = f.vx - f.ux, ey = f.vy - f.uy, ez = f.vz - f.uz;
  const double to_b = std::sqrt(bx * bx + by * by + bz * bz);
  const double to_c = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double ab = std::sqrt(f.ux * f.ux + f.uy * f.uy + f.uz * f.uz);
  const double ac = std::sqrt(f.vx * f.vx + f.vy * f.vy + f.vz * f.vz);
  const double bc = std::sqrt(ex * ex + ey * ey + ez * ez);
  share[0] = normal * to_a;
  share[1] = 4 * normal + to_a * bc + to_b * ac + to_c * ab;
}

// Each group's area-weighted centroid from its sums (columns 0-2; 0 for no area).
void centroids(double* sums, std::int64_t groups) {
  for (std::int64_t g = 0; g < groups; ++g) {
    double* row = sums + 7 * g;
    const double total = row[3] != 0.0 ? row[3] : 1.0;
    row[0] = row[0] / total;
    row[1] = row[1] / total;
    row[2] = row[2] / total;
  }
}

// Adds the shares of faces [first, stop) into their groups, in face order (the same bits on
// any number of threads).
void add_shares(const std::int64_t* group, bool second, std::int64_t first, std::int64_t stop,
                const double* shares, double* sums) {
  for (std::int64_t face = first; face < stop; ++face) {
    double* row = sums + 7 * group[face];
    const double* share = shares + 5 * (face - first);
    if (second) {
      row[5] += share[0];
      row[6] += share[1];
    } else {
      row[0] += share[0];
      row[1] += share[1];
      row[2] += share[2];
      row[3] += share[3];
      row[4] = std::max(row[4], share[4]);
    }
  }
}

// det(A - c, B - c, C - c) of each face into `terms`, c its group's area-weighted centroid, and
// per group into `sums` (zeros on entry): the centroid (columns 0-2), the area, the largest
// |coordinate|, the sums of the bounds and of the sensitivities. Chunk by chunk, each face's
// share is taken on every thread, then added into its group in face order on one.
void cone_sums(Rows points, double factor, Triangles faces, Rows crosses,
               In<bool, nb::shape<-1>> recomputed, Groups group, Out<double, nb::shape<-1>> terms,
               Out<double, nb::shape<-1, 7>> sums) {
  const std::int64_t count = static_cast<std::int64_t>(faces.shape(0));
  const std::int64_t groups = static_cast<std::int64_t>(sums.shape(0));
  if (static_cast<std::int64_t>(crosses.shape(0)) != count ||
      static_cast<std::int64_t>(recomputed.shape(0)) != count ||
      static_cast<std::int64_t>(terms.shape(0)) != count) {
    throw nb::value_error("crosses, recomputed and terms must have one row a face.");
  }
  check_triangles(faces, static_cast<std::int64_t>(points.shape(0)));
  check_groups(group, count, groups);
  const ConeInput in{points.data(), factor,         faces.data(),
                     crosses.data(), recomputed.data(), group.data()};
  double* t = terms.data();
  double* s = sums.data();
  nb::gil_scoped_release release;
  std::vector<double> shares(static_cast<std::size_t>(5 * std::min(count, cone_chunk)));
  for (const bool second : {false, true}) {
    if (second) {
      centroids(s, groups);
    }
    for (std::int64_t first = 0; first < count; first += cone_chunk) {
      const std::int64_t stop = std::min(count, first + cone_chunk);
      parallel_for(stop - first, cone_grain, [&](std::int64_t begin, std::int64_t end) {
        for (std::int64_t face = first + begin; face < first + end; ++face) {
          if (face + ahead < count) {
            prefetch_corners(in.points, in.faces, face + ahead);
          }
          double* share = shares.data() + 5 * (face - first);
          if (second) {
            term_share(in, s, face, t, share);
          } else {
            centroid_share(in, face, share);
          }
        }
      });
      add_shares(in.group, second, first, stop, shares.data(), s);
    }
  }
}

// The squared distance from the origin to the triangle a, b, c (Ericson, Real-Time Collision
// Detection, 5.1.5, with the point at the origin); a triangle without area by its three edges.
double squared_distance(const double* a, const double* b, const double* c) {
  const auto dot = [](const double* u, const double* v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  const auto segment = [&dot](const double* p, const double* q) {
    const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double length = dot(d, d);
    const double t = length > 0.0 ? std::clamp(-dot(p, d) / length, 0.0, 1.0) : 0.0;
    const double x[3] = {p[0] + t * d[0], p[1] + t * d[1], p[2] + t * d[2]};
    return dot(x, x);
  };
  const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double d1 = -dot(ab, a), d2 = -dot(ac, a);
  if (d1 <= 0.0 && d2 <= 0.0) {
    return dot(a, a);
  }
  const double d3 = -dot(ab, b), d4 = -dot(ac, b);
  if (d3 >= 0.0 && d4 <= d3) {
    return dot(b, b);
  }
  const double d5 = -dot(ab, c), d6 = -dot(ac, c);
  if (d6 >= 0.0 && d5 <= d6) {
    return dot(c, c);
  }
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    return segment(a, b);
  }
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    return segment(a, c);
  }
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return segment(b, c);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0) || !std::isfinite(sum)) {  // no area: the nearest of its edges
    return std::min({segment(a, b), segment(b, c), segment(c, a)});
  }
  const double v = vb / sum, w = vc / sum;
  const double x[3] = {a[0] + v * ab[0] + w * ac[0], a[1] + v * ab[1] + w * ac[1],
                       a[2] + v * ab[2] + w * ac[2]};
  return dot(x, x);
}

// The generalized winding number of `faces` at one sample: Van Oosterom and Strackee's solid
// angle of each triangle, summed in face order, over 4 pi; and in `clearance` the squared
// distance from the sample to the nearest face, which says whether the sum can be trusted.
double winding_number(const double* points, double factor, const std::int64_t* faces,
                      std::int64_t count, const double* sample, double& clearance) {
  const double px = sample[0], py = sample[1], pz = sample[2];
  double total = 0.0;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::int64_t f = 0; f < count; ++f) {
    const double* a = points + 3 * faces[3 * f];
    const double* b = points + 3 * faces[3 * f + 1];
    const double* c = points + 3 * faces[3 * f + 2];
    const double ax = a[0] * factor - px, ay = a[1] * factor - py, az = a[2] * factor - pz;
    const double bx = b[0] * factor - px, by = b[1] * factor - py, bz = b[2] * factor - pz;
    const double cx = c[0] * factor - px, cy = c[1] * factor - py, cz = c[2] * factor - pz;
    const double la = std::sqrt(ax * ax + ay * ay + az * az);
    const double lb = std::sqrt(bx * bx + by * by + bz * bz);
    const double lc = std::sqrt(cx * cx + cy * cy + cz * cz);
    const double det =
        ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    double dot = la * lb * lc + (ax * bx + ay * by + az * bz) * lc;
    dot += (ax * cx + ay * cy + az * cz) * lb + (bx * cx + by * cy + bz * cz) * la;
    total += 2.0 * std::atan2(det, dot);
    // The distance only where the face may be nearer than the nearest so far: no point of it
    // is nearer than its nearest corner less its longest edge, which |AB| + |AC| bounds.
    const double edges = std::abs(bx - ax) + std::abs(by - ay) + std::abs(bz - az) +
                         std::abs(cx - ax) + std::abs(cy - ay) + std::abs(cz - az);
    const double reach = std::min({la, lb, lc}) - edges;
    if (reach <= 0.0 || reach * reach < nearest) {
      const double ra[3] = {ax, ay, az}, rb[3] = {bx, by, bz}, rc[3] = {cx, cy, cz};
      nearest = std::min(nearest, squared_distance(ra, rb, rc));
    }
  }
  clearance = nearest;
  return total / (4.0 * pi);
}

// The winding number of `faces` at each sample and the squared distance from it to the nearest
// face, the samples on every thread.
void winding_numbers(Rows points, double factor, Triangles faces, Rows samples,
                     Out<double, nb::shape<-1>> winding, Out<double, nb::shape<-1>> clearance) {
  const std::int64_t count = static_cast<std::int64_t>(samples.shape(0));
  if (static_cast<std::int64_t>(winding.shape(0)) != count ||
      static_cast<std::int64_t>(clearance.shape(0)) != count) {
    throw nb::value_error("winding and clearance must have one place a sample.");
  }
  check_triangles(faces, static_cast<std::int64_t>(points.shape(0)));
  const double* p = points.data();
  const std::int64_t* f = faces.data();
  const std::int64_t face_count = static_cast<std::int64_t>(faces.shape(0));
  const double* s = samples.data();
  double* w = winding.data();
  double* d = clearance.data();
  nb::gil_scoped_release release;
  // Threads only where each has about winding_grain faces to visit: starting one costs more
  // than a small shell's samples.
  const std::int64_t grain = std::max<std::int64_t>(1, winding_grain / std::max<std::int64_t>(1, face_count));
  parallel_for(count, grain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      w[i] = winding_number(p, factor, f, face_count, s + 3 * i, d[i]);
    }
  });
}

// The pairs (k, j) of boxes where box k lies within box j (k != j; low[j] <= low[k] and
// high[k] <= high[j] on every axis), the first `pairs.shape(0)` of them in `pairs`, and in
// `boxed` which boxes lie within another; returns how many pairs there are (once past the room,
// at least the room and one more), or -1 past `budget` comparisons of two boxes. A sweep along
// `axis` in the order of the boxes' low ends, holding the boxes whose range is still open
// there: about linear when few boxes overlap along that axis, as parts side by side do.
std::int64_t contained_boxes(Rows low, Rows high, std::int64_t axis, std::int64_t budget,
                             Out<std::int64_t, nb::shape<-1, 2>> pairs,
                             Out<bool, nb::shape<-1>> boxed) {
  const std::int64_t count = static_cast<std::int64_t>(low.shape(0));
  if (static_cast<std::int64_t>(high.shape(0)) != count ||
      static_cast<std::int64_t>(boxed.shape(0)) != count) {
    throw nb::value_error("low, high and boxed must have one row a box.");
  }
  if (axis < 0 || axis > 2) {
    throw nb::value_error("axis must be 0, 1 or 2.");
  }
  const double* lo = low.data();
  const double* hi = high.data();
  for (std::int64_t i = 0; i < 3 * count; ++i) {
    if (!(lo[i] <= hi[i])) {  // also refuses NaN
      throw nb::value_error("every box must have low <= high.");
    }
  }
  const std::int64_t capacity = static_cast<std::int64_t>(pairs.shape(0));
  std::int64_t* out = pairs.data();
  bool* inside = boxed.data();
  nb::gil_scoped_release release;
  std::vector<std::int64_t> order(static_cast<std::size_t>(count));
  for (std::int64_t i = 0; i < count; ++i) {
    order[static_cast<std::size_t>(i)] = i;
  }
  std::stable_sort(order.begin(), order.end(), [&](std::int64_t x, std::int64_t y) {
    return lo[3 * x + axis] < lo[3 * y + axis];
  });
  const auto within = [&](std::int64_t k, std::int64_t j) {
    for (int a = 0; a < 3; ++a) {
      if (lo[3 * j + a] > lo[3 * k + a] || hi[3 * k + a] > hi[3 * j + a]) {
        return false;
      }
    }
    return true;
  };
  std::vector<std::int64_t> open;
  std::int64_t found = 0;
  std::int64_t compared = 0;
  std::size_t next = 0;
  while (next < order.size()) {
    // Every box whose low end is at this place opens before any of them is tested: boxes
    // with equal low ends may hold each other.
    const double place = lo[3 * order[next] + axis];
    const std::size_t first = next;
    while (next < order.size() && lo[3 * order[next] + axis] == place) {
      open.push_back(order[next++]);
    }
    // Boxes that ended before this place hold no box from here on.
    open.erase(std::remove_if(open.begin(), open.end(),
                              [&](std::int64_t j) { return hi[3 * j + axis] < place; }),
               open.end());
    for (std::size_t i = first; i < next; ++i) {
      const std::int64_t k = order[i];
      compared += static_cast<std::int64_t>(open.size());
      if (compared > budget) {
        return -1;
      }
      for (const std::int64_t j : open) {
        if (j != k && within(k, j)) {
          if (found < capacity) {
            out[2 * found] = k;
            out[2 * found + 1] = j;
          }
          ++found;
          inside[k] = true;
          if (found > capacity) {  // past the room only `boxed` is wanted: one holder is enough
            break;
          }
        }
      }
    }
  }
  return found;
}

// A face as (middle * width + highest) * 2 + even, even meaning wound as its sorted points (a
// rotation of them, or a point repeats): twins share all but the last bit.
std::int64_t twin_key(const std::int64_t* row, std::int64_t width) {
  const std::int64_t a = row[0], b = row[1], c = row[2];
  const std::int64_t low = std::min({a, b, c}), high = std::max({a, b, c});
  const int ascents = (a < b ? 1 : 0) + (b < c ? 1 : 0) + (c < a ? 1 : 0);
  const bool even = ascents == 2 || a == b || b == c || c == a;
  return ((a + b + c - low - high) * width + high) * 2 + (even ? 1 : 0);
}

// Marks the twins among the faces order[first:last], which share their smallest point; `keys`
// is the thread's scratch.
template <typename Index>
void compare_group(const std::int64_t* faces, std::int64_t count, std::int64_t width,
                   const Index* order, std::int64_t first, std::int64_t last,
                   std::vector<std::int64_t>& keys, bool* twinned) {
  const std::int64_t size = last - first;
  keys.resize(static_cast<std::size_t>(size));
  for (std::int64_t row = 0; row < size; ++row) {
    if (first + row + ahead < count) {  // a later group's face: far away in a large mesh
      prefetch(faces + 3 * order[first + row + ahead]);
    }
    keys[static_cast<std::size_t>(row)] = twin_key(faces + 3 * order[first + row], width);
  }
  if (size <= few_twins) {
    for (std::int64_t i = 0; i < size; ++i) {
      for (std::int64_t j = i + 1; j < size; ++j) {
        if ((keys[static_cast<std::size_t>(i)] ^ keys[static_cast<std::size_t>(j)]) == 1) {
          twinned[order[first + i]] = true;
          twinned[order[first + j]] = true;
        }
      }
    }
    return;
  }
  std::vector<std::int64_t> ranked(keys);
  std::sort(ranked.begin(), ranked.end());
  for (std::int64_t row = 0; row < size; ++row) {
    const std::int64_t other = keys[static_cast<std::size_t>(row)] ^ 1;
    if (std::binary_search(ranked.begin(), ranked.end(), other)) {
      twinned[order[first + row]] = true;
    }
  }
}

// The faces grouped by their smallest point with a counting sort, then compared within each
// group on every thread (a face is in one group, so each writes only its own faces' marks).
template <typename Index>
void mark_twins(const std::int64_t* faces, std::int64_t count, std::int64_t width,
                bool* twinned) {
  std::vector<std::int64_t> ends(static_cast<std::size_t>(width) + 1, 0);
  auto smallest = [faces](std::int64_t face) {
    return std::min({faces[3 * face], faces[3 * face + 1], faces[3 * face + 2]});
  };
  for (std::int64_t face = 0; face < count; ++face) {
    ends[static_cast<std::size_t>(smallest(face)) + 1] += 1;
  }
  for (std::int64_t point = 0; point < width; ++point) {
    ends[static_cast<std::size_t>(point) + 1] += ends[static_cast<std::size_t>(point)];
  }
  std::vector<Index> order(static_cast<std::size_t>(count));
  for (std::int64_t face = 0; face < count; ++face) {
    std::int64_t& place = ends[static_cast<std::size_t>(smallest(face))];
    order[static_cast<std::size_t>(place++)] = static_cast<Index>(face);
  }
  parallel_for(width, twin_grain, [&](std::int64_t begin, std::int64_t end) {
    std::vector<std::int64_t> keys;
    std::int64_t first = begin > 0 ? ends[static_cast<std::size_t>(begin - 1)] : 0;
    for (std::int64_t point = begin; point < end; ++point) {
      const std::int64_t last = ends[static_cast<std::size_t>(point)];
      if (last - first > 1) {
        compare_group(faces, count, width, order.data(), first, last, keys, twinned);
      }
      first = last;
    }
  });
}

// Marks in `twinned` (false on entry) the faces whose three points another face has, wound the
// other way; every point is below `width`, and (width * width) * 2 fits 62 bits.
void twinned_faces(Triangles faces, std::int64_t width, Out<bool, nb::shape<-1>> twinned) {
  const std::int64_t count = static_cast<std::int64_t>(faces.shape(0));
  if (static_cast<std::int64_t>(twinned.shape(0)) != count) {
    throw nb::value_error("twinned must have one flag a face.");
  }
  if (width < 1 || width > ((std::int64_t{1} << 61) - 1) / width) {
    throw nb::value_error("the number of points is out of range for one key a face.");
  }
  check_triangles(faces, width);
  const std::int64_t* f = faces.data();
  bool* marks = twinned.data();
  nb::gil_scoped_release release;
  if (count < (std::int64_t{1} << 31)) {
    mark_twins<std::int32_t>(f, count, width, marks);
  } else {
    mark_twins<std::int64_t>(f, count, width, marks);
  }
}

}  // namespace

inline void bind_orientation(nb::module_& m) {
  const auto group = nb::arg("group").noconvert();
  const char* sum_doc = "sums[g] += the weights of the faces of group g, in face order.";
  m.def("sum_by_group", &sum_by_group<double>, group, nb::arg("weights").noconvert(),
        nb::arg("sums").noconvert(), sum_doc);
  m.def("sum_by_group", &sum_by_group<std::int8_t>, group, nb::arg("weights").noconvert(),
        nb::arg("sums").noconvert(), sum_doc);
  m.def("count_by_group", &count_by_group, group, nb::arg("counts").noconvert(),
        "counts[g] += how many faces group g has.");
  m.def("cone_sums", &cone_sums, nb::arg("points").noconvert(), nb::arg("factor"),
        nb::arg("faces").noconvert(), nb::arg("crosses").noconvert(),
        nb::arg("recomputed").noconvert(), group, nb::arg("terms").noconvert(),
        nb::arg("sums").noconvert(),
        "The cone term of each face about its group's centroid, and each group's centroid, "
        "area, largest |coordinate|, bounds and sensitivities.");
  m.def("winding_numbers", &winding_numbers, nb::arg("points").noconvert(), nb::arg("factor"),
        nb::arg("faces").noconvert(), nb::arg("samples").noconvert(),
        nb::arg("winding").noconvert(), nb::arg("clearance").noconvert(),
        "The generalized winding number of the faces at each sample, and the squared distance "
        "from it to the nearest face.");
  m.def("contained_boxes", &contained_boxes, nb::arg("low").noconvert(),
        nb::arg("high").noconvert(), nb::arg("axis"), nb::arg("budget"),
        nb::arg("pairs").noconvert(),
        nb::arg("boxed").noconvert(),
        "The pairs (k, j) where box k lies within box j, up to the room in pairs; returns "
        "how many there are, or -1 past the budget of comparisons.");
  m.def("twinned_faces", &twinned_faces, nb::arg("faces").noconvert(), nb::arg("width"),
        nb::arg("twinned").noconvert(),
        "Mark the faces whose three points another face has, wound the other way.");
}

}  // namespace mesh_normal
