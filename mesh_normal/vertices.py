"""Vertex normals of a triangle mesh: weighted averages of its face normals.

Each corner (one vertex of one face) gives its face's unit normal a weight:

- ``"uniform"``: 1, the plain mean of the incident face normals;
- ``"area"``: the face's area (the sum of the raw cross products);
- ``"angle"``: the corner's angle (Thuermer and Wuethrich 1998), computed stably as
  ``atan2(|n|, p . q)`` for the corner's edges p and q, with the face's most accurate |n|;
- ``"max"``: sin(angle) / (|p| |q|), i.e. |p x q| / (|p|**2 |q|**2) (Nelson Max 1999,
  "Weights for computing vertex normals from facet normals"), exact when the vertex and
  its neighbours lie on a sphere.

The sums are compiled with numba (see :mod:`mesh_normal.kernels`): chunk by chunk, every core
takes the faces' weighted normals, from their :class:`~mesh_normal.faces.FaceGeometry`, and then
one thread adds them into their three vertices in face order, so the bits are the same on any
number of cores; each sum is normalised once. Degenerate faces (see
:mod:`mesh_normal.faces`) weigh nothing. A vertex in no usable face, or whose sum cancels (at
most ``MESH_CANCELLED_SUM`` of its total weight), gets a zero row and ``True`` in the
``missing`` mask; nothing is NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mesh_normal.checks import CheckedMesh, refuse_faces
from mesh_normal.choices import Weighting as Weighting
from mesh_normal.faces import FaceGeometry, MeshInput, kernel_ranged_input
from mesh_normal.kernels import (
    AHEAD,
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
    prefetch,
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


#: Faces per chunk of the sums, at most. Each chunk's terms are taken on every core (the
#: products, the weights: most of the arithmetic), then one thread adds them into the vertices
#: in face order, so each vertex's sum is added in the same order on any number of cores and
#: has the same bits. Fewer, larger chunks are faster (the terms and the sums evict each
#: other's rows from the cache between chunks: at the Dragon size, one chunk 25 ms, two 27,
#: four 32), but a chunk's terms (32 or 48 bytes a face) are kept within 1.5 times the size of
#: the normals returned (24 bytes a vertex), so that the extra memory stays under twice it.
CHUNK = 1 << 22


def chunk_faces(faces: int, vertices: int, columns: int) -> int:
    """The faces per chunk of :func:`smooth` for terms of ``columns`` doubles (see
    :data:`CHUNK`): at least a block, at most every face (and 1 for no faces)."""
    within = 36 * vertices // (8 * columns)  # 1.5 times the normals' 24 bytes a vertex
    return max(1, min(faces, max(BLOCK, min(CHUNK, within))))


@kernel(parallel=True)
def _face_terms_kernel(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    fused: bool,
    first: int,
    terms: FloatArray,
    bad: IndexArray,
    counter: IndexArray,
    workers: int,
) -> None:
    """The terms of faces ``first`` to ``first + len(terms)`` (or the last), in whole blocks
    claimed by the workers, into row ``face - first`` of ``terms``: a vector, then its weight
    (4 columns) or its corners' weights (6 columns). Where the corners are gathered, each
    index is checked as it is read (``gather``): one out of range sets
    ``bad[0]``, and the caller must not add these terms.

    ``"area"``: the cross product and its length; ``"uniform"``: the unit normal and 1.0; the
    others: the unit normal and each corner's weight. A degenerate face's row is zeros: adding
    them changes no sum (a sum that starts at 0.0 is never -0.0). ``fused``: the cross products
    are taken here, as ``geometry_kernel`` takes them, else read from ``crosses`` and
    ``lengths``; the corners are gathered where they are taken or the weights need the edges.
    """
    stop = min(first + len(terms), len(faces))
    blocks = (stop - first + BLOCK - 1) // BLOCK
    for _ in prange(workers):  # blocks write disjoint rows: any worker may take any block
        corners = np.empty((BLOCK, 9))
        block = claim(counter)
        while block < blocks:
            start = first + block * BLOCK
            if not _block_terms(
                code, points, factor, faces[:stop], crosses, lengths, degenerate, fused,
                first, start, corners, terms,
            ):  # fmt: skip
                bad[0] = 1
            block = claim(counter)


@kernel()
def _block_terms(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    fused: bool,
    first: int,
    start: int,
    corners: FloatArray,
    terms: FloatArray,
) -> bool:
    """The terms of the block of faces from ``start`` (see :func:`_face_terms_kernel`);
    False (and the block left) at an index out of range."""
    if (fused or code >= _ANGLE) and gather(points, factor, faces, start, corners) < 0:
        return False
    for face in range(start, min(start + BLOCK, len(faces))):
        row = face - first
        if fused:
            (nx, ny, nz), square, found = face_cross(face_edges(corners, face - start))
            usable = found != DEGENERATE
            length = math.sqrt(square)
        else:
            usable = not degenerate[face]
            length = lengths[face]
            nx, ny, nz = crosses[face, 0], crosses[face, 1], crosses[face, 2]
        if not usable:
            for column in range(terms.shape[1]):
                terms[row, column] = 0.0
        elif code == _AREA:  # the cross product itself is the unit normal times |n|
            # n, not weight * n / |n|, which would round twice more
            terms[row, 0], terms[row, 1], terms[row, 2], terms[row, 3] = nx, ny, nz, length
        else:
            terms[row, 0], terms[row, 1], terms[row, 2] = nx / length, ny / length, nz / length
            if code == _UNIFORM:
                terms[row, 3] = 1.0
            else:
                w0, w1, w2 = face_weights(code, face_edges(corners, face - start), length)
                terms[row, 3], terms[row, 4], terms[row, 5] = w0, w1, w2
    return True


@kernel()
def _add_terms(faces: IndexArray, first: int, terms: FloatArray, sums: FloatArray) -> None:
    """Add the terms of faces ``first`` on (see :func:`_face_terms_kernel`) into their
    vertices' rows of ``sums``, (n, 4): the weighted normal, then the weight, so that each
    corner updates one cache line. With one weight, each corner adds the vector and the
    weight as they are (area: the cross product; uniform: the unit normal, times 1.0 exactly);
    with three, the weight of its own corner times the unit normal.

    In face order, on one thread; the vertices' rows of the face ``AHEAD`` faces on are asked
    for in advance (each is a cache miss on a large mesh).
    """
    stop = min(first + len(terms), len(faces))
    shared = terms.shape[1] == 4
    for face in range(first, stop):
        ahead = face + AHEAD
        if ahead < stop:
            prefetch(sums, faces[ahead, 0])
            prefetch(sums, faces[ahead, 1])
            prefetch(sums, faces[ahead, 2])
        row = face - first
        x, y, z = terms[row, 0], terms[row, 1], terms[row, 2]
        a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
        if shared:
            w = terms[row, 3]
            _add_row(sums, a, x, y, z, w)
            _add_row(sums, b, x, y, z, w)
            _add_row(sums, c, x, y, z, w)
        else:
            w0, w1, w2 = terms[row, 3], terms[row, 4], terms[row, 5]
            _add_row(sums, a, w0 * x, w0 * y, w0 * z, w0)
            _add_row(sums, b, w1 * x, w1 * y, w1 * z, w1)
            _add_row(sums, c, w2 * x, w2 * y, w2 * z, w2)


@kernel()
def _add_row(sums: FloatArray, vertex: int, x: float, y: float, z: float, w: float) -> None:
    """``sums[vertex] += (x, y, z, w)``, element by element (a view of the row measured 13-29 %
    slower)."""
    sums[vertex, 0] += x
    sums[vertex, 1] += y
    sums[vertex, 2] += z
    sums[vertex, 3] += w


@kernel()
def normalise_kernel(sums: FloatArray, normals: FloatArray, missing: BoolArray) -> None:
    """Unit rows of ``sums[:, :3]``, or zero where they cancel against ``sums[:, 3]``.

    ``normals`` may share memory with ``sums``: row i is read before rows up to i are
    written, as (n, 3) is packed more densely than (n, 4). (Into the same memory, on one
    core: measured at the Lucy size, a separate (n, 3) array normalised on two cores took
    longer, its fresh memory costing more than the second core saved.)
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


