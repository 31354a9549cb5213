// Nearest neighbours: a k-d tree over a point cloud and each point's k nearest among the points
// themselves (the neighbourhoods of the point-normal estimate, mesh_normal/points/estimate.py).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core.hpp"

namespace mesh_normal {

namespace {

using Index = std::int64_t;

// Points a leaf holds at most: a leaf is scanned whole, so small leaves prune more and large
// ones descend less.
constexpr Index kLeafSize = 32;

// A query collects up to this many times k candidates before it keeps only the k nearest (and
// prunes by the k-th's distance from then on).
constexpr Index kHeld = 4;

// A candidate neighbour. Ordered by distance, then by index, so that the k nearest are one set
// in one order whatever the tree's shape or the number of threads.
struct Neighbour {
  double distance;  // squared
  Index index;      // the row in the caller's points
};

MESH_NORMAL_INLINE bool before(const Neighbour& a, const Neighbour& b) {
  return a.distance < b.distance || (a.distance == b.distance && a.index < b.index);
}

// A node's points are rows begin..end-1 of the tree's order, inside its box (the smallest that
// holds them). Its first child follows it; `second` is the other's position, -1 at a leaf.
struct Node {
  double low[3];
  double high[3];
  Index begin;
  Index end;
  Index second;
};

// The squared distance from (x, y, z) to a box. Rounding is monotonic, so it is never more than
// the distance computed (the same way) to any point inside: pruning by it loses no neighbour.
MESH_NORMAL_INLINE double box_distance(const Node& node, double x, double y, double z) {
  const double dx = std::max(std::max(node.low[0] - x, x - node.high[0]), 0.0);
  const double dy = std::max(std::max(node.low[1] - y, y - node.high[1]), 0.0);
  const double dz = std::max(std::max(node.low[2] - z, z - node.high[2]), 0.0);
  return dx * dx + dy * dy + dz * dz;
}

// The tree keeps its own copy of the points in its order, so that a leaf's points are adjacent
// in memory and the caller's array may change after it is built.
class PointTree {
 public:
  // `points` (count, 3), finite.
  PointTree(const double* points, Index count)
      : coordinates_(3 * static_cast<std::size_t>(count)),
        index_(static_cast<std::size_t>(count)),
        position_(static_cast<std::size_t>(count)) {
    for (Index i = 0; i < count; ++i) {
      index_[i] = i;
    }
    if (count > 0) {
      nodes_.reserve(static_cast<std::size_t>(2 * (count / kLeafSize + 1)));
      build(points, 0, count, 1);
    }
    for (Index row = 0; row < count; ++row) {
      const Index i = index_[row];
      position_[i] = row;
      for (int axis = 0; axis < 3; ++axis) {
        coordinates_[3 * row + axis] = points[3 * i + axis];
      }
    }
  }

  Index size() const { return static_cast<Index>(index_.size()); }

  // For the rows start..stop-1 of the points: the indices of each one's k nearest, nearest
  // first, ties by the smaller index, into out ((stop - start) rows of k).
  void nearest(Index start, Index stop, Index k, Index* out) const {
    parallel_for(stop - start, 128, [&](Index begin, Index end) {
      std::vector<Neighbour> found(static_cast<std::size_t>(kHeld * k + kLeafSize));
      std::vector<Neighbour> spare(found.size());
      std::vector<Pending> pending(static_cast<std::size_t>(depth_ + 1));
      Buckets buckets(2 * found.size() + 1);
      // The tree's rows of the previous query's k nearest: their farthest from this query
      // bounds its k-th nearest, so that only the points within it are held.
      std::vector<Index> previous(static_cast<std::size_t>(k));
      for (Index q = begin; q < end; ++q) {
        const double* here = coordinates_.data() + 3 * position_[start + q];
        double bound = std::numeric_limits<double>::infinity();
        if (q > begin) {
          double farthest = 0.0;
          for (const Index row : previous) {
            const double* p = coordinates_.data() + 3 * row;
            const double dx = p[0] - here[0];
            const double dy = p[1] - here[1];
            const double dz = p[2] - here[2];
            farthest = std::max(farthest, dx * dx + dy * dy + dz * dz);
          }
          bound = farthest;
        }
        Index held = search(here, k, bound, found.data(), pending.data());
        // Never fewer than k: the bound is k points' distance, computed as search computes
        // it. Checked all the same, since a short list would go unnoticed downstream.
        if (held < k) {
          held = search(here, k, std::numeric_limits<double>::infinity(), found.data(),
                        pending.data());
        }
        const Neighbour* sorted = sort_nearest(found.data(), held, k, buckets, spare.data());
        Index* row = out + q * k;
        for (Index j = 0; j < k; ++j) {
          row[j] = sorted[j].index;
          previous[j] = position_[sorted[j].index];
        }
      }
    });
  }

