"""What is wrong with each face of a mesh, as one code per face, worst problem first.

The 3D view colours faces by these codes, the histogram marks zero-area faces in the
degenerate colour, and the page's legend lists :data:`CLASSES`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal.types import IndexArray

OK, BOUNDARY, NONMANIFOLD, FLIPPED, DEGENERATE = range(5)


@dataclass(frozen=True, slots=True)
class FaceClass:
    code: int
    key: str
    color: str
    label: str


#: What each colour means, worst first; the page's HTML legend is built from this.
CLASSES = (
    FaceClass(DEGENERATE, "degenerate", "#e03131", "No area (degenerate), drawn as dots"),
    FaceClass(
        FLIPPED,
        "flipped",
        "#f76707",
        "Flipped by the fix: wound against its neighbours, or on a part wound inward",
    ),
    FaceClass(NONMANIFOLD, "nonmanifold", "#9c36b5", "On an edge shared by 3 or more faces"),
    FaceClass(BOUNDARY, "boundary", "#f2c94c", "On a boundary edge (a hole or border)"),
    FaceClass(OK, "ok", "#aab4cc", "No problem"),
)
COLORS = {item.code: item.color for item in CLASSES}


def edge_keys(edges: NDArray[np.integer[Any]], vertex_count: int) -> NDArray[np.int64]:
    """One integer per undirected edge: ``min * n + max`` for (k, 2) vertex pairs."""
    pairs = np.sort(np.asarray(edges, dtype=np.int64).reshape(-1, 2), axis=1)
    return pairs[:, 0] * max(vertex_count, 1) + pairs[:, 1]


def faces_on_edges(
    faces: IndexArray, vertex_count: int, edges: NDArray[np.integer[Any]]
) -> NDArray[np.bool_]:
    """For (m, 3) faces, whether each has one of the (k, 2) ``edges`` as a side."""
    if not len(edges) or not len(faces):
        return np.zeros(len(faces), dtype=bool)
    sides = np.stack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1)
    keys = edge_keys(sides, vertex_count).reshape(-1, 3)
    return np.asarray(np.isin(keys, edge_keys(edges, vertex_count)).any(axis=1), dtype=np.bool_)


def face_classes(
    faces: IndexArray,
    vertex_count: int,
    degenerate: NDArray[np.bool_],
    flipped: NDArray[np.bool_],
    boundary_edges: NDArray[np.integer[Any]],
    nonmanifold_edges: NDArray[np.integer[Any]],
) -> NDArray[np.int8]:
    """Each face's worst problem, as one of the codes OK .. DEGENERATE; shape (m,)."""
    classes = np.full(len(faces), OK, dtype=np.int8)
    classes[faces_on_edges(faces, vertex_count, boundary_edges)] = BOUNDARY
    classes[faces_on_edges(faces, vertex_count, nonmanifold_edges)] = NONMANIFOLD
    classes[np.asarray(flipped, dtype=bool)] = FLIPPED
    classes[np.asarray(degenerate, dtype=bool)] = DEGENERATE
    return classes
