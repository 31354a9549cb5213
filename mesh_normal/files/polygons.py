"""Polygons triangulated inside themselves: fans where they fit, ear clipping elsewhere.

A polygon of ``k`` corners becomes ``k - 2`` consecutive triangles, in file order, wound like
the polygon: every triangle's normal agrees with the polygon's Newell normal. The fan from the
first corner is kept wherever none of its triangles faces against the polygon: every convex
polygon, and any polygon star-shaped around its first corner. That test is one compiled pass
(:mod:`mesh_normal.files.polygon_shapes`, about as long as building the fans on a million
quads; files of triangles skip it); only polygons whose fan folds over (concave ones seen from
their first corner) are ear-clipped, one at a time, on the plane of their Newell normal with
mapbox-earcut. Polygons that are not planar keep the triangles the same rules give and are
counted in a note.
"""

from __future__ import annotations

import mapbox_earcut
import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.polygon_shapes import Shapes, measure_polygons
from mesh_normal.types import FloatArray, IndexArray

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
    shapes = None
    if np.any(sizes >= 4):
        shapes = measure_polygons(sizes, indices, points)
    clipped, crossing = (0, 0)
    if shapes is not None:
        clipped, crossing = _ear_clip(corners, sizes, indices, points, shapes)
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


def _ear_clip(
    corners: IndexArray,
    counts: IndexArray,
    corner_vertices: IndexArray,
    vertices: FloatArray,
    shapes: Shapes,
) -> tuple[int, int]:
    """Replace, in place, the fans that fold over with ear-clipped triangles (the same ``k - 2``
    rows); return how many were clipped and how many kept their fan because ear clipping could
    not cover them (they cross themselves)."""
    if not shapes.folded.any():
        return 0, 0
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
        ear clipping cannot cover it with ``k - 2`` triangles (the polygon crosses itself).
    """
    axis = np.zeros(3)
    axis[np.argmin(np.abs(normal))] = 1.0
    across = np.cross(normal, axis)
    across /= np.linalg.norm(across)
    plane = points @ np.stack([across, np.cross(normal, across)], axis=1)  # u x v = normal
    ring = np.array([len(points)], dtype=np.uint32)
    found = mapbox_earcut.triangulate_float64(np.ascontiguousarray(plane), ring)
    local = _restore_dropped(np.asarray(found, dtype=np.intp).reshape(-1, 3), len(points))
    if local is None or len(local) != len(points) - 2:
        return None
    a, b, c = plane[local[:, 0]], plane[local[:, 1]], plane[local[:, 2]]
    backwards = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    local[backwards] = local[backwards][:, [0, 2, 1]]
    return local


def _restore_dropped(local: IndexArray, k: int) -> IndexArray | None:
    """Put back the corners ear clipping dropped (earcut drops a corner equal to the one
    before it), splitting the triangle on the edge that skips them, so a polygon keeps its
    ``k - 2`` triangles; ``None`` when no triangle has that edge.

    Parameters
    ----------
    local : (t, 3) intp
        Triangles over corners ``0 .. k - 1``.
    """
    used = np.zeros(k, dtype=bool)
    used[local.ravel()] = True
    if used.all() or not used.any():
        return local
    triangles = [tuple(map(int, row)) for row in local]
    first = int(np.argmax(used))
    ring = [(first + step) % k for step in range(1, k + 1)]  # ends at first, a used corner
    before, skipped = first, []
    for corner in ring:
        if not used[corner]:
            skipped.append(corner)
            continue
        if skipped:
            split = _split(triangles, before, corner, skipped)
            if split is None:
                return None
            triangles = split
        before, skipped = corner, []
    return np.array(triangles, dtype=np.intp)


def _split(
    triangles: list[tuple[int, ...]], start: int, end: int, between: list[int]
) -> list[tuple[int, ...]] | None:
    """Replace the triangle with edge ``start -> end`` by a fan over ``between`` from its third
    corner."""
    for row, (a, b, c) in enumerate(triangles):
        for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
            if (p, q) == (start, end):
                chain = [start, *between, end]
                fan_rows = [(chain[i], chain[i + 1], r) for i in range(len(chain) - 1)]
                return triangles[:row] + fan_rows + triangles[row + 1 :]
    return None


def _notes(
    counts: NDArray[np.intp], shapes: Shapes | None, clipped: int, crossing: int
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
