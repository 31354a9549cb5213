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
  hierarchy (faces sorted along a Morton curve, split in halves; any hit ends the search),
  built and searched by the compiled core (``_core.cast_rays``, ``cpp/visibility.cpp``).
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

import mesh_normal._core as _core
from mesh_normal.mesh.bounds import column_bounds
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


def _directions() -> FloatArray:
    """(DIRECTIONS, 3): a Fibonacci spiral over the band of the hemisphere above the face,
    as (along the first edge, across it, along the normal), equal solid angle each."""
    i = np.arange(DIRECTIONS) + 0.5
    up = 1.0 - i / DIRECTIONS * (1.0 - ELEVATION_SINE)
    turn = i * math.pi * (3.0 - math.sqrt(5.0))
    around = np.sqrt(1.0 - up * up)
    return np.column_stack([around * np.cos(turn), around * np.sin(turn), up])


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
        ``mesh_normal.mesh.orientation.HeadStart``); else it is taken here.

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
    unit, (codes, order) = frame
    del frame
    most = RAYS // (2 * DIRECTIONS * FEWEST)
    if len(chosen) > most:
        chosen = np.sort(chosen[np.argsort(-area[chosen], kind="stable")[:most]])
    per = int(np.clip(RAYS // (2 * DIRECTIONS * len(chosen)), FEWEST, SAMPLES))
    samples, owner = _samples(group, chosen, per)
    leaf = leaf_size(len(faces), 2 * DIRECTIONS * len(samples))
    escaped, unsure, weights, against = _core.cast_rays(
        unit, faces, codes, order, leaf, leaf <= _LEAF, samples, _directions(), T_MIN
    )
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

    One pass over the faces picks them (``_core.pick_samples``); gathering each patch's
    members with a stable sort first takes about half a second at the Lucy size for a patch of
    every face.
    """
    slot = np.full(int(group.max(initial=0)) + 1, -1, dtype=np.intp)
    slot[chosen] = np.arange(len(chosen))
    counts = np.bincount(group, minlength=len(slot))[chosen]
    take = np.minimum(counts, per)
    offsets = np.cumsum(take) - take
    samples = np.empty(int(take.sum()), dtype=np.intp)
    _core.pick_samples(group, slot, counts, take, offsets, samples)
    return samples, np.repeat(np.arange(len(chosen)), take)


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
    tested at its own size), and the faces' Morton order (``_core.face_morton_order``: the
    Morton codes of their centroids on a 1024**3 grid over [-1, 1]**3, in increasing order,
    and that order, equal codes in file order); None for a box of no size."""
    low, high = column_bounds(points, faces)
    centre, half = low / 2 + high / 2, float(np.max(high / 2 - low / 2))  # no overflow
    if not half > 0 or not math.isfinite(half):
        return None
    unit = (points - centre) / half
    return unit, _core.face_morton_order(unit, faces)
