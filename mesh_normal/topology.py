"""How the faces of a mesh meet: the corners around each vertex.

A corner is one vertex of one face, numbered ``3 * face + k`` for ``faces[face, k]``, so
corner ids follow ``faces.ravel()``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

IndexArray = NDArray[np.intp]

#: Sort keys vertex * 3m + corner must stay below this to fit int64 with room to spare.
KEY_LIMIT = 2**62


@dataclass(frozen=True, slots=True)
class VertexCorners:
    """The corners of every vertex, as one sorted array and offsets into it.

    Attributes
    ----------
    order : (3 m,) intp
        Corner ids sorted by vertex, and by corner id within a vertex.
    starts : (n + 1,) intp
        The corners of vertex ``v`` are ``order[starts[v]:starts[v + 1]]``.
    """

    order: IndexArray
    starts: IndexArray

    @property
    def counts(self) -> IndexArray:
        """(n,) intp: how many corners (face uses) each vertex has."""
        return np.diff(self.starts)


def vertex_corners(
    faces: IndexArray, vertex_count: int, corners: IndexArray | None = None
) -> VertexCorners:
    """Group the corners of ``faces`` (or just the given ``corners``) by vertex.

    Parameters
    ----------
    faces : (m, 3) intp
        Checked indices (see :func:`mesh_normal.faces.check_mesh`).
    vertex_count : int
        n, the number of vertices.
    corners : (k,) intp, optional
        Corner ids to group, in increasing order; all 3 m corners by default.

    Returns
    -------
    VertexCorners
        A stable sort of the corner ids by vertex, and the offsets of each vertex's group
        (empty groups for vertices with no corner among those given).
    """
    flat = faces.ravel()
    ids = np.arange(len(flat)) if corners is None else corners
    vertex = flat[ids]
    span = len(flat)
    if vertex_count * span < KEY_LIMIT:
        # Sorting unique keys vertex * span + corner is stable by construction and several
        # times faster than a stable argsort (NumPy sorts integer values with SIMD).
        order = np.sort(vertex * span + ids) % span
    else:
        order = ids[np.argsort(vertex, kind="stable")]
    starts = np.zeros(vertex_count + 1, dtype=np.intp)
    np.cumsum(np.bincount(vertex, minlength=vertex_count), out=starts[1:])
    return VertexCorners(order, starts)
