"""Polygons triangulated inside themselves: fans where they fit, ear clipping elsewhere.

A polygon of ``k`` corners becomes ``k - 2`` consecutive triangles, in file order, wound like
the polygon: every triangle's normal agrees with the polygon's Newell normal. The fan from the
first corner is kept wherever none of its triangles faces against the polygon: every convex
polygon, and any polygon star-shaped around its first corner. That test is vectorised, so
triangles and quads cost a few array passes; only polygons whose fan folds over (concave ones
seen from their first corner) are ear-clipped, one at a time, on the plane of their Newell
normal with mapbox-earcut.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mapbox_earcut
import numpy as np
from numpy.typing import NDArray

from mesh_normal.kernels import announce_compiling, kernel
from mesh_normal.types import BoolArray, FloatArray, IndexArray, Vector

#: A fan triangle faces against its polygon when its area along the polygon's normal is below
#: ``-FAN_FOLD * size**2``: rounding on a degenerate (collinear) triangle stays far above that.
FAN_FOLD = 1e-10
#: A polygon is not planar when a corner lies farther from its plane than this share of its size
#: (the diagonal of its bounding box).
PLANAR_SHARE = 1e-3

Triangulated = tuple[NDArray[np.intp], NDArray[np.intp], list[str]]


def triangulate(
    counts: NDArray[np.integer],
    corner_vertices: NDArray[np.integer],
    vertices: NDArray[np.floating],
) -> Triangulated:
    """Triangulate polygons of ``counts[i]`` corners, each inside itself.

    Parameters
    ----------
    counts : (p,) int
        Corners of each polygon; their corners are consecutive in one flat array.
    corner_vertices : (c,) int
        The vertex of each corner in that flat array (``c = counts.sum()``).
    vertices : (n, 3) float
        Vertex positions. Out-of-range indices or non-finite positions leave fans (the reader's
        checks report them).

    Returns
    -------
    corners : (t, 3) intp
        Positions in the flat corner array, ``k - 2`` consecutive triangles for each polygon in
        polygon order; polygons with fewer than three corners give none.
    source : (t,) intp
        The polygon each triangle came from.
    notes : list of str
        What was triangulated, skipped or found not planar, as sentences (empty for all
        triangles).
    """
    sizes = np.asarray(counts, dtype=np.intp)
    corners, source = fan(sizes)
    if np.all(sizes == 3):
        return corners, source, []
    indices = np.asarray(corner_vertices, dtype=np.intp)
    points = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    shapes = _measure(sizes, indices, points)
    clipped, crossing = _ear_clip(corners, sizes, indices, points, shapes) if shapes else (0, 0)
    return corners, source, _notes(sizes, shapes, clipped, crossing)


def fan(counts: NDArray[np.integer]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Fans from each polygon's first corner: ``[a, b, c, d]`` gives ``[a, b, c]``, ``[a, c, d]``.

    Parameters
    ----------
    counts : (p,) int

    Returns
    -------
    corners : (t, 3) intp
        Positions in the flat corner array.
    source : (t,) intp
        The polygon each triangle came from.
    """
    counts = np.asarray(counts, dtype=np.intp)
    starts = np.cumsum(counts) - counts
    if np.all(counts == 3):
        return starts[:, None] + np.arange(3), np.arange(len(counts))
    pieces = np.maximum(counts - 2, 0)
    source = np.repeat(np.arange(len(counts)), pieces)
    first = starts[source]
    step = np.arange(len(source)) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 1
    return np.stack([first, first + step, first + step + 1], axis=1), source


@dataclass(frozen=True)
class _Shapes:
    """Every polygon measured on its own plane (full length; polygons under four corners are
    never folded and have deviation 0).

    Attributes
    ----------
    normals : (p, 3) float64
        Unit Newell normals (NaN where a polygon of four or more corners has no area).
    folded : (p,) bool
        The fan from the first corner has a triangle facing against the polygon.
    deviation : (p,) float64
        Farthest corner from the polygon's plane, as a share of its size (NaN without area).
    """

    normals: FloatArray
    folded: BoolArray
    deviation: FloatArray


