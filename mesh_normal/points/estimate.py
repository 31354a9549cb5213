"""Normals of a point cloud: the flattest direction of each point's neighbourhood.

Points at exactly the same place are estimated once (:func:`coincident_groups`) and each gets
the normal of its place: a k-d tree cannot split a pile of equal points, so its queries would
take time quadratic in the pile's size, and copies of a point say nothing of the surface.
Neighbourhoods are of places: each place's neighbours (its k nearest, those within a radius,
or at most k within a radius, itself included) come from a k-d tree built and queried with the
places in Morton (Z-curve) order, so that neighbouring queries touch neighbouring memory; the
results go back to input order. The k nearest come from the compiled core's own tree
(``mesh_normal._core.PointTree``, ``cpp/nearest.cpp``; nearest first, equal distances by
index), those within a radius from scipy's ``cKDTree``. Coordinates are first moved so that
the bounding box is centred on the origin and scaled by a power of two (exact) into [-1, 1]:
the normals do not depend on where the cloud sits or its unit. The compiled kernel
(``mesh_normal._core.neighbourhood_normals``, ``cpp/points.cpp``) centres each neighbourhood on
its mean, takes the covariance in float64 and solves it by cyclic Jacobi rotations (accurate
for flat, linear and isotropic neighbourhoods alike); the normal is the eigenvector of the
smallest eigenvalue, the curvature (surface variation) that eigenvalue over their sum. Rows
are independent, so the results are the same bits for any number of threads.

Where the neighbourhood does not determine a plane there is no normal (a zero row and a status
that says why; never NaN, never a made-up direction). A place alone in its neighbourhood, or
with one other, that holds three points or more with its copies is ``duplicates`` or
``collinear``, as its points are. "To rounding" below is the variance that rounding the
coordinates alone could give: ``(POINT_ROUNDING_FACTOR * EPSILON * max |x|)**2``. Non-finite
points get ``not_finite`` and are no one's neighbours. Then the normals are oriented
(:mod:`mesh_normal.points.orient`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import ArrayLike, NDArray

import mesh_normal._core as _core
from mesh_normal.mesh.checks import HeldCloud, held_points
from mesh_normal.points.orient import (
    ORIENT_MODES,
    ComponentOrientation,
    OrientMode,
    Signs,
    along_tree,
    towards,
)
from mesh_normal.tolerances import (
    EPSILON,
    ORIENT_MAX_ANGLE,
    ORIENT_NEIGHBOURS,
    POINT_GAP_RATIO,
    POINT_LINE_RATIO,
    POINT_ROUNDING_FACTOR,
)
from mesh_normal.types import BoolArray, FloatArray, IndexArray

#: Points queried at once: bounds the memory of the neighbour lists (2**17 points, k = 30:
#: 31 MB of indices and as much of distances).
QUERY_CHUNK = 2**17

#: The default's scales: with neither k nor radius, each point is fitted over its nearest 12,
#: 24, 48 and 96 (itself included), from one query of the largest.
ADAPTIVE_SCALES = (12, 24, 48, 96)

#: A larger scale is taken while its normal stays within this many times the two fits' spreads
#: from noise of every smaller scale's (Lepski's rule; measured on benchmarks.points_accuracy).
ADAPTIVE_AGREEMENT = 3.0

#: Smaller scales whose smallest eigenvalue is over this fraction of the middle one are not
#: held against a larger scale: noise, not the surface, shapes them.
ADAPTIVE_PLANAR = 0.1

#: Wider scales for flat noisy places, without a larger query: the largest scale's moments
#: merged with those of the ADAPTIVE_WIDE_NEIGHBOURS nearest, once and twice, reach about
#: these many points (the area of the largest scale's radius plus one and two of the
#: neighbours'), counting as ADAPTIVE_WIDE_EFFECTIVE against noise.
ADAPTIVE_WIDE = (240, 440)
ADAPTIVE_WIDE_NEIGHBOURS = 32
ADAPTIVE_WIDE_EFFECTIVE = (160.0, 280.0)

#: A wider scale is taken only where its residual is at most this many times the scale's
#: before: noise keeps the residual level (a curve raises it as the square of the radius).
ADAPTIVE_WIDE_GROWTH = 1.2

#: Only a point whose largest query scale is at most this many times as rough (in residual)
#: as its smallest is widened: noise is as rough at every scale (a few points' residual
#: underestimates it), a thin part's two sides or a curve are not.
ADAPTIVE_WIDE_ROUGHNESS = 5.0

#: Near a sharp edge: among the planes of a point's nearest ADAPTIVE_SHARP_NEIGHBOURS' fits,
#: the one through the point that holds the most of them (within ADAPTIVE_SHARP_FACTOR times
#: the lower quartile of their residuals) is the side it lies on; where it leaves out more than
#: ADAPTIVE_SHARP_KEEP of them, the normal is refitted to it, and taken where the point's own
#: fit is over ADAPTIVE_SHARP_BLEND times less flat (a blend of two sides; on a curved surface
#: the side's band is no flatter) and the refit turns it by a sine over ADAPTIVE_SHARP_TURN
#: (less is what noise turns a normal by). Fewer where the largest scale is smaller; a cloud
#: too small for ADAPTIVE_SHARP_LEAST neighbours a point (about 1,000 points) is not searched
#: for edges: its neighbourhoods are too coarse to tell an edge from a curve. A point whose
#: chosen scale reaches past an edge its nearest 32 do not is found among its nearest 64.
ADAPTIVE_SHARP_NEIGHBOURS = 64
ADAPTIVE_SHARP_LEAST = 32
ADAPTIVE_SHARP_FACTOR = 3.0
ADAPTIVE_SHARP_KEEP = 0.9
ADAPTIVE_SHARP_BLEND = 1.5
ADAPTIVE_SHARP_TURN = 0.05


class PointStatus(IntEnum):
    """Why a point has its normal, or has none (``PointNormals.status``, uint8).

    Attributes
    ----------
    ok : 0
        A unit normal, oriented as asked.
    not_finite : 1
        A coordinate is NaN or infinite.
    too_few_neighbours : 2
        Fewer than three points in its neighbourhood, itself included.
    duplicates : 3
        Its neighbourhood's points coincide (to rounding).
    collinear : 4
        They lie on a line (to rounding, or 2**-20 of their length).
    ambiguous : 5
        Two directions are equally flat (e.g. a symmetric corner).
    unoriented : 6
        A unit normal, but its side could not be decided; see ``components``.
    sharp : 7
        A unit normal, oriented as asked, near a sharp edge or corner: the normal of the flat
        side the point lies on, not a blend of both (the default neighbourhood only).
    """

    ok = 0  #: a unit normal, oriented as asked
    not_finite = 1  #: a coordinate is NaN or infinite
    too_few_neighbours = 2  #: fewer than three points in its neighbourhood, itself included
    duplicates = 3  #: its neighbourhood's points coincide (to rounding)
    collinear = 4  #: they lie on a line (to rounding, or 2**-20 of their length)
    ambiguous = 5  #: two directions are equally flat (e.g. a symmetric corner)
    unoriented = 6  #: a unit normal, but its side could not be decided; see ``components``
    sharp = 7  #: a unit normal near a sharp edge: the flat side's the point lies on


@dataclass(frozen=True, slots=True, eq=False)
class PointNormals:
    """One normal for each of ``n`` points, in input order.

    Attributes
    ----------
    normals : (n, 3) float64
        Unit normals where ``valid``, zero rows elsewhere.
    curvature : (n,) float64
        λ0 / (λ0 + λ1 + λ2) of the neighbourhood's covariance, in [0, 1/3]; 0 where its points
        are fewer than three or coincide.
    neighbours : (n,) int
        How many places the neighbourhood held (the point's own included; coincident points
        are one place).
    valid : (n,) bool
        The point has a normal: status ``ok``, ``sharp`` or ``unoriented``.
    status : (n,) uint8
        A :class:`PointStatus` per point.
    orient : str
        The orientation that was asked for.
    components : tuple of ComponentOrientation
        For ``"mst"`` and ``"riemannian"`` one per connected part of the neighbour graph that
        has normals, largest first; for the per-point modes one for the whole cloud; none for
        ``"none"``.
    """

    normals: FloatArray
    curvature: FloatArray
    neighbours: IndexArray
    valid: BoolArray
    status: NDArray[np.uint8]
    orient: OrientMode
    components: tuple[ComponentOrientation, ...]

    @property
    def flipped(self) -> int:
        """Normals turned by the orientation, in all components."""
        return sum(part.flipped for part in self.components)

    @property
    def unoriented(self) -> int:
        """Normals whose side could not be decided, in all components."""
        return sum(part.unoriented for part in self.components)

    def counts(self) -> dict[str, int]:
        """How many points have each status, by name (every status, zeros included)."""
        found = np.bincount(self.status, minlength=len(PointStatus))
        return {status.name: int(found[status]) for status in PointStatus}


@dataclass(frozen=True, slots=True, eq=False)
class _Frame:
    """The finite points' places (coincident points are one), centred and scaled, in Morton
    order, and where they came from."""

    points: FloatArray  # (m, 3), C-contiguous
    origin: IndexArray  # (m,) input index of each row's first point
    weight: IndexArray  # (m,) how many input points sit at each row's place
    finite: IndexArray  # (f,) input index of each finite point
    place: IndexArray  # (f,) the row of each finite point's place
    centre: FloatArray  # (3,) subtracted first
    scale: float  # then divided by this power of two
    tiny: float  # the variance of rounding alone, in these units


def point_normals(
    points: ArrayLike | HeldCloud,
    *,
    k: int | None = None,
    radius: float | None = None,
    orient: OrientMode = "mst",
    viewpoint: ArrayLike | None = None,
    direction: ArrayLike | None = None,
    stored: ArrayLike | None = None,
    max_angle: float = ORIENT_MAX_ANGLE,
    progress: Callable[[int, int], None] | None = None,
) -> PointNormals:
    """Return the normal, curvature and status of every point of a cloud.

    Parameters
    ----------
    points : (n, 3) float, or a cloud
        Coordinates; NaN or infinite rows are allowed and get ``not_finite``. Or a cloud as
        people hold it: what :func:`~mesh_normal.points.read_points` returns, an Open3D
        ``PointCloud``, a ``trimesh.PointCloud``, a PyVista ``PolyData``, or a mesh (its
        vertices); with ``orient="file"`` and no ``stored``, its own normals are taken.
    k : int or None
        The neighbourhood's size, the point itself included (at least 3); with ``radius``, at
        most this many within it; None with a radius: all within it. With neither (the
        default), each point's scale is chosen from the data: its nearest 12, 24, 48 or 96, or
        about 240 or 440 from merged neighbourhoods, the largest whose normal a smaller one's
        agrees with to within noise (a curved or noise-free place keeps a small one, a flat
        noisy one a large one; ``neighbours`` says which), and points near a sharp edge take
        the normal of the side they lie on (status ``sharp``).
    radius : float or None
        Only neighbours within this distance, in the points' unit.
    orient : {"mst", "riemannian", "viewpoint", "direction", "file", "none"}
        How to choose each normal's side (see :mod:`mesh_normal.points.orient`). ``"none"``
        leaves the canonical sign: each normal's largest component positive.
    viewpoint : (3,) float
        With ``orient="viewpoint"``: the sensor's position; normals face it.
    direction : (3,) float
        With ``orient="direction"``: normals make an acute angle with it (e.g. (0, 0, 1)).
    stored : (n, 3) float
        With ``orient="file"``: normals read with the points (by default a cloud's own);
        each normal is turned to agree with its stored one (zero or non-finite rows leave it
        unoriented).
    max_angle : float
        ``"mst"`` and ``"riemannian"``: the largest angle, in degrees, between neighbours'
        normal lines that a sign is carried across.
    progress : callable, optional
        Called as ``progress(done, total)`` after each chunk of the estimation (``total``: the
        finite points' distinct places); the orientation follows the last call.

    Returns
    -------
    PointNormals
        Full-length arrays in input order, and the orientation's summary.
    """
    held, held_normals = held_points(points)
    cloud = _checked_points(held)
    if orient == "file" and stored is None:
        stored = held_normals  # an Open3D cloud's or read_points' own normals
    k, radius = _checked_neighbourhood(k, radius)
    references = _checked_orientation(len(cloud), orient, viewpoint, direction, stored, max_angle)
    n = len(cloud)
    normals, curvature = np.zeros((n, 3)), np.zeros(n)
    neighbours = np.zeros(n, dtype=np.intp)
    status = np.full(n, PointStatus.not_finite, dtype=np.uint8)
    frame = _frame(cloud)
    m = len(frame.points)
    if m == 0:
        return PointNormals(normals, curvature, neighbours, status == 0, status, orient, ())
    local_normals, local_curvature, used, codes, graph = _estimate(frame, k, radius, progress)
    has_normal = (codes == PointStatus.ok) | (codes == PointStatus.sharp)
    signs = _signs(frame, local_normals, has_normal, graph, orient, references, max_angle)
    local_normals[signs.flip] *= -1.0
    codes[signs.unoriented] = PointStatus.unoriented
    finite, place = frame.finite, frame.place
    normals[finite], curvature[finite] = local_normals[place], local_curvature[place]
    neighbours[finite], status[finite] = used[place], codes[place]
    origin = frame.origin
    valid = np.isin(status, (PointStatus.ok, PointStatus.unoriented, PointStatus.sharp))
    components = tuple(
        ComponentOrientation(
            part.points,
            part.flipped,
            part.unoriented,
            part.reason,
            int(origin[part.seed]) if part.seed >= 0 else -1,
        )
        for part in signs.components
    )
    return PointNormals(normals, curvature, neighbours, valid, status, orient, components)


# --- inputs -------------------------------------------------------------------------------


def _checked_points(points: ArrayLike) -> FloatArray:
    try:
        cloud = np.asarray(points)
    except (TypeError, ValueError) as error:
        raise ValueError(f"points must be an (n, 3) array of numbers: {error}") from None
    if cloud.dtype.kind not in "biuf":
        raise ValueError(f"points must be real numbers, not {cloud.dtype}")
    if cloud.ndim != 2 or cloud.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), not {cloud.shape}")
    return np.ascontiguousarray(cloud, dtype=np.float64)


def _checked_neighbourhood(k: int | None, radius: float | None) -> tuple[int | None, float | None]:
    if k is not None:
        if isinstance(k, bool) or not isinstance(k, int | np.integer):
            raise ValueError(f"k must be a whole number, not {k!r}")
        if k < 3:
            raise ValueError(f"k must be at least 3 (the point and two neighbours), not {k}")
    if radius is not None:
        radius = float(radius)
        if not (math.isfinite(radius) and radius > 0):
            raise ValueError(f"radius must be a positive finite number, not {radius}")
    return (None if k is None else int(k)), radius


def _checked_vector(value: ArrayLike | None, name: str, orient: str) -> FloatArray:
    if value is None:
        raise ValueError(f'orient="{orient}" needs {name}')
    vector = np.asarray(value, dtype=np.float64)
    if vector.shape != (3,) or not np.isfinite(vector).all():
        raise ValueError(f"{name} must be three finite numbers, not {value!r}")
    return vector


def _checked_orientation(
    n: int,
    orient: str,
    viewpoint: ArrayLike | None,
    direction: ArrayLike | None,
    stored: ArrayLike | None,
    max_angle: float,
) -> FloatArray | None:
    """The reference that ``orient`` needs, checked; and nothing it does not use."""
    if orient not in ORIENT_MODES:
        raise ValueError(f"orient must be one of {', '.join(ORIENT_MODES)}, not {orient!r}")
    given = {"viewpoint": viewpoint, "direction": direction, "file": stored}
    for mode, value in given.items():
        if value is not None and mode != orient:
            name = "stored" if mode == "file" else mode
            raise ValueError(f'{name} is only used with orient="{mode}"')
    if not (isinstance(max_angle, int | float) and 0 < max_angle <= 90):
        raise ValueError(f"max_angle must be in degrees, over 0 and at most 90, not {max_angle!r}")
    if orient == "viewpoint":
        return _checked_vector(viewpoint, "viewpoint", orient)
    if orient == "direction":
        vector = _checked_vector(direction, "direction", orient)
        if not vector.any():
            raise ValueError("direction must not be zero")
        return vector
    if orient == "file":
        if stored is None:
            raise ValueError('orient="file" needs stored normals')
        normals = np.asarray(stored)
        if normals.dtype.kind not in "biuf" or normals.shape != (n, 3):
            raise ValueError(f"stored normals must be ({n}, 3) numbers, not {normals.shape}")
        return normals.astype(np.float64)
    return None


# --- the frame and the neighbourhoods -----------------------------------------------------------


def coincident_groups(points: FloatArray) -> tuple[IndexArray, IndexArray]:
    """The distinct rows of ``points`` (n, 3): the index of each one's first occurrence,
    ascending, and for each row the position of its own in that list. 0.0 and -0.0 are equal.

    Sorted by a hash of the rows' bits, so that equal rows fall together in O(n log n); where
    two different rows share a hash, by the rows themselves.
    """
    n = len(points)
    bits = np.ascontiguousarray(points + 0.0).view(np.uint64).reshape(n, 3)
    key = bits[:, 0] * np.uint64(0x9E3779B97F4A7C15)
    key ^= bits[:, 1] * np.uint64(0xC2B2AE3D27D4EB4F)
    key ^= (bits[:, 2] * np.uint64(0x165667B19E3779F9)) >> np.uint64(7)
    order = np.argsort(key, kind="stable")
    rows = bits[order]
    same = np.all(rows[1:] == rows[:-1], axis=1)
    if np.any(~same & (key[order[1:]] == key[order[:-1]])):
        order = np.lexsort(bits.T[::-1])  # stable, as argsort's was
        same = np.all(bits[order[1:]] == bits[order[:-1]], axis=1)
    if not same.any():
        return np.arange(n), np.arange(n)
    starts = np.r_[True, ~same]
    first = order[starts]  # a stable sort: each run's smallest index comes first
    by_first = np.argsort(first)
    rank = np.empty(len(first), dtype=np.intp)
    rank[by_first] = np.arange(len(first))
    group = np.empty(n, dtype=np.intp)
    group[order] = rank[np.cumsum(starts) - 1]
    return first[by_first], group


def _frame(cloud: FloatArray) -> _Frame:
    finite = np.flatnonzero(np.isfinite(cloud).all(axis=1))
    if len(finite) == 0:
        return _Frame(cloud[finite], finite, finite, finite, finite, np.zeros(3), 1.0, 0.0)
    first, group = coincident_groups(cloud[finite])
    points = cloud[finite[first]]
    weight = np.bincount(group, minlength=len(first))
    low, high = points.min(axis=0), points.max(axis=0)
    centre = low / 2 + high / 2  # no overflow near the largest double
    half = float((high / 2 - low / 2).max())
    scale = math.ldexp(1.0, math.frexp(half)[1]) if half > 0 else 1.0  # 2**e >= half
    rounding = EPSILON * float(np.abs(points).max())
    local = (points - centre) / scale
    order = _morton_order(local)
    tiny = (POINT_ROUNDING_FACTOR * rounding / scale) ** 2
    row = np.empty(len(order), dtype=np.intp)
    row[order] = np.arange(len(order))
    return _Frame(
        np.ascontiguousarray(local[order]),
        finite[first[order]],
        weight[order],
        finite,
        row[group],
        centre,
        scale,
        tiny,
    )


def _morton_order(local: FloatArray) -> IndexArray:
    """The order of the points along a Z curve through [-1, 1]**3, 21 bits an axis."""
    cells = np.clip(((local + 1.0) * 2.0**20).astype(np.int64), 0, 2**21 - 1).astype(np.uint64)
    code = np.zeros(len(local), dtype=np.uint64)
    for axis in range(3):
        code |= _spread(cells[:, axis]) << np.uint64(axis)
    return np.argsort(code, kind="stable")


def _spread(bits: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """Bit i of a 21-bit number moved to bit 3i."""
    x = bits & np.uint64(0x1FFFFF)
    for shift, mask in (
        (32, 0x1F00000000FFFF),
        (16, 0x1F0000FF0000FF),
        (8, 0x100F00F00F00F00F),
        (4, 0x10C30C30C30C30C3),
        (2, 0x1249249249249249),
    ):
        x = (x | (x << np.uint64(shift))) & np.uint64(mask)
    return x


def _estimate(
    frame: _Frame,
    k: int | None,
    radius: float | None,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[FloatArray, FloatArray, IndexArray, NDArray[np.uint8], NDArray[np.int32]]:
    """Normals, curvature, counts, codes and the orientation graph, in the frame's order."""
    m = len(frame.points)
    if k is None and radius is None:
        return _adaptive(frame, progress)
    normals, curvature = np.empty((m, 3)), np.empty(m)
    used, codes = np.empty(m, dtype=np.intp), np.empty(m, dtype=np.intp)
    g = min(ORIENT_NEIGHBOURS, m if k is None else min(k, m))
    graph = np.full((m, g), -1, dtype=np.int32)
    bound = math.inf if radius is None else np.nextafter(radius / frame.scale, math.inf)
    for start, indptr, indices, nearest in _neighbourhoods(frame.points, k, bound, g):
        stop = start + len(indptr) - 1
        _core.neighbourhood_normals(
            frame.points,
            indptr,
            indices,
            frame.tiny,
            POINT_LINE_RATIO,
            POINT_GAP_RATIO,
            normals[start:stop],
            curvature[start:stop],
            used[start:stop],
            codes[start:stop],
        )
        graph[start:stop] = np.where(nearest < m, nearest, -1)
        if progress is not None:
            progress(stop, m)
    _degenerate_piles(frame.weight, used, codes, graph)
    return normals, curvature, used, codes.astype(np.uint8), graph


def _adaptive(
    frame: _Frame, progress: Callable[[int, int], None] | None
) -> tuple[FloatArray, FloatArray, IndexArray, NDArray[np.uint8], NDArray[np.int32]]:
    """The default: each point's scale chosen among ADAPTIVE_SCALES and, where the largest
    holds, ADAPTIVE_WIDE; then the sharp pass."""
    m = len(frame.points)
    # A neighbourhood of over a 32nd of the cloud is a good part of its shape, not a patch.
    largest = min(ADAPTIVE_SCALES[-1], max(ADAPTIVE_SCALES[0], m // 32), m)
    scales = np.array([s for s in ADAPTIVE_SCALES if s < largest] + [largest], dtype=np.intp)
    fitted, curvature, residual, spread = np.empty((m, 3)), np.empty(m), np.empty(m), np.empty(m)
    planes, centres, moments = np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 10))
    roughness = np.empty(m)
    used, codes = np.empty(m, dtype=np.intp), np.empty(m, dtype=np.intp)
    g = min(ORIENT_NEIGHBOURS, largest)
    graph = np.full((m, g), -1, dtype=np.int32)
    # The sharp pass's neighbourhood stays within a 64th of the cloud: wider, a curve's
    # neighbourhood holds bands that look like sides (62 neighbours mark false edges on a
    # 2,000-point sphere).
    sides = min(ADAPTIVE_SHARP_NEIGHBOURS, largest, max(ADAPTIVE_SHARP_LEAST, m // 64))
    candidates = np.full((m, sides), -1, dtype=np.int32)
    beside = min(ADAPTIVE_WIDE_NEIGHBOURS, largest)  # whose moments a widened scale merges
    chunk = max(1, QUERY_CHUNK * 30 // largest)
    tree = _core.PointTree(frame.points)
    lists = np.empty((min(chunk, m), largest), dtype=np.intp)
    for start in range(0, m, chunk):
        stop = min(m, start + chunk)
        nearest = lists[: stop - start]
        tree.nearest(start, stop, largest, nearest)
        _core.multiscale_normals(
            frame.points,
            nearest,
            scales,
            frame.tiny,
            POINT_LINE_RATIO,
            POINT_GAP_RATIO,
            ADAPTIVE_AGREEMENT,
            ADAPTIVE_PLANAR,
            fitted[start:stop],
            curvature[start:stop],
            used[start:stop],
            codes[start:stop],
            residual[start:stop],
            spread[start:stop],
            planes[start:stop],
            centres[start:stop],
            roughness[start:stop],
            moments[start:stop],
        )
        graph[start:stop] = nearest[:, :g]
        candidates[start:stop] = nearest[:, : candidates.shape[1]]
        if progress is not None:
            progress(stop, m)
    _degenerate_piles(frame.weight, used, codes, graph)
    if largest == ADAPTIVE_SCALES[-1]:
        grow = (used == largest) & (codes == PointStatus.ok)
        # Noise is as rough at every scale; a thin part's two sides, or a curve, make the
        # largest scale much rougher than the smallest.
        grow &= residual <= ADAPTIVE_WIDE_ROUGHNESS * roughness
        neighbours = np.ascontiguousarray(candidates[:, :beside])
        _widened(frame, moments, neighbours, grow, fitted, curvature, residual, spread, used)
    normals = fitted.copy()
    sharp = np.zeros(m, dtype=bool)
    if candidates.shape[1] < ADAPTIVE_SHARP_LEAST:  # a small cloud: no edges to tell
        return normals, curvature, used, codes.astype(np.uint8), graph
    _core.sharp_normals(
        frame.points,
        candidates,
        fitted,
        residual,
        spread,
        codes,
        planes,
        centres,
        frame.tiny,
        POINT_LINE_RATIO,
        POINT_GAP_RATIO,
        ADAPTIVE_SHARP_FACTOR,
        ADAPTIVE_SHARP_KEEP,
        ADAPTIVE_SHARP_BLEND,
        ADAPTIVE_SHARP_TURN,
        math.sqrt(frame.tiny),
        normals,
        sharp,
    )
    codes[sharp] = PointStatus.sharp
    return normals, curvature, used, codes.astype(np.uint8), graph


def _widened(
    frame: _Frame,
    moments: FloatArray,
    neighbours: NDArray[np.int32],
    grow: BoolArray,
    fitted: FloatArray,
    curvature: FloatArray,
    residual: FloatArray,
    spread: FloatArray,
    used: IndexArray,
) -> None:
    """Scales past the largest query, for flat noisy places: each point's largest-scale
    moments merged with its neighbours', once and twice (about ADAPTIVE_WIDE points); a point
    of ``grow`` takes a wider one while Lepski's rule holds and its residual stays level. The
    arrays are updated in place."""
    m = len(moments)
    grow = grow.copy()
    held = [(fitted.copy(), spread.copy())]  # the fits a wider one must agree with
    level = residual.copy()  # the residual of the scale before
    merged = moments
    for size, effective in zip(ADAPTIVE_WIDE, ADAPTIVE_WIDE_EFFECTIVE, strict=True):
        wider = np.empty_like(moments)
        _core.widened_moments(merged, neighbours, wider)
        merged = wider
        normals, bent, rms, spreads = np.empty((m, 3)), np.empty(m), np.empty(m), np.empty(m)
        status = np.empty(m, dtype=np.intp)
        _core.moment_normals(
            merged,
            effective,
            frame.tiny,
            POINT_LINE_RATIO,
            POINT_GAP_RATIO,
            normals,
            bent,
            rms,
            spreads,
            status,
        )
        grow &= (status == PointStatus.ok) & (rms <= ADAPTIVE_WIDE_GROWTH * level)
        for before, before_spread in held:
            cosine = np.minimum(1.0, np.abs(np.einsum("ij,ij->i", before, normals)))
            sine = np.sqrt(1.0 - cosine * cosine)
            limit = ADAPTIVE_AGREEMENT * (before_spread + np.minimum(before_spread, spreads))
            grow &= sine <= limit
        if not grow.any():
            return
        fitted[grow], curvature[grow], residual[grow] = normals[grow], bent[grow], rms[grow]
        spread[grow], used[grow] = spreads[grow], size
        held.append((normals, spreads))
        level = rms


def _degenerate_piles(
    weight: IndexArray, used: IndexArray, codes: IndexArray, graph: NDArray[np.int32]
) -> None:
    """Places alone in their neighbourhood, or with one other (the graph's nearest after
    itself), whose points number three or more: their points coincide, or lie on a line."""
    few = np.flatnonzero(used < 3)
    if not len(few):
        return
    held = weight[few].copy()
    pair = used[few] == 2
    if pair.any():  # a graph of one column has no pairs
        held[pair] += weight[graph[few[pair], 1]]
    codes[few[(held >= 3) & ~pair]] = PointStatus.duplicates
    codes[few[(held >= 3) & pair]] = PointStatus.collinear


def _neighbourhoods(
    points: FloatArray, k: int | None, bound: float, g: int
) -> Iterator[tuple[int, IndexArray, IndexArray, IndexArray]]:
    """Per chunk of queries: its start, the neighbour lists as CSR, and the g nearest."""
    m = len(points)
    if k is not None and bound == math.inf:
        yield from _nearest(points, min(k, m), g)
        return
    from scipy.spatial import cKDTree  # type: ignore[import-untyped]  # on first use: 0.5 s

    tree = cKDTree(points, balanced_tree=False, compact_nodes=False)
    for start in range(0, m, QUERY_CHUNK):
        queries = points[start : start + QUERY_CHUNK]
        if k is not None:
            count = min(k, m)
            _, nearest = tree.query(queries, k=count, distance_upper_bound=bound, workers=-1)
            nearest = nearest.reshape(len(queries), count)
            indptr = np.arange(len(queries) + 1, dtype=np.intp) * count
            yield start, indptr, nearest.ravel().astype(np.intp), nearest[:, :g]
        else:
            lists = tree.query_ball_point(queries, bound, workers=-1, return_sorted=False)
            sizes = np.fromiter(map(len, lists), dtype=np.intp, count=len(lists))
            indptr = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
            indices = np.concatenate([np.asarray(x, dtype=np.intp) for x in lists])
            _, nearest = tree.query(queries, k=g, distance_upper_bound=bound, workers=-1)
            yield start, indptr, indices, nearest.reshape(len(queries), g)


def _nearest(
    points: FloatArray, k: int, g: int
) -> Iterator[tuple[int, IndexArray, IndexArray, IndexArray]]:
    """As _neighbourhoods, for the k nearest without a radius (the compiled tree)."""
    m = len(points)
    tree = _core.PointTree(points)
    for start in range(0, m, QUERY_CHUNK):
        stop = min(m, start + QUERY_CHUNK)
        nearest = np.empty((stop - start, k), dtype=np.intp)
        tree.nearest(start, stop, k, nearest)
        indptr = np.arange(stop - start + 1, dtype=np.intp) * k
        yield start, indptr, nearest.ravel(), nearest[:, :g]


def _signs(
    frame: _Frame,
    normals: FloatArray,
    valid: BoolArray,
    graph: NDArray[np.int32],
    orient: str,
    references: FloatArray | None,
    max_angle: float,
) -> Signs:
    """The orientation asked for, in the frame's order."""
    m = len(normals)
    weight = frame.weight
    if orient in ("mst", "riemannian"):
        riemannian = orient == "riemannian"
        return along_tree(frame.points, normals, valid, graph, max_angle, riemannian, weight)
    if references is None:  # "none"
        return Signs(np.zeros(m, dtype=bool), np.zeros(m, dtype=bool), ())
    if orient == "viewpoint":
        sensor = (references - frame.centre) / frame.scale
        return towards(normals, valid, sensor - frame.points, "viewpoint", weight)
    if orient == "direction":
        return towards(normals, valid, references, "direction", weight)
    # A place's points may store different normals: its first point's decides.
    return towards(normals, valid, references[frame.origin], "stored normals", weight)
