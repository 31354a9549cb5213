// Exact welding of corners into points numbered by first appearance (an STL's corners), and the
// measures of polygons that decide their triangulation (OBJ, PLY and OFF faces).
#include <nanobind/stl/optional.h>
#include <nanobind/stl/tuple.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>
#include <optional>
#include <tuple>
#include <type_traits>
#include <utility>

#if __has_include(<sys/mman.h>)
#include <sys/mman.h>
#endif

#include "core.hpp"

namespace mesh_normal {

namespace {

// ---- welding ----------------------------------------------------------------------------------

// The corners' bytes, (faces, corners per face, 3 coordinates of 4 or 8 bytes), strided in any
// way along the first two axes: a binary STL's corners where they lie in its 50-byte records.
using Grid = nb::ndarray<const std::uint8_t, nb::numpy, nb::device::cpu, nb::ndim<3>>;
using Vertices = nb::ndarray<nb::numpy, double>;
using Index = nb::ndarray<nb::numpy, std::int64_t>;
using Welded = std::tuple<Vertices, Index>;

// A corner's three coordinates as unsigned integers of their bits, with -0.0's bits (only the
// sign bit) as 0.0's: two corners are one point when these are equal.
template <typename W>
struct Words {
  W x, y, z;
  bool operator==(const Words& other) const {
    return x == other.x && y == other.y && z == other.z;
  }
  bool operator<(const Words& other) const {
    return std::tie(x, y, z) < std::tie(other.x, other.y, other.z);
  }
};

template <typename W>
struct Corners {
  const std::uint8_t* data;
  std::int64_t faces, per, face_stride, corner_stride;

  std::int64_t count() const { return faces * per; }

  W word(const std::uint8_t* at) const {
    constexpr W sign = W{1} << (8 * sizeof(W) - 1);
    W value;
    std::memcpy(&value, at, sizeof(W));
    return value == sign ? W{0} : value;
  }
  const std::uint8_t* at(std::int64_t face, std::int64_t corner) const {
    return data + face * face_stride + corner * corner_stride;
  }
  Words<W> words(std::int64_t face, std::int64_t corner) const {
    const std::uint8_t* p = at(face, corner);
    return {word(p), word(p + sizeof(W)), word(p + 2 * sizeof(W))};
  }
  // The row's coordinates as float64, -0.0 as 0.0 (plus 0.0).
  void point(std::int64_t row, double* out) const {
    using Float = std::conditional_t<sizeof(W) == 4, float, double>;
    const std::uint8_t* p = at(row / per, row % per);
    for (int axis = 0; axis < 3; ++axis) {
      Float value;
      std::memcpy(&value, p + axis * sizeof(W), sizeof(W));
      out[axis] = static_cast<double>(value) + 0.0;
    }
  }
};

constexpr std::uint32_t kMurmur = 0x5BD1E995u;

// MurmurHash2's step of a 32-bit piece into a 32-bit state (wrapping arithmetic).
std::uint32_t mix(std::uint32_t state, std::uint32_t piece) {
  piece *= kMurmur;
  piece ^= piece >> 24;
  piece *= kMurmur;
  return (state * kMurmur) ^ piece;
}

std::uint32_t final_mix(std::uint32_t state) {
  state ^= state >> 13;
  state *= kMurmur;
  return state ^ (state >> 15);
}

// A 32-bit hash of a corner's words, 32 bits at a time (low half first for 8-byte words).
template <typename W>
std::uint32_t words_hash(const Words<W>& w) {
  std::uint32_t state = 0x9747B28Cu;
  for (const W word : {w.x, w.y, w.z}) {
    state = mix(state, static_cast<std::uint32_t>(word));
    if constexpr (sizeof(W) == 8) {
      state = mix(state, static_cast<std::uint32_t>(word >> 32));
    }
  }
  return final_mix(state);
}

// The table's memory; a large one asked for in huge pages where the system gives them only on
// request: with 4 KB pages, the probes of a table larger than the cache also wait on the page
// tables (the weld of 5,000,000 faces takes about an eighth longer).
template <typename T>
class Table {
 public:
  explicit Table(std::size_t size) : size_(size) {
    const std::size_t bytes = size * sizeof(T);
#ifdef MADV_HUGEPAGE
    if (bytes >= kHuge) {
      const std::size_t pages = (bytes + kHuge - 1) / kHuge * kHuge;
      data_ = static_cast<T*>(std::aligned_alloc(kHuge, pages));
      if (data_ != nullptr) {
        madvise(data_, pages, MADV_HUGEPAGE);  // a hint, whatever it answers
      }
    } else {
      data_ = static_cast<T*>(std::malloc(bytes));
    }
#else  // no such request (and, on Windows, no std::aligned_alloc): the system's own pages
    data_ = static_cast<T*>(std::malloc(bytes));
#endif
    if (data_ == nullptr) {
      throw std::bad_alloc();
    }
  }
  ~Table() { std::free(data_); }
  Table(const Table&) = delete;
  Table& operator=(const Table&) = delete;
  void swap(Table& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
  }
  T& operator[](std::size_t at) { return data_[at]; }
  std::size_t size() const { return size_; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }

