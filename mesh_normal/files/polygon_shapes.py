"""The measures that decide how each polygon is triangulated, in one compiled pass.

``_core.polygon_shapes`` measures each polygon of four or more corners on its own plane, in
one pass over its corners: the centroid and the bounding-box diagonal, the Newell normal of
the corners taken relative to the centroid (so a polygon far from the origin measures as one
at it), the farthest corner from that plane, and whether a triangle of the fan from the first
corner faces against the polygon (its area along the normal below ``-1e-10 * size**2``:
rounding on a degenerate, collinear triangle stays far above that).
One pass over the corners, without allocating, is about 20 times faster than the same in NumPy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import mesh_normal._core as _core
from mesh_normal.types import BoolArray, FloatArray, IndexArray


@dataclass(frozen=True)
class Shapes:
    """Every polygon measured on its own plane (full length; polygons under four corners are
    never folded and have a zero normal and deviation 0).

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
    counts = np.ascontiguousarray(counts, dtype=np.int64)
    corner_vertices = np.ascontiguousarray(corner_vertices, dtype=np.int64)
    vertices = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    if len(corner_vertices) != counts.sum():
        return None
    starts = np.cumsum(counts) - counts
    normals, deviation = np.zeros((len(counts), 3)), np.zeros(len(counts))
    folded = np.zeros(len(counts), dtype=bool)
    if not _core.polygon_shapes(
        counts, starts, corner_vertices, vertices, normals, deviation, folded
    ):
        return None
    return Shapes(normals, folded, deviation)
