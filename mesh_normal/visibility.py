"""Which side of an open patch is outside: the side from which the rest of the world is seen.

An open patch (a bowl, a car body panel, a scan fragment, one side of a box whose sides have
their own vertices) encloses nothing, so no volume tells its outside. It is decided by
*visibility from outside*, as libigl's ``reorient_facets_raycast`` does: rays leave sample
points of the patch on both sides, and the side from which more of them escape to infinity,
missing every face of the whole mesh, is outside. So the pieces of an object are judged
together: the inner side of a car's panel looks at the other panels, its outer side at the
sky; the inside of a bowl sees the bowl; six separate sides of a box see each other inside.

The method, fixed so that the verdict is the same wherever the mesh is, however it is turned
and scaled (up to rounding, which only a ray grazing an edge can feel):

- *Samples*: up to ``SAMPLES`` faces of each patch, spread evenly over its faces in file
  order; at the centroid of each, ``DIRECTIONS`` rays on each side, in a fixed pattern of the
  face's own frame (its first edge by vertex number, and its plane's normal), between
  ``ELEVATION_SINE`` and straight up from the face: the pattern turns with the mesh and does
  not depend on the face's winding, so flipping a patch exactly swaps its two counts.
- *Escape*: a ray escapes when it hits no other face of the mesh farther than ``T_MIN`` (a
  fraction of the mesh's size: a face lying on the sample's own face, a duplicate, does not
  block it). The mesh is centred and scaled to its bounding box first, so a mesh far from
  the origin is tested in coordinates of its own size. Hits are found in a bounding-volume
  hierarchy (faces sorted along a Morton curve, split in halves; any hit ends the search).
- *Evidence*: the patch's score is the area-weighted share of escaping rays on the side its
  consistent winding faces minus that on the other side, in [-1, 1]. The patch is decided
  only when the score is at least ``MARGIN`` in size: a plane sheet, a slightly curved scan
  or a single triangle sees the world from both sides alike, a patch shut inside another
  object sees it from neither, and those stay undetermined (nothing flipped).
- *Cost*: at most ``RAYS`` rays in all. With many patches each gets fewer samples (never fewer
  than ``FEWEST``); beyond ``RAYS / (2 DIRECTIONS FEWEST)`` patches the largest by area are
  decided and the others stay undetermined.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from mesh_normal.bounds import column_bounds
from mesh_normal.kernels import (
    AHEAD,
    BLOCK,
    PARALLEL_KERNELS,
    announce_compiling,
    claim,
    kernel,
    lower_bound,
    prange,
    prefetch,
    prefetch_row,
    workers,
)
from mesh_normal.types import BoolArray, FloatArray, IndexArray, ParityArray

#: Rays per side of each sample.
DIRECTIONS = 16
#: The lowest ray leaves the face at an angle whose sine is this (about 6 degrees): lower rays
#: graze the neighbours of a face on a gently curved patch.
ELEVATION_SINE = 0.1
#: Most and fewest sample faces per patch, and the most rays in all.
SAMPLES = 32
FEWEST = 4
RAYS = 2**19
#: A patch is decided when the escaping shares of its two sides differ by at least this.
MARGIN = 0.35
#: Hits nearer than this fraction of the half-diagonal of the mesh's box do not block a ray.
T_MIN = 2.0**-30
#: Faces per leaf of the hierarchy: at least ``_LEAF``, and up to ``_WIDEST_LEAF`` where the
#: rays are few for the faces (see :func:`leaf_size`).
_LEAF = 4
_WIDEST_LEAF = 64
#: The largest call of these kernels, in array elements, that runs in Python before numba is
#: loaded (see :data:`mesh_normal.kernels.PYTHON_ELEMENTS`): a dozen faces. Casting rays in
#: Python is about a hundred times slower than compiled (100 faces of a soup take about 3 s).
PYTHON_RAYS = 600
#: What a ray meets (see :func:`_blocked`).
_CLEAR, _HIT, _UNSURE = range(3)
#: A hit this close (in barycentric coordinates, or in the sine of the angle to the face's
#: plane) to a face's edge or plane is unsure: another position, turn or scale of the mesh
#: may round it the other way. Far above rounding (about 1e-15 here), far below a real edge.
_UNSURE_BAND = 2.0**-30


def _directions() -> FloatArray:
    """(DIRECTIONS, 3): a Fibonacci spiral over the band of the hemisphere above the face,
    as (along the first edge, across it, along the normal), equal solid angle each."""
    i = np.arange(DIRECTIONS) + 0.5
    up = 1.0 - i / DIRECTIONS * (1.0 - ELEVATION_SINE)
    turn = i * math.pi * (3.0 - math.sqrt(5.0))
    around = np.sqrt(1.0 - up * up)
    return np.column_stack([around * np.cos(turn), around * np.sin(turn), up])


@kernel(python=True)  # here, not in kernels: the face normals never compile it
def prefetch_corners(points: np.ndarray, faces: IndexArray, face: int) -> None:
    """Ask for the rows of ``points`` at ``face``'s three corners, if there is such a face
    (a loop over faces in file order reads points far apart in a large, shuffled mesh). The
    orientation's cone terms use it too."""
    if face < len(faces):
        prefetch_row(points, faces[face, 0])
        prefetch_row(points, faces[face, 1])
        prefetch_row(points, faces[face, 2])