 private:
  static constexpr std::size_t kHuge = std::size_t{1} << 21;
  T* data_;
  std::size_t size_;
};

// A slot of the table: a point's words and its number (-1 when free). 16 bytes for float32.
template <typename W>
struct Slot {
  Words<W> words;
  std::make_signed_t<W> number;
};

// The distinct points' first rows, in order, and every row's point.
struct Numbered {
  std::vector<std::int64_t> leaders;
  std::int64_t* index;
};

// Places every point of `table` in a table twice the size, in slot order; false if one had to
// look more than `most` slots on.
template <typename W>
bool regrow(Table<Slot<W>>& table, std::uint32_t mask, std::int64_t most) {
  const std::size_t size = 2 * table.size();
  Table<Slot<W>> larger(size);
  std::fill(larger.begin(), larger.end(), Slot<W>{{0, 0, 0}, -1});
  for (const Slot<W>& old : table) {
    if (old.number < 0) {
      continue;
    }
    std::size_t slot = words_hash(old.words) & mask & (size - 1);
    std::int64_t probes = 0;
    while (larger[slot].number >= 0) {
      if (++probes > most) {
        return false;
      }
      slot = (slot + 1) & (size - 1);
    }
    larger[slot] = old;
  }
  table.swap(larger);
  return true;
}

// How many rows ahead the table pass asks for the slot it will probe: the table is larger than
// the cache on a large mesh, and each row's slot is a random place in it.
constexpr std::int64_t kAhead = 16;

// Numbers each row's point by first appearance through a hash table of the points (open
// addressing, a quarter as many slots as rows to start with, doubled when half full). False
// when a row had to look more than `most` slots on (a file made so that many points share a
// slot): the caller sorts instead.
template <typename W>
bool table_weld(const Corners<W>& corners, std::uint32_t mask, std::int64_t most,
                Numbered& out) {
  const std::int64_t count = corners.count();
  std::vector<std::uint32_t> digests(static_cast<std::size_t>(count));
  parallel_for(corners.faces, 1 << 13, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t face = begin; face < end; ++face) {
      for (std::int64_t corner = 0; corner < corners.per; ++corner) {
        digests[face * corners.per + corner] = words_hash(corners.words(face, corner));
      }
    }
  });
  std::size_t size = 16;
  while (static_cast<std::int64_t>(size) < count / 4) {
    size *= 2;
  }
  Table<Slot<W>> table(size);
  std::fill(table.begin(), table.end(), Slot<W>{{0, 0, 0}, -1});
  std::int64_t points = 0;
  std::int64_t row = 0;
  for (std::int64_t face = 0; face < corners.faces; ++face) {
    for (std::int64_t corner = 0; corner < corners.per; ++corner, ++row) {
      if (row + kAhead < count) {
        prefetch_for_write(&table[digests[row + kAhead] & mask & (size - 1)]);
      }
      const Words<W> words = corners.words(face, corner);
      std::size_t slot = digests[row] & mask & (size - 1);
      std::int64_t probes = 0;
      while (true) {
        Slot<W>& here = table[slot];
        if (here.number < 0) {
          here = Slot<W>{words, static_cast<std::make_signed_t<W>>(points)};
          out.leaders.push_back(row);
          out.index[row] = points++;
          break;
        }
        if (here.words == words) {
          out.index[row] = here.number;
          break;
        }
        if (++probes > most) {
          return false;
        }
        slot = (slot + 1) & (size - 1);
      }
      if (2 * points > static_cast<std::int64_t>(size)) {
        if (!regrow(table, mask, most)) {
          return false;
        }
        size = table.size();
      }
    }
  }
  return true;
}