def _measure(
    counts: IndexArray, corner_vertices: IndexArray, vertices: FloatArray
) -> _Shapes | None:
    """Measure the polygons, or ``None`` when a corner index is not a vertex."""
    if len(corner_vertices) != counts.sum():
        return None
    starts = np.cumsum(counts) - counts
    normals, deviation = np.empty((len(counts), 3)), np.zeros(len(counts))
    folded = np.zeros(len(counts), dtype=bool)
    announce_compiling()
    if not _polygon_shapes(counts, starts, corner_vertices, vertices, normals, deviation, folded):
        return None
    return _Shapes(normals, folded, deviation)


@kernel()
def _polygon_shapes(
    counts: IndexArray,
    starts: IndexArray,
    corner_vertices: IndexArray,
    vertices: FloatArray,
    normals: FloatArray,
    deviation: FloatArray,
    folded: BoolArray,
) -> bool:
    """Fill ``normals``, ``deviation`` and ``folded`` for polygons of four or more corners, in
    one pass over their corners (NumPy took 20 times as long on a million quads). Corners are
    taken relative to the polygon's centroid, so a polygon far from the origin measures as
    one at it. Returns False, having filled nothing reliable, when a corner index is not a
    vertex."""
    for polygon in range(len(counts)):
        k, start = counts[polygon], starts[polygon]
        if k < 4:
            continue
        for corner in range(start, start + k):
            if corner_vertices[corner] < 0 or corner_vertices[corner] >= len(vertices):
                return False
        centre, size = _centre_and_size(vertices, corner_vertices[start : start + k])
        normal = _newell(vertices, corner_vertices[start : start + k], centre)
        normals[polygon] = normal
        deviation[polygon] = (
            _farthest(vertices, corner_vertices[start : start + k], centre, normal) / size
        )
        folded[polygon] = _fan_folds(
            vertices, corner_vertices[start : start + k], normal, -FAN_FOLD * size * size
        )
    return True


@kernel()
def _relative(vertices: FloatArray, vertex: int, origin: Vector) -> Vector:
    return (
        vertices[vertex, 0] - origin[0],
        vertices[vertex, 1] - origin[1],
        vertices[vertex, 2] - origin[2],
    )


@kernel()
def _centre_and_size(vertices: FloatArray, ring: IndexArray) -> tuple[Vector, float]:
    """The centroid of a polygon's corners and its bounding-box diagonal."""
    x = y = z = 0.0
    low_x = low_y = low_z = np.inf
    high_x = high_y = high_z = -np.inf
    for vertex in ring:
        px, py, pz = vertices[vertex, 0], vertices[vertex, 1], vertices[vertex, 2]
        x, y, z = x + px, y + py, z + pz
        low_x, low_y, low_z = min(low_x, px), min(low_y, py), min(low_z, pz)
        high_x, high_y, high_z = max(high_x, px), max(high_y, py), max(high_z, pz)
    size = math.sqrt((high_x - low_x) ** 2 + (high_y - low_y) ** 2 + (high_z - low_z) ** 2)
    return (x / len(ring), y / len(ring), z / len(ring)), size


@kernel()
def _newell(vertices: FloatArray, ring: IndexArray, centre: Vector) -> Vector:
    """The unit Newell normal of a polygon, its corners taken relative to ``centre``."""
    x = y = z = 0.0
    k = len(ring)
    for corner in range(k):
        a, b = ring[corner], ring[(corner + 1) % k]
        ax, ay, az = _relative(vertices, a, centre)
        bx, by, bz = _relative(vertices, b, centre)
        x, y, z = x + ay * bz - az * by, y + az * bx - ax * bz, z + ax * by - ay * bx
    length = math.sqrt(x * x + y * y + z * z)
    return x / length, y / length, z / length


@kernel()
def _farthest(vertices: FloatArray, ring: IndexArray, centre: Vector, normal: Vector) -> float:
    """The largest distance of a corner from the plane through ``centre`` along ``normal``."""
    farthest = 0.0
    for vertex in ring:
        height = 0.0
        for i in range(3):
            height += (vertices[vertex, i] - centre[i]) * normal[i]
        farthest = max(farthest, abs(height))
    return farthest


@kernel()
def _fan_folds(vertices: FloatArray, ring: IndexArray, normal: Vector, floor: float) -> bool:
    """Whether a fan triangle of the polygon has its (doubled) area along ``normal`` below
    ``floor``."""
    first = (vertices[ring[0], 0], vertices[ring[0], 1], vertices[ring[0], 2])
    for corner in range(1, len(ring) - 1):
        b, c = ring[corner], ring[corner + 1]
        bx, by, bz = _relative(vertices, b, first)
        cx, cy, cz = _relative(vertices, c, first)
        along = (
            (by * cz - bz * cy) * normal[0]
            + (bz * cx - bx * cz) * normal[1]
            + (bx * cy - by * cx) * normal[2]
        )
        if along < floor:
            return True
    return False