 private:
  // Per bucket of sort_nearest: its first position, then where its next point goes.
  using Buckets = std::vector<Index>;

  // A subtree still to search and its box's distance from the query.
  struct Pending {
    Index node;
    double distance;
  };

  // Builds the subtree over index_[begin..end-1] at `depth` (the root's is 1): split at the
  // median of the box's widest side, so that the depth is about log2(count / kLeafSize)
  // whatever the points. Returns the node's position.
  Index build(const double* points, Index begin, Index end, Index depth) {
    const Index at = static_cast<Index>(nodes_.size());
    nodes_.push_back(Node{});
    Node node{};
    for (int axis = 0; axis < 3; ++axis) {
      node.low[axis] = std::numeric_limits<double>::infinity();
      node.high[axis] = -std::numeric_limits<double>::infinity();
    }
    for (Index row = begin; row < end; ++row) {
      const double* p = points + 3 * index_[row];
      for (int axis = 0; axis < 3; ++axis) {
        node.low[axis] = std::min(node.low[axis], p[axis]);
        node.high[axis] = std::max(node.high[axis], p[axis]);
      }
    }
    node.begin = begin;
    node.end = end;
    node.second = -1;
    depth_ = std::max(depth_, depth);
    if (end - begin > kLeafSize) {
      int axis = 0;
      for (int a = 1; a < 3; ++a) {
        if (node.high[a] - node.low[a] > node.high[axis] - node.low[axis]) {
          axis = a;
        }
      }
      // Equal coordinates are ordered by index: the split is the same on every platform.
      Index* first = index_.data();
      const Index middle = begin + (end - begin) / 2;
      std::nth_element(first + begin, first + middle, first + end, [&](Index a, Index b) {
        const double pa = points[3 * a + axis];
        const double pb = points[3 * b + axis];
        return pa < pb || (pa == pb && a < b);
      });
      build(points, begin, middle, depth + 1);
      node.second = build(points, middle, end, depth + 1);
    }
    nodes_[at] = node;
    return at;
  }

  // Moves the k nearest of found[0..held-1] to its front (held >= k).
  static void keep_nearest(Neighbour* found, Index held, Index k) {
    if (held > k) {
      std::nth_element(found, found + (k - 1), found + held,
                       [](const Neighbour& a, const Neighbour& b) { return before(a, b); });
    }
  }

  // The k nearest of found[0..held-1] (held >= k), sorted, in found or spare (room for held).
  // A comparison sort's branches are a coin toss each: the candidates are first counted into
  // buckets by distance (a surface's points are about as many in each band of squared
  // distance), then only the buckets that hold the k nearest are sorted, each a few points.
  static const Neighbour* sort_nearest(Neighbour* found, Index held, Index k, Buckets& buckets,
                                       Neighbour* spare) {
    const auto order = [](const Neighbour& a, const Neighbour& b) { return before(a, b); };
    double largest = 0.0;
    for (Index i = 0; i < held; ++i) {
      largest = std::max(largest, found[i].distance);
    }
    const Index count = held;
    const double scale = static_cast<double>(count) / largest;
    if (!(largest > 0.0) || !std::isfinite(scale) || !std::isfinite(largest)) {
      keep_nearest(found, held, k);
      std::sort(found, found + k, order);
      return found;
    }
    // A bucket's number: monotonic in the distance, so bucket order is distance order.
    Index* start = buckets.data();
    std::fill(start, start + count + 1, Index{0});
    for (Index i = 0; i < held; ++i) {
      ++start[1 + std::min(count - 1, static_cast<Index>(found[i].distance * scale))];
    }
    Index last = 0;  // one past the bucket of the k-th nearest
    for (Index b = 1; b <= count; ++b) {
      start[b] += start[b - 1];
      if (last == 0 && start[b] >= k) {
        last = b;
      }
    }
    Index* slot = buckets.data() + count + 1;
    std::copy(start, start + count, slot);
    for (Index i = 0; i < held; ++i) {
      const Index b = std::min(count - 1, static_cast<Index>(found[i].distance * scale));
      spare[slot[b]++] = found[i];
    }
    for (Index b = 0; b < last; ++b) {
      Neighbour* first = spare + start[b];
      Neighbour* end = spare + start[b + 1];
      if (end - first > 16) {
        std::sort(first, end, order);
        continue;
      }
      for (Neighbour* p = first + 1; p < end; ++p) {  // insertion: a few points
        const Neighbour moving = *p;
        Neighbour* hole = p;
        while (hole > first && before(moving, hole[-1])) {
          *hole = hole[-1];
          --hole;
        }
        *hole = moving;
      }
    }
    return spare;
  }