// The same numbering by a sort of the rows by their words (then by row): exact whatever the
// hashes, for the files that crowd the table.
template <typename W>
void sort_weld(const Corners<W>& corners, Numbered& out) {
  struct Keyed {
    Words<W> words;
    std::int64_t row;
  };
  const std::int64_t count = corners.count();
  std::vector<Keyed> keyed(static_cast<std::size_t>(count));
  std::int64_t row = 0;
  for (std::int64_t face = 0; face < corners.faces; ++face) {
    for (std::int64_t corner = 0; corner < corners.per; ++corner, ++row) {
      keyed[row] = Keyed{corners.words(face, corner), row};
    }
  }
  std::sort(keyed.begin(), keyed.end(), [](const Keyed& a, const Keyed& b) {
    return a.words < b.words || (a.words == b.words && a.row < b.row);
  });
  // Each row's first row of its point (index holds it for now): the first of its run.
  std::int64_t first = 0;
  for (std::size_t at = 0; at < keyed.size(); ++at) {
    if (at == 0 || !(keyed[at].words == keyed[at - 1].words)) {
      first = keyed[at].row;
    }
    out.index[keyed[at].row] = first;
  }
  keyed = {};
  // Numbered in row order: a row's first row comes no later, so it is numbered already.
  for (std::int64_t r = 0; r < count; ++r) {
    const std::int64_t lead = out.index[r];
    if (lead == r) {
      out.index[r] = static_cast<std::int64_t>(out.leaders.size());
      out.leaders.push_back(r);
    } else {
      out.index[r] = out.index[lead];
    }
  }
}

// The leading rows' coordinates as float64, in turn, into `vertices` (3 per point).
template <typename W>
void leading_points(const Corners<W>& corners, const std::vector<std::int64_t>& leaders,
                    double* vertices) {
  parallel_for(static_cast<std::int64_t>(leaders.size()), 1 << 14,
               [&](std::int64_t begin, std::int64_t end) {
                 for (std::int64_t point = begin; point < end; ++point) {
                   corners.point(leaders[point], vertices + 3 * point);
                 }
               });
}

template <typename W>
std::optional<Welded> weld_words(const Corners<W>& corners, bool by_table, std::uint32_t mask,
                                 std::int64_t most) {
  const auto count = static_cast<std::size_t>(corners.count());
  std::unique_ptr<std::int64_t[]> index_buffer(new std::int64_t[count]);
  std::int64_t* index = index_buffer.get();
  Index index_array = owned(std::move(index_buffer), count);
  Numbered numbered{{}, index};
  std::unique_ptr<double[]> vertices;
  {
    nb::gil_scoped_release release;
    if (by_table) {
      numbered.leaders.reserve(count / 4);
      if (!table_weld(corners, mask, most, numbered)) {
        numbered.leaders = {};
      }
    } else {
      sort_weld(corners, numbered);
    }
    if (!numbered.leaders.empty()) {
      vertices.reset(new double[3 * numbered.leaders.size()]);
      leading_points(corners, numbered.leaders, vertices.get());
    }
  }
  if (vertices == nullptr) {
    return std::nullopt;
  }
  return Welded{owned(std::move(vertices), numbered.leaders.size(), 3), index_array};
}

std::optional<Welded> weld_grid(const Grid& grid, bool by_table, std::uint32_t mask,
                                std::int64_t most) {
  const std::int64_t row_bytes = static_cast<std::int64_t>(grid.shape(2));
  if (row_bytes != 12 && row_bytes != 24) {
    throw nb::value_error("each corner must be 3 coordinates of 4 or 8 bytes.");
  }
  if (grid.stride(2) != 1) {
    throw nb::value_error("each corner's coordinates must be contiguous.");
  }
  const auto faces = static_cast<std::int64_t>(grid.shape(0));
  const auto per = static_cast<std::int64_t>(grid.shape(1));
  if (by_table && faces * per >= (std::int64_t{1} << 31)) {
    throw nb::value_error("the table numbers fewer than 2**31 corners.");
  }
  if (faces * per == 0) {
    return Welded{owned(new double[0], 0, 3), owned(new std::int64_t[0], 0)};
  }
  if (row_bytes == 12) {
    const Corners<std::uint32_t> corners{grid.data(), faces, per, grid.stride(0), grid.stride(1)};
    return weld_words(corners, by_table, mask, most);
  }
  const Corners<std::uint64_t> corners{grid.data(), faces, per, grid.stride(0), grid.stride(1)};
  return weld_words(corners, by_table, mask, most);
}

