"""The surface the mesh page draws: the mesh itself, or a simplified copy of a large one.

A browser draws some tens of thousands of faces smoothly; a scan has millions. Above the
target, the faces that are not kept are decimated by quadric edge collapse
(`fast-simplification <https://github.com/pyvista/fast-simplification>`_), which keeps the
shape and its winding, and the kept faces (the ones the view colours as problems) are put back
as they were. The decimation may not move the seam between the two parts, so the kept faces
meet the simplified rest without cracks; the price is that the faces around the seam stay
too, so kept faces scattered one by one make the surface larger than the target (about five
faces more for each), while kept faces in patches (a hole's rim, a part wound inward) cost
little.

Quadric errors are squared distances, so the decimation runs on coordinates brought to a
half-extent of about one (shifted to the centre and scaled by a power of two): a mesh in
nanometres or light years, near the origin or far from it, simplifies the same way.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import fast_simplification  # imported with the page (not on the first large mesh): see warmup
import numpy as np
from numpy.typing import NDArray

from mesh_normal.types import IndexArray

#: How hard the decimation pushes towards its target (fast-simplification's ``agg``): 7 is
#: the library's default, a fair balance of speed and shape.
AGGRESSIVENESS = 7.0
# fast-simplification holds the mesh it works on in one global of its C++ module.
_LOCK = threading.Lock()


@dataclass(frozen=True, slots=True)
class Surface:
    """A mesh to draw, and where each of its faces and points came from.

    points : (p, 3) float
    faces : (q, 3) int, indices into ``points``
    source : (q,) int, the input face each face is a copy of, or -1 for a simplified face
    vertex_source : (p,) int, the input vertex each point is, or -1 for a new point
    """

    points: NDArray[np.float64]
    faces: IndexArray
    source: IndexArray
    vertex_source: IndexArray

    @property
    def simplified(self) -> bool:
        return bool(len(self.source)) and bool(self.source.min() < 0)


def _unit(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """Points shifted to their centre and scaled by 2**-e to a half-extent in [0.5, 1)."""
    low, high = points.min(axis=0), points.max(axis=0)
    centre = low / 2 + high / 2
    half = float((high / 2 - low / 2).max())
    exponent = int(np.frexp(half)[1]) if half > 0 else 0
    if exponent > 0:  # large: scale first, so the difference cannot overflow
        unit = np.ldexp(points, -exponent) - np.ldexp(centre, -exponent)
    else:  # small: subtract first, so the scaling cannot overflow
        unit = np.ldexp(points - centre, -exponent)
    return unit, centre, exponent


def _decimate(
    points: NDArray[np.float64], faces: IndexArray, target: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    with _LOCK:
        out_points, out_faces = fast_simplification.simplify(
            points,
            faces.astype(np.int32),
            target_count=max(target, 0),
            agg=AGGRESSIVENESS,
            preserve_border=True,  # the seam to the kept faces stays put
        )
    return np.asarray(out_points, dtype=np.float64), np.asarray(out_faces, dtype=np.int64)


def _exact_matches(found: NDArray[np.float64], among: NDArray[np.float64]) -> IndexArray:
    """For each row of ``found``, a row of ``among`` with the very same bits, or -1."""
    if not len(found) or not len(among):
        return np.full(len(found), -1, dtype=np.intp)
    kind = np.dtype((np.void, 24))
    keys = np.ascontiguousarray(among).view(kind).ravel()
    wanted = np.ascontiguousarray(found).view(kind).ravel()
    order = np.argsort(keys, kind="stable")
    at = np.searchsorted(keys[order], wanted).clip(0, len(keys) - 1)
    hit = keys[order][at] == wanted
    return np.where(hit, order[at], -1).astype(np.intp)


def used_vertices(faces: IndexArray, vertex_count: int) -> tuple[IndexArray, IndexArray]:
    """The vertices ``faces`` use, in order, and the faces renumbered on them (no sort)."""
    used = np.flatnonzero(np.bincount(faces.ravel(), minlength=vertex_count))
    renumber = np.zeros(vertex_count, dtype=np.intp)
    renumber[used] = np.arange(len(used))
    return used, renumber[faces]


def _simplified_rest(
    vertices: NDArray[np.float64], rest: IndexArray, target: int, seam: IndexArray
) -> tuple[NDArray[np.float64], NDArray[np.int64], IndexArray]:
    """The ``rest`` faces decimated to about ``target``: points, faces and each point's source.

    The decimation leaves the ``seam`` vertices (those shared with the kept faces) where they
    are, bit for bit: each output point that is one of them gets its index, the others -1. A
    new point is clipped to the input's bounding box, which it lies in up to rounding.
    """
    used, local = used_vertices(rest, len(vertices))
    unit, centre, exponent = _unit(vertices[used])
    out_points, out_faces = _decimate(unit, local, target)
    seam_local = np.flatnonzero(np.isin(used, seam, assume_unique=True))
    matched = _exact_matches(out_points, unit[seam_local])
    source = np.full(len(out_points), -1, dtype=np.intp)
    source[matched >= 0] = used[seam_local[matched[matched >= 0]]]
    with np.errstate(over="ignore", invalid="ignore"):
        if exponent > 0:
            back = np.ldexp(out_points + np.ldexp(centre, -exponent), exponent)
        else:
            back = np.ldexp(out_points, exponent) + centre
    low, high = vertices[used].min(axis=0), vertices[used].max(axis=0)
    back = np.clip(np.nan_to_num(back, nan=0.0, posinf=np.inf, neginf=-np.inf), low, high)
    back[source >= 0] = vertices[source[source >= 0]]
    return back, out_faces, source


def display_surface(
    vertices: NDArray[np.float64],
    faces: IndexArray,
    keep_faces: NDArray[np.integer[Any]],
    target: int,
) -> Surface:
    """The mesh to draw: itself when it has at most ``target`` faces, else about ``target``.

    vertices : (n, 3) float, finite
    faces : (m, 3) int
    keep_faces : (k,) int, faces drawn exactly as they are (all of them, even beyond the target)
    target : the number of faces to aim for

    A face whose corners repeat an index has no area and is dropped from the simplified part.
    The result is deterministic: the same input gives the same surface.
    """
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.intp).reshape(-1, 3)
    if not np.isfinite(vertices).all():
        raise ValueError("display_surface needs finite vertices")
    everything = np.arange(len(faces), dtype=np.intp)
    if len(faces) <= target:
        return Surface(vertices, faces, everything, np.arange(len(vertices), dtype=np.intp))
    keep = np.unique(np.asarray(keep_faces, dtype=np.intp))
    kept = np.zeros(len(faces), dtype=bool)
    kept[keep] = True
    flat = (
        (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    )
    rest = everything[~kept & ~flat]
    goal = max(target - len(keep), 0)
    if len(rest) <= goal or not len(rest):
        shown = np.sort(np.concatenate([keep, rest]))
        return _compact(vertices, faces[shown], shown)
    seam = np.flatnonzero(np.bincount(faces[keep].ravel(), minlength=len(vertices)))
    new_points, new_faces, point_source = _simplified_rest(vertices, faces[rest], goal, seam)
    return _joined(vertices, faces, keep, new_points, new_faces, point_source)


def _compact(vertices: NDArray[np.float64], faces: IndexArray, source: IndexArray) -> Surface:
    used, local = used_vertices(faces, len(vertices))
    return Surface(vertices[used], local, source, used)


def _joined(
    vertices: NDArray[np.float64],
    faces: IndexArray,
    keep: IndexArray,
    new_points: NDArray[np.float64],
    new_faces: NDArray[np.int64],
    point_source: IndexArray,
) -> Surface:
    """The kept faces and the simplified ones on one set of points, welded along the seam."""
    old = point_source >= 0
    originals = np.unique(np.concatenate([faces[keep].ravel(), point_source[old]]))
    index = np.empty(len(new_points), dtype=np.intp)
    index[old] = np.searchsorted(originals, point_source[old])
    index[~old] = len(originals) + np.arange(np.count_nonzero(~old))
    points = np.concatenate([vertices[originals], new_points[~old]])
    joined = np.concatenate(
        [np.searchsorted(originals, faces[keep]).reshape(-1, 3), index[new_faces]]
    ).astype(np.intp)
    source = np.concatenate([keep, np.full(len(new_faces), -1, dtype=np.intp)])
    vertex_source = np.concatenate([originals, np.full(np.count_nonzero(~old), -1)])
    return Surface(points, joined, source, vertex_source.astype(np.intp))
