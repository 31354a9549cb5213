"""The measures that decide how each polygon is triangulated, in one compiled pass.

Its own module so that reading a file of triangles never imports numba (the readers stay light);
polygons of four or more corners bring it in. One pass over the corners, without allocating,
is about 20 times faster than the same in NumPy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mesh_normal.kernels import announce_compiling, kernel
from mesh_normal.types import BoolArray, FloatArray, IndexArray, Vector

#: A polygon's corners: the flat corner array, where they start, and how many.
Ring = tuple[IndexArray, int, int]

#: A fan triangle faces against its polygon when its area along the polygon's normal is below
#: ``-FAN_FOLD * size**2``: rounding on a degenerate (collinear) triangle stays far above that.
FAN_FOLD = 1e-10


@dataclass(frozen=True)
class Shapes:
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


def measure_polygons(
    counts: IndexArray, corner_vertices: IndexArray, vertices: FloatArray
) -> Shapes | None:
    """Measure the polygons, or ``None`` when a corner index is not a vertex."""
    if len(corner_vertices) != counts.sum():
        return None
    starts = np.cumsum(counts) - counts
    normals, deviation = np.empty((len(counts), 3)), np.zeros(len(counts))
    folded = np.zeros(len(counts), dtype=bool)
    announce_compiling()
    if not _polygon_shapes(counts, starts, corner_vertices, vertices, normals, deviation, folded):
        return None
    return Shapes(normals, folded, deviation)


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
    one pass over their corners (NumPy takes 20 times as long). Corners are
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
        ring = (corner_vertices, start, k)  # a tuple, not a slice: no reference counting
        centre, size = _centre_and_size(vertices, ring)
        normal = _newell(vertices, ring, centre)
        normals[polygon, 0], normals[polygon, 1], normals[polygon, 2] = normal
        deviation[polygon] = _farthest(vertices, ring, centre, normal) / size
        folded[polygon] = _fan_folds(vertices, ring, normal, -FAN_FOLD * size * size)
    return True


@kernel()
def _relative(vertices: FloatArray, vertex: int, origin: Vector) -> Vector:
    return (
        vertices[vertex, 0] - origin[0],
        vertices[vertex, 1] - origin[1],
        vertices[vertex, 2] - origin[2],
    )


@kernel()
def _centre_and_size(vertices: FloatArray, ring: Ring) -> tuple[Vector, float]:
    """The centroid of a polygon's corners and its bounding-box diagonal."""
    x = y = z = 0.0
    low_x = low_y = low_z = np.inf
    high_x = high_y = high_z = -np.inf
    corner_vertices, start, k = ring
    for corner in range(start, start + k):
        vertex = corner_vertices[corner]
        px, py, pz = vertices[vertex, 0], vertices[vertex, 1], vertices[vertex, 2]
        x, y, z = x + px, y + py, z + pz
        low_x, low_y, low_z = min(low_x, px), min(low_y, py), min(low_z, pz)
        high_x, high_y, high_z = max(high_x, px), max(high_y, py), max(high_z, pz)
    size = math.sqrt((high_x - low_x) ** 2 + (high_y - low_y) ** 2 + (high_z - low_z) ** 2)
    return (x / k, y / k, z / k), size


@kernel()
def _newell(vertices: FloatArray, ring: Ring, centre: Vector) -> Vector:
    """The unit Newell normal of a polygon, its corners taken relative to ``centre``."""
    x = y = z = 0.0
    corner_vertices, start, k = ring
    for corner in range(k):
        a, b = corner_vertices[start + corner], corner_vertices[start + (corner + 1) % k]
        ax, ay, az = _relative(vertices, a, centre)
        bx, by, bz = _relative(vertices, b, centre)
        x, y, z = x + ay * bz - az * by, y + az * bx - ax * bz, z + ax * by - ay * bx
    length = math.sqrt(x * x + y * y + z * z)
    return x / length, y / length, z / length


@kernel()
def _farthest(vertices: FloatArray, ring: Ring, centre: Vector, normal: Vector) -> float:
    """The largest distance of a corner from the plane through ``centre`` along ``normal``."""
    farthest = 0.0
    corner_vertices, start, k = ring
    for corner in range(start, start + k):
        vertex = corner_vertices[corner]
        height = 0.0
        for i in range(3):
            height += (vertices[vertex, i] - centre[i]) * normal[i]
        farthest = max(farthest, abs(height))
    return farthest


@kernel()
def _fan_folds(vertices: FloatArray, ring: Ring, normal: Vector, floor: float) -> bool:
    """Whether a fan triangle of the polygon has its (doubled) area along ``normal`` below
    ``floor``."""
    corner_vertices, start, k = ring
    first = _relative(vertices, corner_vertices[start], (0.0, 0.0, 0.0))
    for corner in range(start + 1, start + k - 1):
        b, c = corner_vertices[corner], corner_vertices[corner + 1]
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