  // Into found (room for kHeld * k + kLeafSize), the points within `bound` (squared) of `q`,
  // among them its k nearest; returns how many. Descends nearer child first, leaving the
  // farther on `pending`. When found fills, only its k nearest are kept and the bound becomes
  // the k-th's distance; a subtree farther than the bound is skipped (one as far may hold a
  // tie of smaller index).
  Index search(const double* q, Index k, double bound, Neighbour* found, Pending* pending) const {
    const double x = q[0];
    const double y = q[1];
    const double z = q[2];
    const double* points = coordinates_.data();
    const Index* index = index_.data();
    const Node* nodes = nodes_.data();
    const Index room = kHeld * k + kLeafSize;
    Index held = 0;
    Index waiting = 0;
    pending[waiting++] = Pending{0, 0.0};
    while (waiting > 0) {
      const Pending next = pending[--waiting];
      if (next.distance > bound) {
        continue;
      }
      Index at = next.node;
      bool pruned = false;
      while (nodes[at].second >= 0) {
        const Index first = at + 1;
        const Index second = nodes[at].second;
        const double near_first = box_distance(nodes[first], x, y, z);
        const double near_second = box_distance(nodes[second], x, y, z);
        const bool first_nearer = near_first <= near_second;
        const Index nearer = first_nearer ? first : second;
        const Index farther = first_nearer ? second : first;
        const double nearer_distance = first_nearer ? near_first : near_second;
        const double farther_distance = first_nearer ? near_second : near_first;
        if (farther_distance <= bound) {
          pending[waiting++] = Pending{farther, farther_distance};
        }
        if (nearer_distance > bound) {
          pruned = true;
          break;
        }
        at = nearer;
      }
      if (pruned) {
        continue;
      }
      const Index end = nodes[at].end;
      if (held + (end - nodes[at].begin) > room) {
        keep_nearest(found, held, k);
        held = k;
        bound = std::max_element(found, found + k, [](const Neighbour& a, const Neighbour& b) {
                  return before(a, b);
                })->distance;
      }
      for (Index row = nodes[at].begin; row < end; ++row) {
        const double* p = points + 3 * row;
        const double dx = p[0] - x;
        const double dy = p[1] - y;
        const double dz = p[2] - z;
        const double distance = dx * dx + dy * dy + dz * dz;
        found[held] = Neighbour{distance, index[row]};
        held += distance <= bound ? 1 : 0;
      }
    }
    return held;
  }

  std::vector<double> coordinates_;  // (count, 3) in the tree's order
  std::vector<Index> index_;         // the caller's row of each row of the tree's order
  std::vector<Index> position_;      // the tree's row of each of the caller's rows
  std::vector<Node> nodes_;          // depth first, the root at 0
  Index depth_ = 0;                  // of the deepest leaf: bounds the pending subtrees
};

PointTree* make_tree(In<double, nb::shape<-1, 3>> points) {
  const double* data = points.data();
  const Index count = static_cast<Index>(points.shape(0));
  for (Index i = 0; i < 3 * count; ++i) {
    if (!std::isfinite(data[i])) {
      throw nb::value_error("the points of a PointTree must be finite");
    }
  }
  nb::gil_scoped_release release;
  return new PointTree(data, count);
}

void nearest(const PointTree& tree, Index start, Index stop, Index k,
             Out<Index, nb::ndim<2>> out) {
  const Index count = tree.size();
  if (start < 0 || stop < start || stop > count) {
    throw nb::value_error("the query rows must satisfy 0 <= start <= stop <= the points");
  }
  if (k < 1 || k > count) {
    throw nb::value_error("k must be from 1 to the number of points");
  }
  if (static_cast<Index>(out.shape(0)) != stop - start || static_cast<Index>(out.shape(1)) != k) {
    throw nb::value_error("out needs one row per query row and k columns");
  }
  Index* rows = out.data();
  nb::gil_scoped_release release;
  tree.nearest(start, stop, k, rows);
}

}  // namespace

void bind_nearest(nb::module_& m) {
  nb::class_<PointTree>(m, "PointTree",
                        "A k-d tree over (m, 3) float64 finite points, with a copy of them.")
      .def(nb::new_(&make_tree), nb::arg("points").noconvert(),
           "Build the tree over points ((m, 3) float64, C-contiguous, finite).")
      .def("__len__", &PointTree::size, "The number of points.")
      .def("nearest", &nearest, nb::arg("start"), nb::arg("stop"), nb::arg("k"),
           nb::arg("out").noconvert(),
           "Into out ((stop - start, k) int64): for each of the rows start..stop-1 of the "
           "points, the indices of its k nearest among them, nearest first, equal distances "
           "by the smaller index (a point is its own nearest).");
}

}  // namespace mesh_normal