// ---- polygon shapes ---------------------------------------------------------------------------

using Vector = std::array<double, 3>;

// A polygon's corners: the vertex of each, and the vertices' rows.
struct Ring {
  const std::int64_t* corners;
  std::int64_t k;
  const double* vertices;

  Vector at(std::int64_t corner, const Vector& origin) const {
    const double* v = vertices + 3 * corners[corner];
    return {v[0] - origin[0], v[1] - origin[1], v[2] - origin[2]};
  }
};

// The running minimum and maximum take the new value only where it compares less (more), so a
// NaN never replaces a number and a number never replaces a NaN already taken.
double lesser(double acc, double value) { return value < acc ? value : acc; }
double greater(double acc, double value) { return value > acc ? value : acc; }

// The centroid of a polygon's corners and its bounding-box diagonal.
std::pair<Vector, double> centre_and_size(const Ring& ring) {
  double x = 0.0, y = 0.0, z = 0.0;
  double low_x = INFINITY, low_y = INFINITY, low_z = INFINITY;
  double high_x = -INFINITY, high_y = -INFINITY, high_z = -INFINITY;
  for (std::int64_t corner = 0; corner < ring.k; ++corner) {
    const double* v = ring.vertices + 3 * ring.corners[corner];
    x = x + v[0], y = y + v[1], z = z + v[2];
    low_x = lesser(low_x, v[0]), low_y = lesser(low_y, v[1]), low_z = lesser(low_z, v[2]);
    high_x = greater(high_x, v[0]), high_y = greater(high_y, v[1]);
    high_z = greater(high_z, v[2]);
  }
  const double dx = high_x - low_x, dy = high_y - low_y, dz = high_z - low_z;
  const double size = std::sqrt(dx * dx + dy * dy + dz * dz);
  const auto k = static_cast<double>(ring.k);
  return {{x / k, y / k, z / k}, size};
}

// The unit Newell normal of a polygon, its corners taken relative to `centre`.
Vector newell(const Ring& ring, const Vector& centre) {
  double x = 0.0, y = 0.0, z = 0.0;
  for (std::int64_t corner = 0; corner < ring.k; ++corner) {
    const Vector a = ring.at(corner, centre);
    const Vector b = ring.at(corner + 1 == ring.k ? 0 : corner + 1, centre);
    x = x + a[1] * b[2] - a[2] * b[1];
    y = y + a[2] * b[0] - a[0] * b[2];
    z = z + a[0] * b[1] - a[1] * b[0];
  }
  const double length = std::sqrt(x * x + y * y + z * z);
  return {x / length, y / length, z / length};
}

// The largest distance of a corner from the plane through `centre` along `normal`.
double farthest(const Ring& ring, const Vector& centre, const Vector& normal) {
  double most = 0.0;
  for (std::int64_t corner = 0; corner < ring.k; ++corner) {
    const double* v = ring.vertices + 3 * ring.corners[corner];
    double height = 0.0;
    for (int i = 0; i < 3; ++i) {
      height += (v[i] - centre[i]) * normal[i];
    }
    most = greater(most, std::fabs(height));
  }
  return most;
}

// Whether a triangle of the fan from the first corner has its (doubled) area along `normal`
// below `floor`: it faces against the polygon.
bool fan_folds(const Ring& ring, const Vector& normal, double floor) {
  const Vector first = ring.at(0, {0.0, 0.0, 0.0});
  for (std::int64_t corner = 1; corner < ring.k - 1; ++corner) {
    const Vector b = ring.at(corner, first);
    const Vector c = ring.at(corner + 1, first);
    const double along = (b[1] * c[2] - b[2] * c[1]) * normal[0] +
                         (b[2] * c[0] - b[0] * c[2]) * normal[1] +
                         (b[0] * c[1] - b[1] * c[0]) * normal[2];
    if (along < floor) {
      return true;
    }
  }
  return false;
}