def smooth(geometry: FaceGeometry | CheckedMesh, weighting: str) -> tuple[FloatArray, BoolArray]:
    """Vertex normals and their mask, from the face geometry, or from a checked mesh whose
    cross products are taken as they are needed (the same bits, none of them kept).

    Chunk by chunk, the faces' terms are taken on every core and then added in face order
    (:data:`CHUNK`). The sums are (n, 4) and the normals are packed into the same memory as
    (n, 3).
    """
    code = weighting_code(weighting)
    if isinstance(geometry, FaceGeometry):
        mesh, fused = geometry.mesh, False
        crosses, lengths, degenerate = geometry.crosses, geometry.lengths, geometry.degenerate
    else:
        mesh, fused = geometry, True
        crosses, lengths, degenerate = _NO_CROSSES, _NO_LENGTHS, _NO_FLAGS
    count, faces = len(mesh.vertices), mesh.faces
    sums = np.zeros((count, 4))
    columns = 6 if code >= _ANGLE else 4
    chunk = chunk_faces(len(faces), count, columns)
    terms = np.empty((chunk, columns))
    bad = np.zeros(1, dtype=np.int64)
    announce_compiling()
    with PARALLEL_KERNELS:
        for first in range(0, len(faces), chunk):
            _face_terms_kernel(
                code, mesh.points, mesh.factor, faces, crosses, lengths, degenerate, fused,
                first, terms, bad, *workers(),
            )  # fmt: skip
            if bad[0]:  # raw faces, whose range was left to this check
                break
            _add_terms(faces, first, terms, sums)
    if bad[0]:
        refuse_faces(faces, count)
    normals = sums.reshape(-1)[: 3 * count].reshape(count, 3)
    missing = np.empty(count, dtype=bool)
    normalise_kernel(sums, normals, missing)
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
    source = kernel_ranged_input(vertices, faces)  # the terms' kernel checks the indices
    weighting_code(weighting)  # refused before the kernels run
    return VertexNormals(*smooth(source, weighting))
