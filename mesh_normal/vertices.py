"""Vertex normals of a triangle mesh: weighted averages of its face normals.

Each corner (one vertex of one face) gives its face's unit normal a weight:

- ``"uniform"``: 1, the plain mean of the incident face normals;
- ``"area"``: the face's area (the sum of the raw cross products);
- ``"angle"``: the corner's angle (Thuermer and Wuethrich 1998), computed stably as
  ``atan2(|n|, p . q)`` for the corner's edges p and q, with the face's most accurate |n|;
- ``"max"``: sin(angle) / (|p| |q|), i.e. |p x q| / (|p|**2 |q|**2) (Nelson Max 1999,
  "Weights for computing vertex normals from facet normals"), exact when the vertex and
  its neighbours lie on a sphere.

The sums are one pass over the faces compiled with numba (see :mod:`mesh_normal.kernels`)
that adds each face's weighted normal, from its :class:`~mesh_normal.faces.FaceGeometry`, into
its three vertices; each sum is normalised once. Degenerate faces (see
:mod:`mesh_normal.faces`) weigh nothing. A vertex in no usable face, or whose sum cancels (at
most ``MESH_CANCELLED_SUM`` of its total weight), gets a zero row and ``True`` in the
``missing`` mask; nothing is NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from mesh_normal.faces import FaceGeometry, MeshInput, checked_input, face_geometry
from mesh_normal.kernels import (
    BLOCK,
    PARALLEL_KERNELS,
    announce_compiling,
    dot,
    face_edges,
    gather,
    kernel,
    prange,
)
from mesh_normal.tolerances import MESH_CANCELLED_SUM
from mesh_normal.types import BoolArray, Edges, FloatArray, IndexArray, Vector

Weighting = Literal["uniform", "area", "angle", "max"]

WEIGHTINGS: tuple[Weighting, ...] = ("uniform", "area", "angle", "max")
_UNIFORM, _AREA, _ANGLE, _MAX = range(4)
_CANCELLED = MESH_CANCELLED_SUM


@dataclass(frozen=True, slots=True)
class VertexNormals:
    """One normal for each of ``n`` vertices.

    Attributes
    ----------
    normals : (n, 3) float64
        Unit normals; zero rows where ``missing``.
    missing : (n,) bool
        The vertex is in no non-degenerate face, or its weighted sum cancels.
    """

    normals: FloatArray
    missing: BoolArray

    def __len__(self) -> int:
        return len(self.missing)


def weighting_code(weighting: str) -> int:
    """The index of ``weighting`` in ``WEIGHTINGS``, as the kernels take it."""
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting must be one of {', '.join(WEIGHTINGS)}, not {weighting!r}.")
    return WEIGHTINGS.index(weighting)


@kernel()
def face_weights(code: int, edges: Edges, length: float) -> Vector:
    """The weights at corners 0, 1, 2 of a usable face (``code`` indexes ``WEIGHTINGS``).

    Corner k lies between edge k - 1 (arriving) and edge k (leaving).
    """
    if code == _UNIFORM:
        return 1.0, 1.0, 1.0
    if code == _AREA:
        return length, length, length
    e0, e1, e2 = edges
    if code == _ANGLE:  # atan2(|n|, p . q) for the corner's edges p, q
        return (
            math.atan2(length, -dot(e2, e0)),
            math.atan2(length, -dot(e0, e1)),
            math.atan2(length, -dot(e1, e2)),
        )
    s0, s1, s2 = dot(e0, e0), dot(e1, e1), dot(e2, e2)  # max: |n| / (|p|**2 |q|**2)
    return length / (s2 * s0), length / (s0 * s1), length / (s1 * s2)


#: The faces are summed in this many halves (in parallel where there are cores), each into
#: its own (n, 4) buffer, and the buffers are added in a fixed order: the result has the same
#: bits on every machine, whatever its number of cores.
_CHUNKS = 2


@kernel(parallel=True)
def _vertex_sums_kernel(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    sums: FloatArray,
    spare: FloatArray,
) -> None:
    """Add each usable face's weighted unit normal and its weight into its vertices' rows.

    ``sums`` and ``spare`` are (n, 4) zeros: the sum of weighted normals and the sum of
    weights side by side, so that each corner updates one cache line. The first half of the
    faces (in whole blocks) goes into ``sums``, the rest into ``spare``; the caller adds
    ``spare`` to ``sums``.
    """
    half = (len(faces) + 2 * BLOCK - 1) // (2 * BLOCK) * BLOCK
    for chunk in prange(_CHUNKS):
        if chunk == 0:
            _accumulate(code, points, factor, faces, crosses, lengths, degenerate, 0, half, sums)
        else:
            stop = len(faces)
            _accumulate(
                code, points, factor, faces, crosses, lengths, degenerate, half, stop, spare
            )


@kernel()
def _accumulate(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    first: int,
    stop: int,
    sums: FloatArray,
) -> None:
    """The sums of faces ``first`` to ``stop`` (``first`` a multiple of the block size).

    Only the angle and max weightings need the edges, so only they gather the corners.
    """
    corners = np.empty((BLOCK, 9))
    stop = min(stop, len(faces))  # the first half may be rounded up past the end
    for start in range(first, stop, BLOCK):
        if code >= _ANGLE:
            gather(points, factor, faces[:stop], start, corners)
        for face in range(start, min(start + BLOCK, stop)):
            if degenerate[face]:
                continue
            length = lengths[face]
            normal = (crosses[face, 0], crosses[face, 1], crosses[face, 2])
            if code == _AREA:  # the cross product itself is the unit normal times |n|
                for k in range(3):
                    _add_raw(sums[faces[face, k]], length, normal)
                continue
            x, y, z = normal[0] / length, normal[1] / length, normal[2] / length
            w0, w1, w2 = (
                face_weights(code, face_edges(corners, face - start), length)
                if code >= _ANGLE
                else (1.0, 1.0, 1.0)
            )
            _add(sums[faces[face, 0]], w0, x, y, z)
            _add(sums[faces[face, 1]], w1, x, y, z)
            _add(sums[faces[face, 2]], w2, x, y, z)


@kernel()
def _add_raw(total: FloatArray, weight: float, normal: Vector) -> None:
    """Area weighting: add n (not weight * n / |n|, which would round twice more)."""
    total[0] += normal[0]
    total[1] += normal[1]
    total[2] += normal[2]
    total[3] += weight


@kernel()
def _add(total: FloatArray, weight: float, x: float, y: float, z: float) -> None:
    total[0] += weight * x
    total[1] += weight * y
    total[2] += weight * z
    total[3] += weight


@kernel()
def normalise_kernel(sums: FloatArray, normals: FloatArray, missing: BoolArray) -> None:
    """Unit rows of ``sums[:, :3]``, or zero where they cancel against ``sums[:, 3]``.

    ``normals`` may share memory with ``sums``: row i is read before rows up to i are
    written, as (n, 3) is packed more densely than (n, 4).
    """
    for row in range(len(sums)):
        x, y, z, total = sums[row, 0], sums[row, 1], sums[row, 2], sums[row, 3]
        square = x * x + y * y + z * z
        cancel = _CANCELLED * total
        missing[row] = square <= cancel * cancel
        length = math.inf if missing[row] else math.sqrt(square)  # x / inf is an exact zero
        normals[row, 0] = x / length + 0.0  # -0.0 becomes 0.0
        normals[row, 1] = y / length + 0.0
        normals[row, 2] = z / length + 0.0


def smooth(geometry: FaceGeometry, weighting: str) -> tuple[FloatArray, BoolArray]:
    """Vertex normals and their mask, from the face geometry.

    The sums are (n, 4) and the normals are packed into the same memory as (n, 3).
    """
    code = weighting_code(weighting)
    mesh = geometry.mesh
    count = len(mesh.vertices)
    sums, spare = np.zeros((count, 4)), np.zeros((count, 4))
    announce_compiling()
    with PARALLEL_KERNELS:
        _vertex_sums_kernel(
            code,
            mesh.points,
            mesh.factor,
            mesh.faces,
            geometry.crosses,
            geometry.lengths,
            geometry.degenerate,
            sums,
            spare,
        )
    sums += spare
    del spare
    normals = sums.reshape(-1)[: 3 * count].reshape(count, 3)
    missing = np.empty(count, dtype=bool)
    normalise_kernel(sums, normals, missing)
    return normals, missing


def vertex_normals(
    vertices: MeshInput, faces: ArrayLike | None = None, weighting: Weighting = "angle"
) -> VertexNormals:
    """Return the weighted average of the face normals around each vertex.

    Parameters
    ----------
    vertices : (n, 3) float64, CheckedMesh or FaceGeometry
        Finite coordinates, or an already checked mesh or its geometry (then ``faces`` is
        None: ``vertex_normals(geometry, weighting="area")``).
    faces : (m, 3) int
        Indices into ``vertices``.
    weighting : {"uniform", "area", "angle", "max"}
        How each face's normal counts at a vertex; see the module docstring.

    Returns
    -------
    VertexNormals
        ``normals`` (n, 3) float64 and the ``missing`` (n,) bool mask, for every vertex,
        used or not.
    """
    source = checked_input(vertices, faces)
    weighting_code(weighting)  # refused before the kernels run
    return VertexNormals(*smooth(face_geometry(source), weighting))
