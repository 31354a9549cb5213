// Signs of point normals along a tree that exterior evidence may overrule (points/orient.py).
#include <cstdint>
#include <memory>
#include <tuple>

#include <nanobind/stl/tuple.h>

#include "core.hpp"

namespace mesh_normal {

namespace {

using Index = std::int64_t;

// The flips that best agree with `evidence` (per point: positive to keep its normal, negative
// to flip it, by that much) where each step down the tree from `parent` that does not carry
// the sign as `agrees` says costs `cost` (the child's row): the exact optimum over the tree,
// in one pass up `order` (breadth first, each root before its children) and one down. A point
// whose parent is -1 is a root. Ties keep the sign carried down the tree, and a root's normal.
nb::ndarray<nb::numpy, bool> tree_signs(In<std::int32_t, nb::ndim<1>> order,
                                        In<std::int32_t, nb::ndim<1>> parent,
                                        In<bool, nb::ndim<1>> agrees,
                                        In<double, nb::ndim<1>> cost,
                                        In<double, nb::ndim<1>> evidence) {
  const Index n = static_cast<Index>(parent.shape(0));
  if (static_cast<Index>(agrees.shape(0)) != n || static_cast<Index>(cost.shape(0)) != n ||
      static_cast<Index>(evidence.shape(0)) != n) {
    throw nb::value_error("the parents, flags, costs and evidence need one row per point");
  }
  const std::int32_t* walk = order.data();
  const std::int32_t* up = parent.data();
  const Index steps = static_cast<Index>(order.shape(0));
  std::unique_ptr<bool[]> seen(new bool[static_cast<std::size_t>(n)]());
  for (Index s = 0; s < steps; ++s) {
    const std::int32_t i = walk[s];
    if (i < 0 || i >= n || seen[i]) {
      throw nb::index_error("the tree's order must list distinct points");
    }
    if (up[i] >= n || (up[i] >= 0 && !seen[up[i]])) {
      throw nb::index_error("a point in the tree's order comes before its parent");
    }
    seen[i] = true;
  }
  const bool* agree = agrees.data();
  const double* price = cost.data();
  const double* say = evidence.data();
  std::unique_ptr<double[]> keep(new double[static_cast<std::size_t>(n)]);
  std::unique_ptr<double[]> turn(new double[static_cast<std::size_t>(n)]);
  std::unique_ptr<bool[]> flip(new bool[static_cast<std::size_t>(n)]());
  {
    nb::gil_scoped_release release;
    for (Index i = 0; i < n; ++i) {
      keep[i] = say[i];
      turn[i] = -say[i];
    }
    // Up: the best score of each subtree with its root kept or turned.
    for (Index s = steps - 1; s >= 0; --s) {
      const Index i = walk[s];
      const Index p = up[i];
      if (p < 0) {
        continue;
      }
      // The child's state that carries the parent's kept (or turned) sign, and the other.
      const double carried_keep = agree[i] ? keep[i] : turn[i];
      const double carried_turn = agree[i] ? turn[i] : keep[i];
      keep[p] += std::max(carried_keep, carried_turn - price[i]);
      turn[p] += std::max(carried_turn, carried_keep - price[i]);
    }
    // Down: each point's state given its parent's.
    for (Index s = 0; s < steps; ++s) {
      const Index i = walk[s];
      const Index p = up[i];
      if (p < 0) {
        flip[i] = turn[i] > keep[i];
        continue;
      }
      const bool carried = agree[i] ? flip[p] : !flip[p];
      const double stay = carried ? turn[i] : keep[i];
      const double other = carried ? keep[i] : turn[i];
      flip[i] = other - price[i] > stay ? !carried : carried;
    }
  }
  return owned(std::move(flip), static_cast<std::size_t>(n));
}

}  // namespace

void bind_orient(nb::module_& m) {
  m.def("tree_signs", &tree_signs, nb::arg("order").noconvert(), nb::arg("parent").noconvert(),
        nb::arg("agrees").noconvert(), nb::arg("cost").noconvert(),
        nb::arg("evidence").noconvert(),
        "The flips along a tree (parent -1 at roots, order breadth first) that best agree with "
        "the evidence (positive: keep), each step that does not carry the sign as agrees says "
        "costing that child's cost: exact, ties keep the carried sign.");
}

}  // namespace mesh_normal
