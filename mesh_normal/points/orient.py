"""Signs for unoriented point normals: along a spanning tree, or towards a reference.

``"mst"`` (Hoppe et al. 1992, as in CGAL's ``mst_orient_normals``): the symmetric graph of each
point's nearest neighbours, weighted by 1 - |n_i . n_j|, its minimum spanning tree (scipy's
csgraph), and signs carried from a seed down the tree. A spanning tree of least weight is also
one whose path between any two points has the smallest possible largest step, so a sign is
never carried across an edge sharper than ``max_angle`` when a gentler path exists; points the
seed reaches only across one take their own votes (below), or, where none of them sees the
outside, are left unoriented and reported, as CGAL does.

``"riemannian"``: the same tree over a graph without the edges that leave either point's
tangent plane by more than ``max_angle`` (a neighbour across a thin wall or on a nearby sheet,
whose normal line is parallel but whose side is not), each edge also weighted by how far it
leaves them. It is the one to use for thin structures and sheets closer together than the
spacing of their points.

Each connected part of the graph is seeded on its own, at an extreme point: its highest, whose
normal is turned up, if that normal is within 60 degrees of vertical; otherwise its farthest
along +x, -x, +y, -y, then -z, the first whose normal is within 60 degrees of that axis. On a
closed surface the extreme point along a direction has its outward normal along it (the plane
through it holds the whole surface on one side), so a closed surface points out, and an open
terrain up. A part with no such point is left unoriented and says so.

On a closed surface the points then vote (``_outside``): on a grid of cells a few spacings
wide, a point whose normal line has the outside (empty cells joined to the grid's corner) on one
side and an enclosed empty cell on the other says which way it faces; a point of a part too thin
to enclose a cell (a leg, a tail), by the side that is outside more often past its own surface,
where the cloud is of closed surfaces (an open scan's far side is often not outside). The signs
along the tree are the ones that best agree with those votes and the seed's side when changing
the sign at a step of the tree costs ``_STEP_COST`` points (an exact pass up and down the tree),
so a part the tree reached the wrong way, across a thin wall or where two closed parts cross, is
turned back by its own points, and a closed part's side is its points' vote, not one seed's. A
piece reached only across a sharp step is oriented by its own votes too, and left unoriented
only when none of its points sees the outside. An open sheet or terrain sees the outside on both
sides: nothing votes, and the seed decides as before.

``"viewpoint"``, ``"direction"`` and ``"file"`` decide each point alone, towards a sensor, along
a vector, or agreeing with stored normals; a point at right angles to its reference (to 2**-20)
is left unoriented.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, get_args

import numpy as np
from numpy.typing import NDArray

import mesh_normal._core as _core
from mesh_normal.choices import OrientMode as OrientMode
from mesh_normal.tolerances import ORIENT_POINT_COSINE, ORIENT_SEED_COSINE
from mesh_normal.types import BoolArray, FloatArray, IndexArray

ORIENT_MODES: tuple[OrientMode, ...] = get_args(OrientMode)

#: Added to every edge weight: scipy's graphs take a zero weight for no edge. Adding the same
#: amount to every edge does not change which spanning tree is least.
_WEIGHT_FLOOR = 2.0**-30

#: The ways a part is looked at for its seed, in order: up first, so that an open terrain
#: faces up; the first whose farthest point has a normal within 60 degrees of it decides.
_SEED_DIRECTIONS = tuple(
    np.array(d, dtype=np.float64)
    for d in ((0, 0, 1), (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, -1))
)


#: The outside is seen on a grid of cells this many times the median distance from a point to
#: its ``_CELL_NEIGHBOUR``-th nearest (the point itself is the 0th): wide enough that a surface
#: sampled at random, or with noise, leaves no empty cell through it once grown by one cell.
_CELL_SPACINGS = 2.5
_CELL_NEIGHBOUR = 6

#: At most this many cells in the grid (a large cloud or a far outlier widens them).
_CELL_MOST = 2**23

#: A point looks this many cells along its normal line each way, nearest first, for the outside
#: on one side and the inside on the other.
_PROBES = (1.5, 3.0, 5.0)

#: A point's own surface, grown by one cell, reaches at most this many cells along its normal:
#: farther probes see past it, so a thin part's inside (filled) and its outside differ there,
#: while an open sheet's two sides are both outside.
_OWN_BAND = 2.0

#: A cloud is of closed surfaces, and its thin parts' votes count, when at least this share of
#: its points see an enclosed cell: most of a closed surface's do (the ant, whose legs and
#: antennae enclose none, 18% at noise 0.006; a sparse closed model 8%), an open scan's almost
#: none (0 to 0.2% on PCL's terrains, rooms and objects). The whole cloud's share, not each
#: connected part's: a thin part apart from its body (an antenna) encloses nothing itself.
_CLOSED_SHARE = 0.04

#: What turning the sign against one step of the tree costs, in points that see the outside: a
#: few points that see it wrongly (where the grid is coarse) turn nothing, a part whose side the
#: tree carried wrongly across a thin wall or where two parts cross is turned by its own points.
_STEP_COST = 50.0

#: What the seed's side (its extreme point) counts for, in points that see the outside: it
#: decides a part that sees no outside (an open sheet, terrain), and the points seeing the
#: outside decide a closed one.
_SEED_EVIDENCE = 8.0


@dataclass(frozen=True, slots=True)
class ComponentOrientation:
    """How one connected part of the cloud was oriented.

    Attributes
    ----------
    points : int
        Its points that have a normal.
    flipped : int
        Those whose normal was turned.
    unoriented : int
        Those whose side could not be decided (their normal keeps its canonical sign).
    reason : str
        Why, in one sentence; empty when every point was oriented.
    seed : int
        The input index of the tree's root, the extreme point whose side counts with the
        votes of the points that see the outside (-1 when there is none).
    """

    points: int
    flipped: int
    unoriented: int
    reason: str
    seed: int


@dataclass(frozen=True, slots=True, eq=False)
class Signs:
    """Which normals to flip and which are left unoriented, per point; and the parts.

    Seeds in ``components`` index the arrays the caller passed (the caller maps them).
    """

    flip: BoolArray
    unoriented: BoolArray
    components: tuple[ComponentOrientation, ...]


def towards(
    normals: FloatArray,
    valid: BoolArray,
    references: FloatArray,
    what: str,
    weight: IndexArray,
) -> Signs:
    """Turn each valid normal to make a positive dot product with its row of ``references``.

    ``references`` is (n, 3) or (3,); a zero, non-finite or perpendicular one leaves the point
    unoriented. The one summary is the whole cloud's (``what`` names the reference), each row
    counting as ``weight`` points in it (a place and its copies).
    """
    references = np.broadcast_to(references, normals.shape)
    with np.errstate(invalid="ignore", over="ignore"):
        lengths = np.sqrt(np.einsum("ij,ij->i", references, references))
        dots = np.einsum("ij,ij->i", normals, references)
    decided = (
        np.isfinite(lengths) & np.isfinite(dots) & (np.abs(dots) > ORIENT_POINT_COSINE * lengths)
    )
    decided &= lengths > 0
    flip = valid & decided & (dots < 0)
    unoriented = valid & ~decided
    left = int(weight[unoriented].sum())
    reason = f"{left} points are at right angles to the {what} or have none" if left else ""
    summary = ComponentOrientation(
        int(weight[valid].sum()), int(weight[flip].sum()), left, reason, -1
    )
    return Signs(flip, unoriented, (summary,) if valid.any() else ())


def along_tree(
    points: FloatArray,
    normals: FloatArray,
    valid: BoolArray,
    graph: NDArray[np.int32],
    max_angle: float,
    offsets: bool,
    weight: IndexArray,
) -> Signs:
    """Signs along minimum spanning trees of the neighbour graph; see the module docstring.

    Parameters
    ----------
    points : (n, 3) float64
        Coordinates centred on the cloud (the seeds look outward from the origin).
    normals : (n, 3) float64
        Unit rows where ``valid``.
    valid : (n,) bool
    graph : (n, g) int
        Each point's nearest neighbours, -1 where there are fewer.
    max_angle : float
        Degrees, in (0, 90].
    offsets : bool
        The ``"riemannian"`` graph: drop edges that leave a tangent plane by over ``max_angle``.
    weight : (n,) int
        How many points each row stands for (a place and its copies), in the summaries' counts
        and the sizes of pieces.
    """
    from scipy.sparse import coo_matrix  # type: ignore[import-untyped]  # on first use
    from scipy.sparse.csgraph import (  # type: ignore[import-untyped]
        breadth_first_order,
        connected_components,
        minimum_spanning_tree,
    )

    n = len(points)
    sharp_cosine = math.cos(math.radians(max_angle))
    rows, cols, weights = _edges(points, normals, valid, graph, offsets, sharp_cosine)
    graph_matrix = coo_matrix((weights, (rows, cols)), shape=(n, n)).tocsr()
    del rows, cols, weights
    tree = minimum_spanning_tree(graph_matrix, overwrite=True)
    del graph_matrix
    count, labels = connected_components(tree, directed=False)
    # Seeds come from each part's largest piece between sharp edges of its tree, and from the
    # whole part only where that piece has no point to decide: an outlier above a scan is its
    # highest point, but seeded there the sign would reach the scan only across a sharp edge.
    main, piece = _main_pieces(tree, normals, valid, weight, labels, sharp_cosine)
    seeds, seed_flip, decided = _seeds(points, normals, main, labels, count)
    if not decided.all():
        more = _seeds(points, normals, valid, labels, count)
        fill = ~decided & more[2]
        seeds[fill], seed_flip[fill], decided[fill] = more[0][fill], more[1][fill], True
    # One breadth-first walk from a virtual root joined to every decided seed.
    tree = tree.tocoo()
    root = np.full(len(seeds[decided]), n)
    walk = coo_matrix(
        (
            np.concatenate([tree.data, np.ones(len(root))]),
            (np.concatenate([tree.row, root]), np.concatenate([tree.col, seeds[decided]])),
        ),
        shape=(n + 1, n + 1),
    ).tocsr()
    order, parent = breadth_first_order(walk, n, directed=False, return_predecessors=True)
    order, parent = order[1:], parent[:n].copy()
    parent[parent == n] = -1
    reached = np.zeros(n, dtype=bool)
    reached[order] = True
    agrees, sharp = _tree_steps(normals, parent, reached, sharp_cosine)
    flags = np.zeros(n, dtype=bool)
    flags[seeds[decided]] = seed_flip[decided]
    order32, parent32 = order.astype(np.int32, copy=False), parent.astype(np.int32, copy=False)
    _, cut = _core.propagate_signs(order32, parent32, agrees, sharp, flags)
    # The tree's signs, overruled where the outside seen from the points says otherwise: a
    # subtree turns against its parent when more of its points see the outside on the other
    # side than a step costs. Below a sharp step nothing is carried (those points are cut).
    strong, weak = _outside(points, normals, valid, graph)
    # Thin parts' votes count only in a cloud of closed surfaces: in an open scan one side of
    # the surface is the outside and the other often is not (a crown over the ground).
    closed = weight[strong != 0].sum() >= _CLOSED_SHARE * weight[valid].sum()
    evidence = np.where(strong != 0, strong, weak if closed else 0.0) * weight.astype(np.float64)
    evidence[seeds[decided]] += np.where(seed_flip[decided], -_SEED_EVIDENCE, _SEED_EVIDENCE)
    carried = np.where(sharp, -1, parent32).astype(np.int32)
    cost = np.full(n, _STEP_COST)
    flip = _core.tree_signs(order32, carried, agrees, cost, evidence)
    # A piece below a sharp step (the tree's edges there are its steps) is oriented when its
    # own points see the outside (or hold a seed); one that sees nothing keeps its canonical
    # sign and is reported.
    seen = np.bincount(piece, weights=np.abs(evidence)) > 0
    unoriented = valid & ((cut & ~seen[piece]) | ~reached)
    flip &= valid & ~unoriented
    summaries = _summaries(
        labels, count, (valid, flip, unoriented), weight, seeds, decided, max_angle
    )
    return Signs(flip, unoriented, summaries)


def _outside(
    points: FloatArray, normals: FloatArray, valid: BoolArray, graph: NDArray[np.int32]
) -> tuple[FloatArray, FloatArray]:
    """(n,) float twice: +1 where a point's normal points out of the closed surface it lies on,
    -1 where it points in, 0 where that cannot be seen; by enclosed cells, and by a thin part's
    filled inside.

    The points are put in cells a few spacings wide (``_CELL_SPACINGS`` times the median distance
    to a point's ``_CELL_NEIGHBOUR``-th nearest), grown by one cell so that the surface leaves no
    gap, and the empty cells joined to the grid's corner are the outside. A point decides when,
    stepping ``_PROBES`` cells along its normal line, one side is outside and the other is an
    empty cell the outside does not reach (within a closed surface), the nearest probe first.
    A thin part (a leg, a tail, an ear) has no such cell: the grown surface fills its inside.
    Its point votes for the side that is outside at more of the probes past its own surface
    (``_OWN_BAND``): the other side is the part's filled inside there. An open sheet, outside
    on both sides, and a surface whose inside the noise fills decide nothing; the thin parts'
    votes count only in a cloud of closed surfaces (``_CLOSED_SHARE``).
    """
    from scipy import ndimage  # type: ignore[import-untyped]  # on first use

    n = len(points)
    evidence, thin = np.zeros(n), np.zeros(n)
    rows = np.flatnonzero(valid)
    if len(rows) < 4 or graph.shape[1] < 2:
        return evidence, thin
    column = graph[rows, min(_CELL_NEIGHBOUR, graph.shape[1] - 1)]
    far = column >= 0
    if not far.any():
        return evidence, thin
    spacing = float(np.median(np.linalg.norm(points[column[far]] - points[rows[far]], axis=1)))
    low, high = points[rows].min(axis=0), points[rows].max(axis=0)
    # Cells a few spacings wide, or wider where the grid would hold too many (a large cloud,
    # outliers far away); two cells of margin keep the corner outside.
    cell = _CELL_SPACINGS * spacing
    if not cell > 0:
        return evidence, thin
    while np.prod(np.floor((high - low) / cell) + 5) > _CELL_MOST:
        cell *= 1.25
    low = low - 2 * cell
    shape = np.floor((high - low) / cell).astype(np.intp) + 3
    occupied = np.zeros(tuple(shape), dtype=bool)
    occupied[tuple(np.floor((points[rows] - low) / cell).astype(np.intp).T)] = True
    occupied = ndimage.binary_dilation(occupied)
    labels, _ = ndimage.label(~occupied)
    # 1 outside, -1 an empty cell within, 0 a cell the surface fills.
    kind = np.where(occupied, 0, np.where(labels == labels[0, 0, 0], 1, -1)).astype(np.int8)

    def seen(at: FloatArray) -> NDArray[np.int8]:
        index = np.floor((at - low) / cell).astype(np.intp)
        within = np.all((index >= 0) & (index < shape), axis=1)  # past the grid is outside
        found = np.ones(len(at), dtype=np.int8)
        found[within] = kind[tuple(index[within].T)]
        return found

    strong, weak = np.zeros(len(rows)), np.zeros(len(rows))
    for probe in _PROBES:
        step = probe * cell * normals[rows]
        ahead, behind = seen(points[rows] + step), seen(points[rows] - step)
        undecided = strong == 0
        strong[undecided & (ahead == 1) & (behind == -1)] = 1.0
        strong[undecided & (ahead == -1) & (behind == 1)] = -1.0
        if probe > _OWN_BAND:
            weak += (ahead == 1).astype(np.float64) - (behind == 1)
    evidence[rows], thin[rows] = strong, np.sign(weak) * (strong == 0)
    return evidence, thin


def _edges(
    points: FloatArray,
    normals: FloatArray,
    valid: BoolArray,
    graph: NDArray[np.int32],
    offsets: bool,
    sharp_cosine: float,
) -> tuple[NDArray[np.int32], NDArray[np.int32], FloatArray]:
    """The graph's edges between valid points, each once: their ends and weights."""
    # Leaving a tangent plane by more than max_angle: a neighbour across a wall.
    sine_limit = math.sqrt(max(0.0, 1.0 - sharp_cosine**2)) if offsets else 1.0
    return _core.graph_edges(points, normals, valid, graph, _WEIGHT_FLOOR, sine_limit)


def _main_pieces(
    tree: Any,
    normals: FloatArray,
    valid: BoolArray,
    weight: IndexArray,
    labels: IndexArray,
    sharp_cosine: float,
) -> tuple[BoolArray, IndexArray]:
    """(n,) bool: the valid points of each part's largest piece (in points, ``weight`` each)
    once its tree's sharp edges are cut (the first such piece where two are as large); and
    (n,) the piece of every point."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(normals)
    edges = tree.tocoo()
    dots = np.einsum("ij,ij->i", normals[edges.row], normals[edges.col])
    gentle = np.abs(dots) >= sharp_cosine
    pieces = coo_matrix(
        (np.ones(int(gentle.sum())), (edges.row[gentle], edges.col[gentle])), shape=(n, n)
    )
    count, piece = connected_components(pieces, directed=False)
    sizes = np.bincount(piece, weights=valid * weight, minlength=count)
    part_of = np.empty(count, dtype=np.intp)
    part_of[piece] = labels
    order = np.lexsort((-sizes, part_of))
    largest = order[np.r_[True, part_of[order][1:] != part_of[order][:-1]]]
    main = np.zeros(count, dtype=bool)
    main[largest] = True
    chosen: BoolArray = valid & main[piece]
    return chosen, piece


def _seeds(
    points: FloatArray, normals: FloatArray, valid: BoolArray, labels: IndexArray, count: int
) -> tuple[IndexArray, BoolArray, BoolArray]:
    """Each part's seed among the ``valid`` points, whether the seed must be flipped, and
    whether it decides at all."""
    seeds = np.full(count, -1)
    seed_flip = np.zeros(count, dtype=bool)
    decided = np.zeros(count, dtype=bool)
    members = np.flatnonzero(valid)
    members = members[np.argsort(labels[members], kind="stable")]
    part = labels[members]
    starts = np.flatnonzero(np.r_[True, part[1:] != part[:-1]]) if len(part) else part
    for direction in _SEED_DIRECTIONS:
        heights = points[members] @ direction
        highest = members[_first_maximum(heights, starts)]
        cosines = normals[highest] @ direction
        take = ~decided[part[starts]] & (np.abs(cosines) >= ORIENT_SEED_COSINE)
        chosen = part[starts][take]
        seeds[chosen], seed_flip[chosen], decided[chosen] = highest[take], cosines[take] < 0, True
    return seeds, seed_flip, decided


def _first_maximum(values: FloatArray, starts: IndexArray) -> IndexArray:
    """Within each run of ``values`` from ``starts``, the position of its first maximum."""
    if len(starts) == 0:
        return starts
    peaks = np.maximum.reduceat(values, starts)
    run = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(values)]))
    at_peak = np.flatnonzero(values == peaks[run])
    return at_peak[np.r_[True, run[at_peak][1:] != run[at_peak][:-1]]]


def _tree_steps(
    normals: FloatArray, parent: IndexArray, reached: BoolArray, sharp_cosine: float
) -> tuple[BoolArray, BoolArray]:
    """Per point: whether its normal agrees with its parent's, and whether that step is sharp."""
    child = np.flatnonzero(reached & (parent >= 0))
    dots = np.einsum("ij,ij->i", normals[child], normals[parent[child]])
    agrees = np.ones(len(parent), dtype=bool)
    sharp = np.zeros(len(parent), dtype=bool)
    agrees[child] = dots >= 0
    sharp[child] = np.abs(dots) < sharp_cosine
    return agrees, sharp


def _summaries(
    labels: IndexArray,
    count: int,
    masks: tuple[BoolArray, BoolArray, BoolArray],
    weight: IndexArray,
    seeds: IndexArray,
    decided: BoolArray,
    max_angle: float,
) -> tuple[ComponentOrientation, ...]:
    """One summary per part that has valid points, largest first; ``masks`` are the valid,
    flipped and unoriented rows, each row counting as ``weight`` points."""
    points, flipped, left = (
        np.bincount(labels, weights=mask * weight, minlength=count).astype(np.intp)
        for mask in masks
    )
    summaries = []
    for label in np.argsort(-points, kind="stable")[: int((points > 0).sum())]:
        if not decided[label]:
            reason = "no point of it faces clearly outward or up: give a viewpoint or a direction"
        elif left[label]:
            reason = f"reached only across edges sharper than {max_angle:g} degrees"
        else:
            reason = ""
        seed = int(seeds[label]) if decided[label] else -1
        summaries.append(
            ComponentOrientation(
                int(points[label]), int(flipped[label]), int(left[label]), reason, seed
            )
        )
    return tuple(summaries)
