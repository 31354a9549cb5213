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

import numpy as np
from numpy.typing import ArrayLike

from mesh_normal.checks import CheckedMesh
from mesh_normal.choices import Weighting as Weighting
from mesh_normal.faces import FaceGeometry, MeshInput, checked_input
from mesh_normal.kernels import (
    BLOCK,
    DEGENERATE,
    PARALLEL_KERNELS,
    announce_compiling,
    claim,
    dot,
    face_cross,
    face_edges,
    gather,
    kernel,
    prange,
    workers,
)
from mesh_normal.tolerances import MESH_CANCELLED_SUM
from mesh_normal.types import BoolArray, Edges, FloatArray, IndexArray, Vector

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


#: The faces are summed in two halves (in whole blocks), each into its own (n, 4) buffer, and
#: the buffers are added in a fixed order: the result has the same bits on every machine,
#: whatever its number of cores. The halves are two tasks that the workers claim (see
#: :func:`mesh_normal.kernels.claim`): one thread alone, or a second one late, takes both.
_HALVES = 2


@kernel(parallel=True)
def _vertex_sums_kernel(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    fused: bool,
    sums: FloatArray,
    spare: FloatArray,
    counter: IndexArray,
    workers: int,
) -> None:
    """Add each usable face's weighted unit normal and its weight into its vertices' rows.

    ``sums`` and ``spare`` are (n, 4) zeros: the sum of weighted normals and the sum of
    weights side by side, so that each corner updates one cache line. The first half of the
    faces (in whole blocks) goes into ``sums``, the rest into ``spare``. ``fused``: the cross
    products are taken here, as ``geometry_kernel`` takes them (``crosses``, ``lengths`` and
    ``degenerate`` are not read), else they are read from those arrays.
    """
    half = (len(faces) + 2 * BLOCK - 1) // (2 * BLOCK) * BLOCK
    for _ in prange(min(workers, _HALVES)):
        task = claim(counter)
        while task < _HALVES:
            first, stop, into = (0, half, sums) if task == 0 else (half, len(faces), spare)
            _accumulate(
                code, points, factor, faces, crosses, lengths, degenerate, fused, first, stop, into
            )
            task = claim(counter)


@kernel()
def _accumulate(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    fused: bool,
    first: int,
    stop: int,
    sums: FloatArray,
) -> None:
    """The sums of faces ``first`` to ``stop`` (``first`` a multiple of the block size).

    The corners are gathered where the products are taken here or the weights need the
    edges (angle, max). The adds are written out: a view per corner (``sums[v]``) measured
    13-29 % slower.
    """
    corners = np.empty((BLOCK, 9))
    stop = min(stop, len(faces))  # the first half may be rounded up past the end
    for start in range(first, stop, BLOCK):
        if fused or code >= _ANGLE:
            gather(points, factor, faces[:stop], start, corners)
        for face in range(start, min(start + BLOCK, stop)):
            if fused:
                (nx, ny, nz), square, found = face_cross(face_edges(corners, face - start))
                if found == DEGENERATE:
                    continue
                length = math.sqrt(square)
            else:
                if degenerate[face]:
                    continue
                length = lengths[face]
                nx, ny, nz = crosses[face, 0], crosses[face, 1], crosses[face, 2]
            a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
            if code == _AREA:  # the cross product itself is the unit normal times |n|
                # n, not weight * n / |n|, which would round twice more
                sums[a, 0] += nx
                sums[a, 1] += ny
                sums[a, 2] += nz
                sums[a, 3] += length
                sums[b, 0] += nx
                sums[b, 1] += ny
                sums[b, 2] += nz
                sums[b, 3] += length
                sums[c, 0] += nx
                sums[c, 1] += ny
                sums[c, 2] += nz
                sums[c, 3] += length
                continue
            x, y, z = nx / length, ny / length, nz / length
            w0, w1, w2 = (
                face_weights(code, face_edges(corners, face - start), length)
                if code >= _ANGLE
                else (1.0, 1.0, 1.0)
            )
            sums[a, 0] += w0 * x
            sums[a, 1] += w0 * y
            sums[a, 2] += w0 * z
            sums[a, 3] += w0
            sums[b, 0] += w1 * x
            sums[b, 1] += w1 * y
            sums[b, 2] += w1 * z
            sums[b, 3] += w1
            sums[c, 0] += w2 * x
            sums[c, 1] += w2 * y
            sums[c, 2] += w2 * z
            sums[c, 3] += w2


@kernel()
def _normalise(
    sums: FloatArray, spare: FloatArray, halves: bool, normals: FloatArray, missing: BoolArray
) -> None:
    """Unit rows of ``sums[:, :3]`` (plus ``spare``'s, added row by row, if ``halves``), or
    zero where they cancel against their fourth column; see :func:`normalise_kernel`."""
    for row in range(len(sums)):
        x, y, z, total = sums[row, 0], sums[row, 1], sums[row, 2], sums[row, 3]
        if halves:  # the same bits as ``sums += spare`` first, without that pass
            x, y, z, total = (
                x + spare[row, 0],
                y + spare[row, 1],
                z + spare[row, 2],
                total + spare[row, 3],
            )
        square = x * x + y * y + z * z
        cancel = _CANCELLED * total
        missing[row] = square <= cancel * cancel
        length = math.inf if missing[row] else math.sqrt(square)  # x / inf is an exact zero
        normals[row, 0] = x / length + 0.0  # -0.0 becomes 0.0
        normals[row, 1] = y / length + 0.0
        normals[row, 2] = z / length + 0.0


def normalise_kernel(sums: FloatArray, normals: FloatArray, missing: BoolArray) -> None:
    """Unit rows of ``sums[:, :3]``, or zero where they cancel against ``sums[:, 3]``.

    ``normals`` may share memory with ``sums``: row i is read before rows up to i are
    written, as (n, 3) is packed more densely than (n, 4).
    """
    _normalise(sums, sums, False, normals, missing)


def smooth(geometry: FaceGeometry | CheckedMesh, weighting: str) -> tuple[FloatArray, BoolArray]:
    """Vertex normals and their mask, from the face geometry, or from a checked mesh in one
    pass that takes the cross products as it goes (the same bits, none of them kept).

    The sums are (n, 4) and the normals are packed into the same memory as (n, 3).
    """
    code = weighting_code(weighting)
    if isinstance(geometry, FaceGeometry):
        mesh, fused = geometry.mesh, False
        crosses, lengths, degenerate = geometry.crosses, geometry.lengths, geometry.degenerate
    else:
        mesh, fused = geometry, True
        crosses, lengths, degenerate = _NO_CROSSES, _NO_LENGTHS, _NO_FLAGS
    count = len(mesh.vertices)
    sums, spare = np.zeros((count, 4)), np.zeros((count, 4))
    announce_compiling()
    with PARALLEL_KERNELS:
        _vertex_sums_kernel(
            code,
            mesh.points,
            mesh.factor,
            mesh.faces,
            crosses,
            lengths,
            degenerate,
            fused,
            sums,
            spare,
            *workers(),
        )
    normals = sums.reshape(-1)[: 3 * count].reshape(count, 3)
    missing = np.empty(count, dtype=bool)
    _normalise(sums, spare, True, normals, missing)
    return normals, missing


#: What the fused pass is given for the arrays it does not read (the types of a geometry's).
_NO_CROSSES, _NO_LENGTHS = np.empty((0, 3)), np.empty(0)
_NO_FLAGS = np.empty(0, dtype=bool)


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
    return VertexNormals(*smooth(source, weighting))