// A fan triangle faces against its polygon when its area along the polygon's normal is below
// -kFanFold * size**2: rounding on a degenerate (collinear) triangle stays far above that.
constexpr double kFanFold = 1e-10;

// Measures the polygons of four or more corners (the others keep what the caller filled);
// false when a polygon's corners run past the corner array or a corner is not a vertex.
bool polygon_shapes(In<std::int64_t, nb::ndim<1>> counts, In<std::int64_t, nb::ndim<1>> starts,
                    In<std::int64_t, nb::ndim<1>> corner_vertices,
                    In<double, nb::shape<-1, 3>> vertices, Out<double, nb::shape<-1, 3>> normals,
                    Out<double, nb::ndim<1>> deviation, Out<bool, nb::ndim<1>> folded) {
  const auto polygons = static_cast<std::int64_t>(counts.shape(0));
  if (starts.shape(0) != counts.shape(0) || normals.shape(0) != counts.shape(0) ||
      deviation.shape(0) != counts.shape(0) || folded.shape(0) != counts.shape(0)) {
    throw nb::value_error("the polygons' arrays must have one row per polygon.");
  }
  const auto corner_count = static_cast<std::int64_t>(corner_vertices.shape(0));
  const auto vertex_count = static_cast<std::int64_t>(vertices.shape(0));
  const std::int64_t* count = counts.data();
  const std::int64_t* start = starts.data();
  const std::int64_t* corners = corner_vertices.data();
  const double* points = vertices.data();
  double* normal_rows = normals.data();
  double* deviations = deviation.data();
  bool* folds = folded.data();
  std::atomic<bool> valid{true};
  nb::gil_scoped_release release;
  parallel_for(polygons, 1 << 12, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t polygon = begin; polygon < end; ++polygon) {
      const std::int64_t k = count[polygon], first = start[polygon];
      if (k < 4) {
        continue;
      }
      if (first < 0 || first > corner_count || k > corner_count - first) {
        valid.store(false, std::memory_order_relaxed);
        return;
      }
      for (std::int64_t corner = first; corner < first + k; ++corner) {
        if (corners[corner] < 0 || corners[corner] >= vertex_count) {
          valid.store(false, std::memory_order_relaxed);
          return;
        }
      }
      const Ring ring{corners + first, k, points};
      const auto [centre, size] = centre_and_size(ring);
      const Vector normal = newell(ring, centre);
      std::copy(normal.begin(), normal.end(), normal_rows + 3 * polygon);
      deviations[polygon] = farthest(ring, centre, normal) / size;
      folds[polygon] = fan_folds(ring, normal, -kFanFold * size * size);
    }
  });
  return valid.load();
}

}  // namespace

void bind_weld(nb::module_& m) {
  m.def(
      "weld_table",
      [](const Grid& corners, std::uint32_t slot_mask, std::int64_t most_probes) {
        return weld_grid(corners, true, slot_mask, most_probes);
      },
      nb::arg("corners").noconvert(), nb::arg("slot_mask"), nb::arg("most_probes"),
      "Weld corners (their bytes, (f, c, 12 or 24)) through a hash table: the distinct points "
      "as float64 in order of first appearance and each corner's point, or None when a corner "
      "had to look more than most_probes slots on.");
  m.def(
      "weld_sort",
      [](const Grid& corners) { return *weld_grid(corners, false, 0, 0); },
      nb::arg("corners").noconvert(),
      "weld_table's answer by a sort of the corners' bits: exact whatever their hashes.");
  m.def("polygon_shapes", &polygon_shapes, nb::arg("counts").noconvert(),
        nb::arg("starts").noconvert(), nb::arg("corner_vertices").noconvert(),
        nb::arg("vertices").noconvert(), nb::arg("normals").noconvert(),
        nb::arg("deviation").noconvert(), nb::arg("folded").noconvert(),
        "Fill normals, deviation and folded for the polygons of four or more corners; False "
        "when a polygon's corners run past the corner array or a corner is not a vertex.");
}

}  // namespace mesh_normal
