"""The normals the 3D view can draw as arrows, for the page to choose from without a request.

For each kind (face, vertex, corner), up to POOL unit normals with where their arrow starts,
in a fixed random order: the first ``k`` of them are a fair sample of ``k``, so the page's
count control just takes a prefix. Face arrows start at the centroid; vertex arrows at the
vertex; corner arrows a fifth of the way from the corner to the centroid, so that the corners
around one vertex do not overlap. The vertex and corner normals are the library's
(angle-weighted; corners with a 30° crease), computed on the whole mesh, the corner ones only
up to CORNER_FACES faces (they take nine numbers a face). Each sampled corner also carries
``around``: the area-weighted normals of the faces at its vertex (its own face first, at most
AROUND of them, scaled to the largest), so that the page's crease slider can recompute it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal.types import IndexArray

#: Most arrows of each kind the page can draw.
POOL = 1_000
#: Corner normals are offered for meshes up to this many faces.
CORNER_FACES = 300_000
CREASE_ANGLE = 30.0
#: Most faces around a sampled corner's vertex sent for the page's crease slider.
AROUND = 64
SEED = 20240608


def _order(count: int, seed: int) -> IndexArray:
    rng = np.random.default_rng(seed)
    if count <= POOL:
        return rng.permutation(count).astype(np.intp)
    return rng.choice(count, size=POOL, replace=False).astype(np.intp)


def _pool(
    starts: NDArray[np.float64], normals: NDArray[np.float64], labels: list[str]
) -> dict[str, Any]:
    return {
        "at": np.round(starts, 6).tolist(),
        "normal": np.round(normals, 5).tolist(),
        "label": labels,
    }


def normal_pools(
    points: NDArray[np.float64],
    faces: IndexArray,
    face_normals: NDArray[np.float64],
    flipped: NDArray[np.bool_],
    file_vertices: NDArray[np.float64],
    vertex_ids: IndexArray,
) -> dict[str, Any]:
    """``{"face", "vertex", "corner"}``: each ``{"at", "normal", "label"}`` (and ``"flipped"``
    for faces), or None for a kind not offered.

    points : (n, 3) float, the vertices in view coordinates
    faces : (m, 3) int
    face_normals : (m, 3) float, zero rows for faces without one
    flipped : (m,) bool, the faces the fix flips (their arrows are drawn orange)
    file_vertices : (n, 3) float, the file's own coordinates, for the vertex and corner normals
    vertex_ids : (n,) int, each vertex's index in the file, for the labels
    """
    from mesh_normal import corner_normals, vertex_normals

    centroids = points[faces].mean(axis=1) if len(faces) else np.zeros((0, 3))
    usable = np.flatnonzero(np.abs(face_normals).sum(axis=1) > 0)
    chosen = usable[_order(len(usable), SEED)]
    pools: dict[str, Any] = {"face": None, "vertex": None, "corner": None}
    pools["face"] = {
        **_pool(centroids[chosen], face_normals[chosen], [f"face {f}" for f in chosen.tolist()]),
        "flipped": np.asarray(flipped, dtype=bool)[chosen].tolist(),
    }
    used = np.flatnonzero(np.bincount(faces.ravel(), minlength=len(points)))
    smooth = vertex_normals(file_vertices, faces, "angle")
    usable_vertices = used[~smooth.missing[used]]
    chosen = usable_vertices[_order(len(usable_vertices), SEED + 1)]
    pools["vertex"] = _pool(
        points[chosen], smooth.normals[chosen], [f"vertex {v}" for v in vertex_ids[chosen].tolist()]
    )
    if len(faces) <= CORNER_FACES:
        corners = corner_normals(file_vertices, faces, CREASE_ANGLE, "angle")
        flat = np.flatnonzero(~corners.missing.ravel())
        chosen = flat[_order(len(flat), SEED + 2)]
        face, corner = np.divmod(chosen, 3)
        starts = points[faces[face, corner]] * 0.8 + centroids[face] * 0.2
        labels = [
            f"face {f}, corner {k}" for f, k in zip(face.tolist(), corner.tolist(), strict=True)
        ]
        pools["corner"] = {
            **_pool(starts, corners.normals[face, corner], labels),
            "around": _around(points, faces, face, faces[face, corner]),
        }
    return pools


def _around(
    points: NDArray[np.float64], faces: IndexArray, own: IndexArray, at: IndexArray
) -> list[list[list[float]]]:
    """For each corner (face ``own``, vertex ``at``): the area-weighted normals (cross
    products) of the faces at the vertex, its own face first, scaled so the largest is 1."""
    p = points[faces]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]) if len(faces) else np.zeros((0, 3))
    incident = np.repeat(np.arange(len(faces), dtype=np.intp), 3)
    order = np.argsort(faces.ravel(), kind="stable")
    by_vertex, incident = faces.ravel()[order], incident[order]
    low = np.searchsorted(by_vertex, at, side="left")
    high = np.searchsorted(by_vertex, at, side="right")
    result = []
    for f, start, stop in zip(own.tolist(), low.tolist(), high.tolist(), strict=True):
        others = incident[start:stop]
        group = np.concatenate([[f], others[others != f][: AROUND - 1]])
        normals = cross[group]
        scale = float(np.linalg.norm(normals, axis=1).max())
        result.append(np.round(normals / (scale or 1.0), 5).tolist())
    return result
