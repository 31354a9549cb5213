// Topology: the half-edges sorted by edge, the runs of equal edges (boundary, manifold,
// non-manifold), the union-find with parities that labels the patches, and the checks of their
// winding. The orientation's kernels (cone sums, winding numbers, twinned faces) are in
// topology_orientation.hpp. mesh_normal/mesh/topology.py says what the terms mean.
#include <algorithm>
#include <cstdint>
#include <tuple>
#include <vector>

#include <nanobind/stl/tuple.h>

#include "core.hpp"
#include "topology_orientation.hpp"

namespace mesh_normal {

namespace {

using std::int64_t;

// The largest sort key (edge * 2**bits + ...) must stay below this (topology.KEY_LIMIT).
constexpr int64_t key_limit = int64_t{1} << 62;
// Vertices per piece of the parallel sort of the runs.
constexpr int64_t run_grain = 4096;

using Faces = In<int64_t, nb::shape<-1, 3>>;
using Flags = In<bool, nb::shape<-1>>;

// Whether `value << bits` stays below key_limit (value >= 0, 0 <= bits < 63).
bool below_limit(int64_t value, int64_t bits) { return value < (key_limit >> bits) || value == 0; }

// Checks the arguments of the half-edge sorts (with the GIL held): the sizes, the bits and that
// every index of a valid face is a vertex. Returns 3 x the number of valid faces.
int64_t checked_half_edges(const Faces& faces, const Flags& valid, int64_t vertex_count,
                           int64_t bits) {
  const int64_t count = static_cast<int64_t>(faces.shape(0));
  if (static_cast<int64_t>(valid.shape(0)) != count) {
    throw nb::value_error("valid must have one flag a face.");
  }
  if (vertex_count < 0 || bits < 1 || bits > 62) {
    throw nb::value_error("the vertex count or the key's bits are out of range.");
  }
  if (count >= int64_t{1} << (bits - 1)) {
    throw nb::value_error("the faces do not fit the key's bits.");
  }
  const int64_t* f = faces.data();
  const bool* v = valid.data();
  int64_t used = 0;
  for (int64_t face = 0; face < count; ++face) {
    for (int k = 0; k < 3; ++k) {
      const int64_t index = f[3 * face + k];
      if (index < 0 || index >= vertex_count) {
        throw nb::index_error("a face refers to a vertex that does not exist.");
      }
    }
    used += v[face] ? 1 : 0;
  }
  return 3 * used;
}

// The counting sort's first pass: starts[low + 1] counts the half-edges whose smaller vertex is
// `low`, then the prefix sums make starts[v] the place where vertex v's run begins.
void run_starts(const int64_t* faces, const bool* valid, int64_t count, int64_t vertex_count,
                int64_t* starts) {
  for (int64_t face = 0; face < count; ++face) {
    if (!valid[face]) {
      continue;
    }
    const int64_t* row = faces + 3 * face;
    for (int k = 0; k < 3; ++k) {
      starts[std::min(row[k], row[(k + 1) % 3]) + 1] += 1;
    }
  }
  for (int64_t vertex = 0; vertex < vertex_count; ++vertex) {
    starts[vertex + 1] += starts[vertex];
  }
}

// Each half-edge into its smaller vertex's run as word(low, high, face, forward); `starts`
// then holds each vertex's end.
template <typename Word>
void scatter_half_edges(const int64_t* faces, const bool* valid, int64_t count, int64_t* starts,
                        int64_t* out, const Word& word) {
  for (int64_t face = 0; face < count; ++face) {
    if (!valid[face]) {
      continue;
    }
    const int64_t* row = faces + 3 * face;
    for (int k = 0; k < 3; ++k) {
      const int64_t start = row[k];
      const int64_t end = row[(k + 1) % 3];
      const int64_t forward = start < end ? 1 : 0;
      const int64_t low = forward ? start : end;
      const int64_t high = forward ? end : start;
      out[starts[low]] = word(low, high, face, forward);
      starts[low] += 1;
    }
  }
}

// Sorts each vertex's run of `key` (run v ends at ends[v]) and hands it to finish(vertex,
// first, last), on every thread: each run is its own, so who sorts it changes nothing.
template <typename Finish>
void sort_runs(int64_t* key, const std::vector<int64_t>& ends, const Finish& finish) {
  const int64_t vertices = static_cast<int64_t>(ends.size()) - 1;
  parallel_for(vertices, run_grain, [&](int64_t begin, int64_t end) {
    int64_t first = begin > 0 ? ends[static_cast<std::size_t>(begin - 1)] : 0;
    for (int64_t vertex = begin; vertex < end; ++vertex) {
      const int64_t last = ends[static_cast<std::size_t>(vertex)];
      std::sort(key + first, key + last);  // a few values, mostly in order
      finish(vertex, first, last);
      first = last;
    }
  });
}

// (min * n + max) << bits | face << 1 | forward for the valid faces' half-edges, sorted: a
// counting sort by the smaller vertex (the key's leading part), then a sort of each vertex's
// few half-edges (about six on a closed surface). The same values as a sort of the whole array
// in two passes over it instead of a full sort's many.
void sorted_half_edges(const Faces& faces, const Flags& valid, int64_t vertex_count, int64_t bits,
                       Out<int64_t, nb::shape<-1>> packed) {
  const int64_t size = checked_half_edges(faces, valid, vertex_count, bits);
  if (vertex_count > 0 && vertex_count > ((key_limit >> bits) - 1) / vertex_count) {
    throw nb::value_error("the edge keys do not fit 64 bits with the faces beside them.");
  }
  if (static_cast<int64_t>(packed.shape(0)) != size) {
    throw nb::value_error("packed must have one place for each half-edge of a valid face.");
  }
  const int64_t* f = faces.data();
  const bool* v = valid.data();
  const int64_t count = static_cast<int64_t>(faces.shape(0));
  int64_t* out = packed.data();
  nb::gil_scoped_release release;
  std::vector<int64_t> starts(static_cast<std::size_t>(vertex_count) + 1, 0);
  run_starts(f, v, count, vertex_count, starts.data());
  const auto word = [vertex_count, bits](int64_t low, int64_t high, int64_t face,
                                         int64_t forward) {
    return (low * vertex_count + high) << bits | face << 1 | forward;
  };
  scatter_half_edges(f, v, count, starts.data(), out, word);
  sort_runs(out, starts, [](int64_t, int64_t, int64_t) {});
}

// The half-edges sorted by edge (key min * n + max), then by face, where the key fits 64 bits
// but not with the face beside it: each vertex's run holds max << bits | face << 1 | forward
// (the smaller vertex is the run's), sorted, then split into the three arrays in place.
template <typename FaceIndex>
void wide_half_edges(const Faces& faces, const Flags& valid, int64_t vertex_count, int64_t bits,
                     Out<int64_t, nb::shape<-1>> key, Out<FaceIndex, nb::shape<-1>> face_of,
                     Out<std::int8_t, nb::shape<-1>> forward) {
  const int64_t size = checked_half_edges(faces, valid, vertex_count, bits);
  if (!below_limit(vertex_count, bits)) {
    throw nb::value_error("the vertex count does not fit 64 bits with the faces beside it.");
  }
  if (vertex_count > 0 && vertex_count - 1 > (key_limit - 1) / vertex_count) {
    throw nb::value_error("the edge keys do not fit 64 bits.");
  }
  if (static_cast<int64_t>(key.shape(0)) != size ||
      static_cast<int64_t>(face_of.shape(0)) != size ||
      static_cast<int64_t>(forward.shape(0)) != size) {
    throw nb::value_error("key, face_of and forward must each have a place a half-edge.");
  }
  const int64_t* f = faces.data();
  const bool* v = valid.data();
  const int64_t count = static_cast<int64_t>(faces.shape(0));
  int64_t* words = key.data();
  FaceIndex* faces_out = face_of.data();
  std::int8_t* directions = forward.data();
  nb::gil_scoped_release release;
  std::vector<int64_t> starts(static_cast<std::size_t>(vertex_count) + 1, 0);
  run_starts(f, v, count, vertex_count, starts.data());
  scatter_half_edges(f, v, count, starts.data(), words,
                     [bits](int64_t, int64_t high, int64_t face, int64_t ahead) {
                       return high << bits | face << 1 | ahead;
                     });
  const int64_t mask = (int64_t{1} << (bits - 1)) - 1;
  sort_runs(words, starts, [=](int64_t vertex, int64_t first, int64_t last) {
    for (int64_t row = first; row < last; ++row) {
      const int64_t value = words[row];
      directions[row] = static_cast<std::int8_t>(value & 1);
      faces_out[row] = static_cast<FaceIndex>(value >> 1 & mask);
      words[row] = vertex * vertex_count + (value >> bits);
    }
  });
}

// Walks the runs of equal sorted keys: run(start, length) for each.
template <typename Run>
void each_run(const int64_t* key, int64_t count, const Run& run) {
  int64_t start = 0;
  while (start < count) {
    int64_t end = start + 1;
    while (end < count && key[end] == key[start]) {
      ++end;
    }
    run(start, end - start);
    start = end;
  }
}

// How many runs of equal sorted keys are one long (boundary edges), two (manifold) and more.
std::tuple<int64_t, int64_t, int64_t> count_runs(In<int64_t, nb::shape<-1>> key) {
  const int64_t* k = key.data();
  const int64_t count = static_cast<int64_t>(key.shape(0));
  int64_t counts[3] = {0, 0, 0};
  {
    nb::gil_scoped_release release;
    each_run(k, count,
             [&](int64_t, int64_t length) { counts[std::min<int64_t>(length, 3) - 1]++; });
  }
  return {counts[0], counts[1], counts[2]};
}

// The first position of each run of equal sorted keys, by its length (one, two, more), and
// the length of the longer ones. The outputs must have count_runs' sizes.
template <typename Paired>
void find_runs(In<int64_t, nb::shape<-1>> key, Out<int64_t, nb::shape<-1>> boundary,
               Out<Paired, nb::shape<-1>> paired, Out<int64_t, nb::shape<-1>> nonmanifold,
               Out<int64_t, nb::shape<-1>> uses) {
  if (nonmanifold.shape(0) != uses.shape(0)) {
    throw nb::value_error("nonmanifold and uses must have the same length.");
  }
  const int64_t* k = key.data();
  const int64_t count = static_cast<int64_t>(key.shape(0));
  const int64_t room[3] = {static_cast<int64_t>(boundary.shape(0)),
                           static_cast<int64_t>(paired.shape(0)),
                           static_cast<int64_t>(nonmanifold.shape(0))};
  int64_t* ones = boundary.data();
  Paired* twos = paired.data();
  int64_t* more = nonmanifold.data();
  int64_t* lengths = uses.data();
  int64_t found[3] = {0, 0, 0};
  bool overflow = false;
  {
    nb::gil_scoped_release release;
    each_run(k, count, [&](int64_t start, int64_t length) {
      const int kind = static_cast<int>(std::min<int64_t>(length, 3)) - 1;
      if (found[kind] >= room[kind]) {
        overflow = true;
        return;
      }
      const int64_t at = found[kind]++;
      if (kind == 0) {
        ones[at] = start;
      } else if (kind == 1) {
        twos[at] = static_cast<Paired>(start);
      } else {
        more[at] = start;
        lengths[at] = length;
      }
    });
  }
  if (overflow || found[0] != room[0] || found[1] != room[1] || found[2] != room[2]) {
    throw nb::value_error("the run arrays must have the sizes that count_runs gives.");
  }
}

// For each manifold edge (its first half-edge at paired[i] of the sorted half-edges, the second
// just after): its two faces, and 1 in `same` where they run along it the same way.
template <typename FaceIndex, typename Paired>
void pair_faces(In<FaceIndex, nb::shape<-1>> face, In<std::int8_t, nb::shape<-1>> forward,
                In<Paired, nb::shape<-1>> paired, Out<FaceIndex, nb::shape<-1>> one,
                Out<FaceIndex, nb::shape<-1>> two, Out<std::int8_t, nb::shape<-1>> same) {
  const int64_t half_edges = static_cast<int64_t>(face.shape(0));
  const int64_t count = static_cast<int64_t>(paired.shape(0));
  if (static_cast<int64_t>(forward.shape(0)) != half_edges ||
      static_cast<int64_t>(one.shape(0)) != count || static_cast<int64_t>(two.shape(0)) != count ||
      static_cast<int64_t>(same.shape(0)) != count) {
    throw nb::value_error("face and forward, and paired, one, two and same, must match in size.");
  }
  const FaceIndex* faces = face.data();
  const std::int8_t* directions = forward.data();
  const Paired* firsts = paired.data();
  FaceIndex* ones = one.data();
  FaceIndex* twos = two.data();
  std::int8_t* sames = same.data();
  bool bad = false;
  {
    nb::gil_scoped_release release;
    for (int64_t i = 0; i < count; ++i) {
      const int64_t first = firsts[i];
      if (first < 0 || first + 1 >= half_edges) {
        bad = true;
        break;
      }
      ones[i] = faces[first];
      twos[i] = faces[first + 1];
      sames[i] = static_cast<std::int8_t>(directions[first] ^ directions[first + 1] ^ 1);
    }
  }
  if (bad) {
    throw nb::index_error("a paired position is not a half-edge followed by another.");
  }
}

// The root of `node` and its parity to it; compresses the path on the way.
std::pair<int64_t, std::int8_t> find(int64_t* parent, std::int8_t* relation, int64_t node) {
  int64_t top = node;
  std::int8_t parity = 0;
  while (parent[top] != top) {
    parity ^= relation[top];
    top = parent[top];
  }
  int64_t step = node;
  std::int8_t step_parity = parity;
  while (parent[step] != step) {
    const int64_t following = parent[step];
    const std::int8_t following_parity = step_parity ^ relation[step];
    parent[step] = top;
    relation[step] = step_parity;
    step = following;
    step_parity = following_parity;
  }
  return {top, parity};
}

// Union-find with parities, one pass over the edges in order; the smaller root always wins, so
// the labels are each node's smallest connected node. `root` and `parity` serve as the forest's
// parents and relations: once every path is compressed, each node's parent is its root and its
// relation its parity to it.
template <typename Node>
void union_find(int64_t count, In<Node, nb::shape<-1>> one, In<Node, nb::shape<-1>> two,
                In<std::int8_t, nb::shape<-1>> same, Out<int64_t, nb::shape<-1>> root,
                Out<std::int8_t, nb::shape<-1>> parity) {
  const int64_t edges = static_cast<int64_t>(one.shape(0));
  if (count < 0 || static_cast<int64_t>(root.shape(0)) != count ||
      static_cast<int64_t>(parity.shape(0)) != count ||
      static_cast<int64_t>(two.shape(0)) != edges ||
      static_cast<int64_t>(same.shape(0)) != edges) {
    throw nb::value_error("root and parity must have count places, one, two and same one an edge.");
  }
  const Node* ones = one.data();
  const Node* twos = two.data();
  const std::int8_t* sames = same.data();
  int64_t* parent = root.data();
  std::int8_t* relation = parity.data();
  bool bad = false;
  {
    nb::gil_scoped_release release;
    for (int64_t node = 0; node < count; ++node) {
      parent[node] = node;
      relation[node] = 0;
    }
    for (int64_t edge = 0; edge < edges; ++edge) {
      if (edge + ahead < edges) {  // the nodes of a later edge: far apart in a large mesh
        const int64_t next_one = ones[edge + ahead];
        const int64_t next_two = twos[edge + ahead];
        if (next_one >= 0 && next_one < count && next_two >= 0 && next_two < count) {
          prefetch(parent + next_one);
          prefetch(parent + next_two);
        }
      }
      const int64_t first = ones[edge];
      const int64_t second = twos[edge];
      if (first < 0 || first >= count || second < 0 || second >= count) {
        bad = true;
        break;
      }
      const auto [a, a_parity] = find(parent, relation, first);
      const auto [b, b_parity] = find(parent, relation, second);
      if (a == b) {
        continue;
      }
      const int64_t high = std::max(a, b);
      parent[high] = std::min(a, b);
      relation[high] = static_cast<std::int8_t>(a_parity ^ b_parity ^ sames[edge]);
    }
    for (int64_t node = 0; node < count && !bad; ++node) {
      find(parent, relation, node);
    }
  }
  if (bad) {
    throw nb::index_error("an edge joins a node that does not exist.");
  }
}

// Replaces each valid node's root by its root's number (roots numbered in order), -1 for an
// invalid node, and returns the first node of each number. In place: a root comes before every
// node that it labels, so its number is written before they read it.
nb::ndarray<nb::numpy, int64_t> number_roots(Out<int64_t, nb::shape<-1>> root, Flags valid) {
  const int64_t count = static_cast<int64_t>(root.shape(0));
  if (static_cast<int64_t>(valid.shape(0)) != count) {
    throw nb::value_error("valid must have one flag a node.");
  }
  int64_t* labels = root.data();
  const bool* flags = valid.data();
  int64_t numbers = 0;
  bool bad = false;
  {
    nb::gil_scoped_release release;
    for (int64_t node = 0; node < count; ++node) {
      const int64_t top = labels[node];
      if (top < 0 || top > node) {
        bad = true;
        break;
      }
      if (!flags[node]) {
        labels[node] = -1;
      } else if (top == node) {
        labels[node] = numbers++;
      } else {
        labels[node] = labels[top];
      }
    }
  }
  if (bad) {
    throw nb::value_error("a node's root must be a node at or before it.");
  }
  std::unique_ptr<int64_t[]> firsts(new int64_t[static_cast<std::size_t>(numbers)]);
  {
    nb::gil_scoped_release release;
    int64_t following = 0;
    for (int64_t node = 0; node < count && following < numbers; ++node) {
      if (labels[node] == following) {
        firsts[following++] = node;
      }
    }
  }
  return owned(std::move(firsts), static_cast<std::size_t>(numbers));
}

// Marks False the patch of every edge whose two faces' parities disagree with how they run
// along it: a patch that cannot be wound consistently.
template <typename FaceIndex>
void mark_unorientable(In<FaceIndex, nb::shape<-1>> one, In<FaceIndex, nb::shape<-1>> two,
                       In<std::int8_t, nb::shape<-1>> same, In<std::int8_t, nb::shape<-1>> parity,
                       In<int64_t, nb::shape<-1>> patch, Out<bool, nb::shape<-1>> orientable) {
  const int64_t edges = static_cast<int64_t>(one.shape(0));
  const int64_t faces = static_cast<int64_t>(parity.shape(0));
  const int64_t patches = static_cast<int64_t>(orientable.shape(0));
  if (static_cast<int64_t>(two.shape(0)) != edges ||
      static_cast<int64_t>(same.shape(0)) != edges ||
      static_cast<int64_t>(patch.shape(0)) != faces) {
    throw nb::value_error("one, two and same must have one value an edge, patch one a face.");
  }
  const FaceIndex* ones = one.data();
  const FaceIndex* twos = two.data();
  const std::int8_t* sames = same.data();
  const std::int8_t* parities = parity.data();
  const int64_t* patch_of = patch.data();
  bool* marks = orientable.data();
  bool bad = false;
  {
    nb::gil_scoped_release release;
    for (int64_t i = 0; i < edges; ++i) {
      const int64_t first = ones[i];
      const int64_t second = twos[i];
      if (first < 0 || first >= faces || second < 0 || second >= faces ||
          patch_of[first] < 0 || patch_of[first] >= patches) {
        bad = true;
        break;
      }
      if ((parities[first] ^ parities[second]) != sames[i]) {
        marks[patch_of[first]] = false;
      }
    }
  }
  if (bad) {
    throw nb::index_error("an edge names a face or a patch that does not exist.");
  }
}

// Binds each function under one name: nanobind tries them in turn, and .noconvert() makes an
// array of another dtype pass on to the next one.
template <typename... Function, typename... Extra>
void def_each(nb::module_& m, const char* name, std::tuple<Function...> functions,
              const Extra&... extra) {
  std::apply([&](auto... function) { (m.def(name, function, extra...), ...); }, functions);
}

auto array(const char* name) { return nb::arg(name).noconvert(); }

}  // namespace

void bind_topology(nb::module_& m) {
  using std::int32_t;
  m.def("sorted_half_edges", &sorted_half_edges, array("faces"), array("valid"),
        nb::arg("vertex_count"), nb::arg("bits"), array("packed"),
        "Sort the valid faces' half-edges (min * n + max) << bits | face << 1 | forward into "
        "packed.");
  def_each(m, "wide_half_edges",
           std::make_tuple(&wide_half_edges<int32_t>, &wide_half_edges<int64_t>), array("faces"),
           array("valid"), nb::arg("vertex_count"), nb::arg("bits"), array("key"),
           array("face_of"), array("forward"),
           "The valid faces' half-edges sorted by edge (min * n + max), then by face: key, face "
           "and direction (1 from min to max), where the key does not fit with the face beside "
           "it.");
  m.def("count_runs", &count_runs, array("key"),
        "How many runs of equal sorted keys are one long, two long, and longer.");
  def_each(m, "find_runs", std::make_tuple(&find_runs<int32_t>, &find_runs<int64_t>),
           array("key"), array("boundary"), array("paired"), array("nonmanifold"), array("uses"),
           "The first position of each run of equal sorted keys by its length (one, two, more), "
           "and the lengths of the longer runs.");
  def_each(m, "pair_faces",
           std::make_tuple(&pair_faces<int32_t, int32_t>, &pair_faces<int32_t, int64_t>,
                           &pair_faces<int64_t, int32_t>, &pair_faces<int64_t, int64_t>),
           array("face"), array("forward"), array("paired"), array("one"), array("two"),
           array("same"),
           "The two faces of each manifold edge (paired: its first sorted half-edge) and whether "
           "they run along it the same way.");
  def_each(m, "union_find", std::make_tuple(&union_find<int32_t>, &union_find<int64_t>),
           nb::arg("count"), array("one"), array("two"), array("same"), array("root"),
           array("parity"),
           "Union-find with parities: each node's smallest connected node, and its parity to it.");
  m.def("number_roots", &number_roots, array("root"), array("valid"),
        "Number the roots in order (in place, -1 for invalid nodes); return the roots.");
  def_each(m, "mark_unorientable",
           std::make_tuple(&mark_unorientable<int32_t>, &mark_unorientable<int64_t>),
           array("one"), array("two"), array("same"), array("parity"), array("patch"),
           array("orientable"),
           "Mark False the patch of every edge whose faces' parities disagree.");
  bind_orientation(m);
}

}  // namespace mesh_normal