def _ear_clip(
    corners: IndexArray,
    counts: IndexArray,
    corner_vertices: IndexArray,
    vertices: FloatArray,
    shapes: _Shapes,
) -> tuple[int, int]:
    """Replace, in place, the fans that fold over with ear-clipped triangles (the same ``k - 2``
    rows); return how many were clipped and how many kept their fan because ear clipping could
    not cover them (they cross themselves)."""
    pieces = np.maximum(counts - 2, 0)
    first_triangle = np.cumsum(pieces) - pieces
    starts = np.cumsum(counts) - counts
    clipped = crossing = 0
    for polygon in np.flatnonzero(shapes.folded):
        begin, end = starts[polygon], starts[polygon] + counts[polygon]
        points = vertices[corner_vertices[begin:end]]
        local = _clip(points - points.mean(axis=0), shapes.normals[polygon])
        if local is None:
            crossing += 1
            continue
        row = first_triangle[polygon]
        corners[row : row + len(local)] = begin + local
        clipped += 1
    return clipped, crossing


def _clip(points: NDArray[np.float64], normal: NDArray[np.float64]) -> NDArray[np.intp] | None:
    """Ear-clip one polygon on its plane.

    Parameters
    ----------
    points : (k, 3) float64
        Its corners, centred.
    normal : (3,) float64
        Its unit Newell normal.

    Returns
    -------
    (k - 2, 3) intp or None
        Corner positions in ``points``, each triangle wound like the polygon; ``None`` when
        ear clipping gives fewer triangles (the polygon crosses itself).
    """
    axis = np.zeros(3)
    axis[np.argmin(np.abs(normal))] = 1.0
    across = np.cross(normal, axis)
    across /= np.linalg.norm(across)
    plane = points @ np.stack([across, np.cross(normal, across)], axis=1)  # u x v = normal
    ring = np.array([len(points)], dtype=np.uint32)
    found = mapbox_earcut.triangulate_float64(np.ascontiguousarray(plane), ring)
    local = np.asarray(found, dtype=np.intp).reshape(-1, 3)
    if len(local) != len(points) - 2:
        return None
    a, b, c = plane[local[:, 0]], plane[local[:, 1]], plane[local[:, 2]]
    backwards = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    local[backwards] = local[backwards][:, [0, 2, 1]]
    return local


def _notes(
    counts: NDArray[np.intp], shapes: _Shapes | None, clipped: int, crossing: int
) -> list[str]:
    fans = counts.copy()
    if shapes is not None:
        fans[shapes.folded] = 0  # counted as clipped or crossing below
    quads, larger = int(np.sum(fans == 4)), int(np.sum(fans > 4))
    notes = []
    if quads or larger:
        parts = [_plural(quads, "quad"), _plural(larger, "larger polygon")]
        made = " and ".join(part for part in parts if part)
        notes.append(f"Triangulated {made} as fans from each one's first corner.")
    if clipped:
        notes.append(
            f"Triangulated {_plural(clipped, 'concave polygon')} by ear clipping on each "
            "one's own plane (a fan from the first corner would fold over)."
        )
    if crossing:
        notes.append(
            f"{_plural(crossing, 'polygon')} cross{'es' if crossing == 1 else ''} "
            f"{'itself' if crossing == 1 else 'themselves'}; "
            f"{'its' if crossing == 1 else 'their'} fan from the first corner is kept."
        )
    if shapes is not None and (bent := shapes.deviation > PLANAR_SHARE).any():
        largest = float(shapes.deviation[bent].max()) * 100
        notes.append(
            f"{_plural(int(bent.sum()), 'polygon')} "
            f"{'is' if bent.sum() == 1 else 'are'} not planar (largest deviation "
            f"{largest:.3g} % of {'its' if bent.sum() == 1 else 'their'} size); "
            f"{'its' if bent.sum() == 1 else 'their'} triangles follow the file's corners."
        )
    if short := int(np.sum(counts < 3)):
        notes.append(f"Skipped {_plural(short, 'face')} with fewer than three corners.")
    return notes


def _plural(count: int, noun: str) -> str:
    return "" if not count else f"{count:,} {noun}" + ("" if count == 1 else "s")