def visible_sides(
    points: FloatArray,
    faces: IndexArray,
    group: IndexArray,
    parity: ParityArray,
    candidates: BoolArray,
    area: FloatArray,
    ahead: Callable[[], Framed | None] | None = None,
) -> FloatArray:
    """The visibility score of each of the ``candidates`` (open, orientable patches).

    Parameters
    ----------
    points : (n, 3) float64
        The vertices (any finite scale).
    faces : (m, 3) intp
        Every face of the mesh: all of them can block a ray.
    group, parity : (m,)
        Each face's patch (``len(candidates)`` for faces in none) and whether it is wound
        against its patch's first face.
    candidates : (p,) bool
        The patches to score.
    area : (p,) float64
        Each patch's area (any common scale): past the budget the largest are scored.
    ahead : callable, optional
        Gives :func:`framed` of ``points`` and ``faces``, taken ahead on another thread (see
        ``mesh_normal.orientation.HeadStart``); else it is taken here.

    Returns
    -------
    (p,) float64
        In [-1, 1]: the area-weighted share of escaping rays on the side that the patch
        faces when wound like its first face, minus that on its other side; NaN where the
        patch was not scored. A patch is decided when the score is at least ``MARGIN`` in
        size, and faces inward when it is negative.
    """
    patches = len(candidates)
    score = np.full(patches, np.nan)
    chosen = np.flatnonzero(candidates)
    if len(chosen) == 0:
        return score
    frame = ahead() if ahead is not None else framed(points, faces)
    if frame is None:
        return score
    unit, ordered = frame
    most = RAYS // (2 * DIRECTIONS * FEWEST)
    if len(chosen) > most:
        chosen = np.sort(chosen[np.argsort(-area[chosen], kind="stable")[:most]])
    per = int(np.clip(RAYS // (2 * DIRECTIONS * len(chosen)), FEWEST, SAMPLES))
    samples, owner = _samples(group, chosen, per)
    leaf = leaf_size(len(faces), 2 * DIRECTIONS * len(samples))
    order, boxes, children, spans, corners = _hierarchy(unit, faces, leaf, ordered)
    del frame, ordered
    escaped = np.zeros((len(samples), 2))  # share of escaping rays: + side, - side of the plane
    unsure = np.zeros((len(samples), 2))  # share of rays that may escape or not
    weights = np.zeros(len(samples))
    against = np.zeros(len(samples), dtype=np.bool_)
    announce_compiling()
    with PARALLEL_KERNELS:
        _cast(
            unit, faces, corners, order, boxes, children, spans, samples, _directions(), T_MIN,
            escaped, unsure, weights, against,
        )  # fmt: skip
    # The side the patch faces when wound like its first face: + if the sample face is wound
    # like the increasing order of its vertex numbers (against is false), turned by its parity.
    facing = against ^ parity[samples].astype(bool)
    front = np.where(facing, escaped[:, 1], escaped[:, 0])
    back = np.where(facing, escaped[:, 0], escaped[:, 1])
    doubt = unsure[:, 0] + unsure[:, 1]  # each unsure ray may swing the difference by one
    total = np.bincount(owner, weights, len(chosen))
    difference = np.bincount(owner, weights * (front - back), len(chosen))
    swing = np.bincount(owner, weights * doubt, len(chosen))
    scored = total > 0
    lowest = (difference - np.where(difference > 0, swing, 0.0))[scored] / total[scored]
    highest = (difference + np.where(difference < 0, swing, 0.0))[scored] / total[scored]
    # The score as counted with every unsure ray against it: its sign and size hold whichever
    # way rounding takes those rays; where they could take it to zero or past it, zero.
    surely = np.where(difference[scored] > 0, np.maximum(lowest, 0.0), np.minimum(highest, 0.0))
    score[chosen[scored]] = surely
    return score


def _samples(group: IndexArray, chosen: IndexArray, per: int) -> tuple[IndexArray, IndexArray]:
    """Up to ``per`` faces of each chosen patch, evenly spread in file order, and the index
    into ``chosen`` of each one's patch: of a patch of c faces that gives t = min(c, per),
    its members number (r c) // t for r = 0 .. t - 1, patch after patch in ``chosen``'s order.

    One pass over the faces picks them (:func:`_pick_samples`); gathering each patch's
    members with a stable sort first takes about half a second at the Lucy size for a patch of
    every face.
    """
    slot = np.full(int(group.max(initial=0)) + 1, -1, dtype=np.intp)
    slot[chosen] = np.arange(len(chosen))
    counts = np.bincount(group, minlength=len(slot))[chosen]
    take = np.minimum(counts, per)
    offsets = np.cumsum(take) - take
    samples = np.empty(int(take.sum()), dtype=np.intp)
    announce_compiling()
    _pick_samples(group, slot, counts, take, offsets, samples)
    return samples, np.repeat(np.arange(len(chosen)), take)


@kernel(python=PYTHON_RAYS)
def _pick_samples(
    group: IndexArray,
    slot: IndexArray,
    counts: IndexArray,
    take: IndexArray,
    offsets: IndexArray,
    samples: IndexArray,
) -> None:
    """``samples[offsets[i] + r]``: member (r counts[i]) // take[i] of chosen patch i, for
    r < take[i]; ``slot[g]`` is the chosen patch i of group g, or -1."""
    seen = np.zeros(len(counts), dtype=np.int64)
    ranks = np.zeros(len(counts), dtype=np.int64)
    for face in range(len(group)):
        patch = group[face]
        if patch >= len(slot) or slot[patch] < 0:
            continue
        i = slot[patch]
        rank = ranks[i]
        if rank < take[i] and seen[i] == rank * counts[i] // take[i]:
            samples[offsets[i] + rank] = face
            ranks[i] = rank + 1
        seen[i] += 1


def leaf_size(faces: int, rays: int) -> int:
    """Faces per leaf: 4, or more where building the hierarchy would cost far more than the
    rays cast through it: a power of two up to ``_WIDEST_LEAF`` near ``faces / (8 rays)``.

    Any leaf size gives the same answers (a ray meets the same faces: every box holding
    them, padded, is entered). One open patch of the Dragon-size torus casts 1024 rays: with
    leaves of 4 its hierarchy takes about fifty times longer to build than to cast through.
    """
    leaf = _LEAF
    while leaf < _WIDEST_LEAF and 16 * leaf * rays <= faces:
        leaf *= 2
    return leaf


#: The vertices scaled into [-1, 1] about their box's centre, and the faces' Morton codes in
#: increasing order with that order (:func:`framed`).
Framed = tuple[FloatArray, tuple[IndexArray, IndexArray]]


def framed(points: FloatArray, faces: IndexArray) -> Framed | None:
    """What the rays need before their patches are known: the vertices that the faces use,
    scaled into [-1, 1] about their box's centre (never the origin's: a mesh far from it is
    tested at its own size), and the faces' Morton order (:func:`_morton_order`); None for a
    box of no size."""
    low, high = column_bounds(points, faces)
    centre, half = low / 2 + high / 2, float(np.max(high / 2 - low / 2))  # no overflow
    if not half > 0 or not math.isfinite(half):
        return None
    unit = (points - centre) / half
    announce_compiling()
    with PARALLEL_KERNELS:
        return unit, _morton_order(unit, faces)


def _hierarchy(
    unit: FloatArray,
    faces: IndexArray,
    leaf: int = _LEAF,
    ordered: tuple[IndexArray, IndexArray] | None = None,
) -> tuple[IndexArray, FloatArray, IndexArray, IndexArray, FloatArray]:
    """A bounding-volume hierarchy over the faces: their order along a Morton curve of their
    centroids; per node its box, children (-1 for a leaf) and span of that order; and the
    faces' corners in that order (see :func:`_corners`).

    With leaves of 4 faces, about 140 bytes a face are kept (the corners 72, the order 8, the
    nodes about 0.7 a face at 80 bytes each), and 70 more for a moment while the nodes are
    made (about 150 bytes a face kept, with the vertices). With larger
    leaves (few rays), the order and a few bytes a face for the nodes: the rays read the
    corners from the points.
    """
    announce_compiling()
    with PARALLEL_KERNELS:  # the Morton codes, the corners and the boxes run on every core
        return _built(unit, faces, leaf, ordered)


def _built(
    unit: FloatArray,
    faces: IndexArray,
    leaf: int,
    ordered: tuple[IndexArray, IndexArray] | None = None,
) -> tuple[IndexArray, FloatArray, IndexArray, IndexArray, FloatArray]:
    """:func:`_hierarchy`, with ``PARALLEL_KERNELS`` held; ``ordered``: the Morton order, if
    it was taken already."""
    codes, order = _morton_order(unit, faces) if ordered is None else ordered
    del ordered
    nodes = max(1, 2 * len(faces))  # at least one face per leaf: fewer than 2 m nodes
    # Room for every node there can be, written by _split only as far as it makes them (at
    # the Lucy size, filling 2m rows with -1 first costs about 1 s of page faults).
    children = np.empty((nodes, 2), dtype=np.intp)
    spans = np.empty((nodes, 2), dtype=np.intp)
    used = _split(codes, leaf, children, spans)
    del codes
    children, spans = children[:used].copy(), spans[:used].copy()
    # The corners in the hierarchy's order where many rays read them; where they are few,
    # read from the points as they are needed (72 bytes a face of fresh memory fewer).
    corners = _corners(unit, faces, order) if leaf <= _LEAF else _NO_CORNERS
    boxes = np.empty((used, 6))
    _boxes(unit, faces, order, corners, children, spans, boxes, *workers())
    return order, boxes, children, spans, corners


#: What :func:`_hierarchy` gives for the corners where they are read from the points.
_NO_CORNERS = np.empty((0, 9))


def _morton_order(unit: FloatArray, faces: IndexArray) -> tuple[IndexArray, IndexArray]:
    """The faces' Morton codes (:func:`_morton`) in increasing order, and the order: that of a
    stable sort, by three passes of a compiled radix sort (:func:`_radix_order`; 5 times
    faster than NumPy's sort of code-and-number keys, itself 7 times faster than
    ``argsort(kind="stable")``)."""
    codes = np.empty(len(faces), dtype=np.int64)
    _morton(unit, faces, codes, *workers())
    order = np.empty(len(faces), dtype=np.intp)
    ordered = np.empty(len(faces), dtype=np.int64)
    _radix_order(codes, order, ordered)
    return ordered, order


#: Bits of a Morton code sorted per pass of :func:`_radix_order`: three passes of 10 (1024
#: buckets each, whose write positions stay in the cache).
_DIGIT = 10


@kernel(python=PYTHON_RAYS, nogil=True)
def _radix_order(codes: IndexArray, order: IndexArray, ordered: IndexArray) -> None:
    """``order``: the stable order of ``codes`` (30-bit, non-negative); ``ordered``: the codes
    in that order. A least-significant-digit radix sort, its three counts taken in one pass;
    each pass is stable, so equal codes keep their faces in file order. ``codes`` is used as
    scratch space (it ends up holding the codes in the order of two passes)."""
    count = len(codes)
    buckets = 1 << _DIGIT
    mask = buckets - 1
    starts = np.zeros((3, buckets), dtype=np.int64)
    for face in range(count):
        code = codes[face]
        starts[0, code & mask] += 1
        starts[1, (code >> _DIGIT) & mask] += 1
        starts[2, (code >> (2 * _DIGIT)) & mask] += 1
    for digit in range(3):
        total = 0
        for bucket in range(buckets):
            size = starts[digit, bucket]
            starts[digit, bucket] = total
            total += size
    # Pass 1 reads the codes in file order and writes them and their faces into ordered and
    # order; pass 2 moves them back into codes and a scratch order; pass 3 into the results.
    scratch = np.empty(count, dtype=np.int64)
    for face in range(count):
        code = codes[face]
        bucket = code & mask
        at = starts[0, bucket]
        starts[0, bucket] = at + 1
        ordered[at], order[at] = code, face
    for k in range(count):
        code = ordered[k]
        bucket = (code >> _DIGIT) & mask
        at = starts[1, bucket]
        starts[1, bucket] = at + 1
        codes[at], scratch[at] = code, order[k]
    for k in range(count):
        code = codes[k]
        bucket = (code >> (2 * _DIGIT)) & mask
        at = starts[2, bucket]
        starts[2, bucket] = at + 1
        ordered[at], order[at] = code, scratch[k]


@kernel(parallel=True, python=PYTHON_RAYS)
def _morton(
    unit: FloatArray, faces: IndexArray, codes: IndexArray, counter: IndexArray, workers: int
) -> None:
    """The Morton code of each face's centroid on a 1024**3 grid over [-1, 1]**3."""
    blocks = (len(faces) + BLOCK - 1) // BLOCK
    for _ in prange(workers):  # blocks write disjoint rows: any worker may take any block
        block = claim(counter)
        while block < blocks:
            for face in range(block * BLOCK, min(len(faces), (block + 1) * BLOCK)):
                prefetch_corners(unit, faces, face + AHEAD)  # far apart in a large mesh
                value = 0
                for axis in range(3):
                    total = unit[faces[face, 0], axis] + unit[faces[face, 1], axis]
                    total += unit[faces[face, 2], axis]
                    cell = min(max(int((total / 3 + 1.0) * 512.0), 0), 1023)
                    # The cell's 10 bits spread to every third bit (bit b to bit 3 b).
                    cell = (cell | (cell << 16)) & 0x30000FF
                    cell = (cell | (cell << 8)) & 0x300F00F
                    cell = (cell | (cell << 4)) & 0x30C30C3
                    cell = (cell | (cell << 2)) & 0x9249249
                    value |= cell << axis
                codes[face] = value
            block = claim(counter)


def _corners(unit: FloatArray, faces: IndexArray, order: IndexArray) -> FloatArray:
    """(m, 9): each face's corners A, B, C in the hierarchy's order, so that a leaf's faces
    lie side by side in memory (the rays' time is mostly waiting for memory)."""
    corners = np.empty((len(order), 9))
    counter, threads = workers()
    _gather_corners(unit, faces, order, corners, counter, threads)
    return corners


@kernel(parallel=True, python=PYTHON_RAYS)
def _gather_corners(
    unit: FloatArray, faces: IndexArray, order: IndexArray, corners: FloatArray,
    counter: IndexArray, workers: int,
) -> None:  # fmt: skip
    """``corners[k] = unit[faces[order[k]]].ravel()`` (10 times faster than NumPy's
    two gathers, which also make a temporary of 24 bytes a face)."""
    blocks = (len(order) + BLOCK - 1) // BLOCK
    for _ in prange(workers):
        block = claim(counter)
        while block < blocks:
            for k in range(block * BLOCK, min(len(order), (block + 1) * BLOCK)):
                face = order[k]
                for corner in range(3):
                    vertex = faces[face, corner]
                    for axis in range(3):
                        corners[k, 3 * corner + axis] = unit[vertex, axis]
            block = claim(counter)


@kernel(python=PYTHON_RAYS)
def _split(codes: IndexArray, leaf: int, children: IndexArray, spans: IndexArray) -> int:
    """Split each span where the highest bit that differs in its Morton codes turns (the
    halves of an octree cell; in the middle where the codes are all equal) down to leaves of
    at most ``leaf`` faces; the number of nodes made. Each node made gets its children (-1
    for a leaf) and its span; the rows past them are left as they were."""
    spans[0, 0], spans[0, 1] = 0, len(codes)
    used = 1
    node = 0
    while node < used:  # nodes are made in breadth order: children after their parent
        lo, hi = spans[node, 0], spans[node, 1]
        if hi - lo > leaf:
            differ = codes[lo] ^ codes[hi - 1]
            if differ == 0:
                mid = (lo + hi) // 2
            else:
                bit = 0
                while differ >> (bit + 1):
                    bit += 1
                # The codes of the span share every bit above ``bit``: the first with it set.
                mid = lower_bound(codes, lo, hi, (codes[hi - 1] >> bit) << bit)
            children[node, 0], children[node, 1] = used, used + 1
            spans[used, 0], spans[used, 1] = lo, mid
            spans[used + 1, 0], spans[used + 1, 1] = mid, hi
            used += 2
        else:
            children[node, 0], children[node, 1] = -1, -1  # a leaf
        node += 1
    return used


@kernel(parallel=True, python=PYTHON_RAYS)
def _boxes(
    unit: FloatArray, faces: IndexArray, order: IndexArray, corners: FloatArray,
    children: IndexArray, spans: IndexArray, boxes: FloatArray, counter: IndexArray,
    workers: int,
) -> None:  # fmt: skip
    """Each node's box, a little larger than its faces' (by 2**-26, more than an unsure hit
    can lie outside a face: 2 ``_UNSURE_BAND`` times its longest edge, at most 4): the
    leaves' on every core, then the others from the leaves up. The corners are read from
    ``corners`` (in the hierarchy's order), or from ``unit`` where it is empty."""
    pad = 2.0**-26
    gathered = len(corners) > 0
    nodes = len(children)
    blocks = (nodes + BLOCK - 1) // BLOCK
    for _ in prange(workers):  # each leaf writes its own row
        block = claim(counter)
        while block < blocks:
            for node in range(block * BLOCK, min(nodes, (block + 1) * BLOCK)):
                if children[node, 0] >= 0:
                    continue
                for axis in range(3):
                    boxes[node, axis], boxes[node, axis + 3] = np.inf, -np.inf
                for k in range(spans[node, 0], spans[node, 1]):
                    if not gathered and k + 2 * AHEAD < len(order):  # their faces, then points
                        prefetch(faces, order[k + 2 * AHEAD])
                    if not gathered and k + AHEAD < len(order):
                        prefetch_corners(unit, faces, order[k + AHEAD])
                    for corner in range(3):
                        for axis in range(3):
                            value = (
                                corners[k, 3 * corner + axis]
                                if gathered
                                else unit[faces[order[k], corner], axis]
                            )
                            boxes[node, axis] = min(boxes[node, axis], value - pad)
                            boxes[node, axis + 3] = max(boxes[node, axis + 3], value + pad)
            block = claim(counter)
    for node in range(nodes - 1, -1, -1):
        left, right = children[node, 0], children[node, 1]
        if left >= 0:
            for axis in range(3):
                boxes[node, axis] = min(boxes[left, axis], boxes[right, axis])
                boxes[node, axis + 3] = max(boxes[left, axis + 3], boxes[right, axis + 3])


@kernel(python=PYTHON_RAYS)
def _entry(
    boxes: FloatArray, node: int, origin: FloatArray, inverse: FloatArray, t_min: float
) -> float:
    """Where the ray enters the node's box (``inf`` if it misses it), at ``t_min`` or later.

    ``inverse`` holds 1 / direction, infinite where the direction is zero; then the slab test
    is made on the origin alone (0 * inf would be NaN).
    """
    near, far = t_min, np.inf
    for axis in range(3):
        o, inv = origin[axis], inverse[axis]
        lo, hi = boxes[node, axis], boxes[node, axis + 3]
        if math.isinf(inv):
            if o < lo or o > hi:
                return np.inf
            continue
        t1, t2 = (lo - o) * inv, (hi - o) * inv
        if t1 > t2:
            t1, t2 = t2, t1
        near, far = max(near, t1), min(far, t2)
    return near if near <= far else np.inf


@kernel(python=PYTHON_RAYS)
def _blocked(
    unit: FloatArray,
    faces: IndexArray,
    corners: FloatArray,
    order: IndexArray,
    boxes: FloatArray,
    children: IndexArray,
    spans: IndexArray,
    own: int,
    origin: FloatArray,
    direction: FloatArray,
    t_min: float,
    stack: IndexArray,
) -> int:
    """Whether the ray hits a face other than ``own`` farther than ``t_min``: ``_CLEAR`` (no),
    ``_HIT`` (yes) or ``_UNSURE`` (only within ``_UNSURE_BAND`` of a face's edge, of its plane
    or of ``t_min``, where rounding may decide it either way). Depth first, the nearer child
    first, so that a hit is found early and ends the search."""
    ox, oy, oz = origin[0], origin[1], origin[2]
    dx, dy, dz = direction[0], direction[1], direction[2]
    inverse = np.empty(3)
    for axis in range(3):
        inverse[axis] = 1.0 / direction[axis] if direction[axis] != 0.0 else np.inf
    if math.isinf(_entry(boxes, 0, origin, inverse, t_min)):
        return _CLEAR
    unsure = False
    gathered = len(corners) > 0
    band = _UNSURE_BAND
    top = 0
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        left, right = children[node, 0], children[node, 1]
        if left >= 0:
            near, far = (
                _entry(boxes, left, origin, inverse, t_min),
                _entry(boxes, right, origin, inverse, t_min),
            )
            if near > far:
                left, right, near, far = right, left, far, near
            if not math.isinf(far):
                top += 1
                stack[top] = right
            if not math.isinf(near):
                top += 1
                stack[top] = left
            continue
        for k in range(spans[node, 0], spans[node, 1]):
            if order[k] == own:
                continue
            if gathered:
                ax, ay, az = corners[k, 0], corners[k, 1], corners[k, 2]
                bx, by, bz = corners[k, 3], corners[k, 4], corners[k, 5]
                cx, cy, cz = corners[k, 6], corners[k, 7], corners[k, 8]
            else:  # the same values, from the points
                a, b, c = faces[order[k], 0], faces[order[k], 1], faces[order[k], 2]
                ax, ay, az = unit[a, 0], unit[a, 1], unit[a, 2]
                bx, by, bz = unit[b, 0], unit[b, 1], unit[b, 2]
                cx, cy, cz = unit[c, 0], unit[c, 1], unit[c, 2]
            e1x, e1y, e1z = bx - ax, by - ay, bz - az
            e2x, e2y, e2z = cx - ax, cy - ay, cz - az
            px, py, pz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
            det = e1x * px + e1y * py + e1z * pz
            # det = -d . (e1 x e2): the sine of the angle between the ray and the face's plane,
            # times twice the face's area.
            nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
            twice = math.sqrt(nx * nx + ny * ny + nz * nz)
            if twice == 0.0:
                continue
            if abs(det) <= band * twice:  # along the face's plane: it may just touch it
                sx, sy, sz = ox - ax, oy - ay, oz - az
                if abs(sx * nx + sy * ny + sz * nz) <= band * twice * 4.0:
                    unsure = True
                continue
            inverse_det = 1.0 / det
            sx, sy, sz = ox - ax, oy - ay, oz - az
            u = (sx * px + sy * py + sz * pz) * inverse_det
            if u < -band or u > 1.0 + band:
                continue
            qx, qy, qz = sy * e1z - sz * e1y, sz * e1x - sx * e1z, sx * e1y - sy * e1x
            v = (dx * qx + dy * qy + dz * qz) * inverse_det
            if v < -band or u + v > 1.0 + band:
                continue
            t = (e2x * qx + e2y * qy + e2z * qz) * inverse_det
            if t < t_min * 0.5:
                continue
            if u < band or v < band or u + v > 1.0 - band or t < t_min * 2.0:
                unsure = True  # on an edge or a corner, or near t_min: rounding decides
                continue
            return _HIT
    return _UNSURE if unsure else _CLEAR


@kernel(parallel=True, python=PYTHON_RAYS)
def _cast(
    unit: FloatArray,
    faces: IndexArray,
    corners: FloatArray,
    order: IndexArray,
    boxes: FloatArray,
    children: IndexArray,
    spans: IndexArray,
    samples: IndexArray,
    pattern: FloatArray,
    t_min: float,
    escaped: FloatArray,
    unsure: FloatArray,
    weights: FloatArray,
    against: BoolArray,
) -> None:
    """For each sample face: the share of its rays that surely escape, and of those unsure,
    on each side of its plane (+ and - of the normal of its vertices in increasing order), its
    area, and whether it is wound against that order."""
    for s in prange(len(samples)):  # each sample writes its own rows: the same bits on any cores
        stack = np.empty(2 * 64 + 2, dtype=np.intp)
        origin, direction = np.empty(3), np.empty(3)
        face = samples[s]
        i, j, k = faces[face, 0], faces[face, 1], faces[face, 2]
        # Sort the vertex numbers; each swap reverses the winding.
        odd = False
        if i > j:
            i, j, odd = j, i, not odd
        if j > k:
            j, k, odd = k, j, not odd
        if i > j:
            i, j, odd = j, i, not odd
        against[s] = odd
        ux, uy, uz = unit[j, 0] - unit[i, 0], unit[j, 1] - unit[i, 1], unit[j, 2] - unit[i, 2]
        vx, vy, vz = unit[k, 0] - unit[i, 0], unit[k, 1] - unit[i, 1], unit[k, 2] - unit[i, 2]
        mx, my, mz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        twice = math.sqrt(mx * mx + my * my + mz * mz)
        along = math.sqrt(ux * ux + uy * uy + uz * uz)
        if twice == 0.0 or along == 0.0:
            continue
        weights[s] = twice / 2
        mx, my, mz = mx / twice, my / twice, mz / twice
        ux, uy, uz = ux / along, uy / along, uz / along
        wx, wy, wz = my * uz - mz * uy, mz * ux - mx * uz, mx * uy - my * ux
        for axis in range(3):
            origin[axis] = (unit[i, axis] + unit[j, axis] + unit[k, axis]) / 3
        for side in range(2):
            sign = 1.0 if side == 0 else -1.0
            free, maybe = 0, 0
            for r in range(len(pattern)):
                a, b, c = pattern[r, 0], pattern[r, 1], sign * pattern[r, 2]
                direction[0] = a * ux + b * wx + c * mx
                direction[1] = a * uy + b * wy + c * my
                direction[2] = a * uz + b * wz + c * mz
                met = _blocked(
                    unit, faces, corners, order, boxes, children, spans, face, origin,
                    direction, t_min, stack,
                )  # fmt: skip
                if met == _CLEAR:
                    free += 1
                elif met == _UNSURE:
                    maybe += 1
            escaped[s, side] = free / len(pattern)
            unsure[s, side] = maybe / len(pattern)
