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
takes the faces' weighted normals, from their :class:`~mesh_normal.faces.FaceGeometry`, while
one thread adds the chunks already taken into their three vertices in face order, so the bits
are the same on any number of cores; each sum is normalised once. Degenerate faces (see
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
    bump,
    claim,
    dot,
    face_cross,
    face_edges,
    gather,
    kernel,
    peek,
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


#: Faces per chunk of the sums. The workers take the terms of a chunk's blocks (the products,
#: the weights: most of the arithmetic) while one of them adds the chunks already taken into
#: their vertices, in face order, so each vertex's sum is added in the same order on any number
#: of cores and has the same bits (:func:`_sums_kernel`). This takes about a third off the
#: area-weighted sums, against taking each chunk's terms on every core and then adding them on
#: one (16, 64 and 256 blocks a chunk are alike; 256 with 3 slots is slower).
CHUNK = 64 * BLOCK
#: Chunks whose terms are held at once: the workers run up to three chunks ahead of the adder.
#: The terms of ``SLOTS * CHUNK`` faces (32 or 48 bytes a face: 6 MiB at most) are all the
#: memory the sums take beyond their own.
SLOTS = 4


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
    """The terms of the block of faces from ``start`` into row ``face - first`` of ``terms``:
    a vector, then its weight (4 columns) or its corners' weights (6 columns); False (and the
    block left) at an index out of range. Where the corners are gathered, each index is
    checked as it is read (``gather``).

    ``"area"``: the cross product and its length; ``"uniform"``: the unit normal and 1.0; the
    others: the unit normal and each corner's weight. A degenerate face's row is zeros: adding
    them changes no sum (a sum that starts at 0.0 is never -0.0). ``fused``: the cross products
    are taken here, as ``geometry_kernel`` takes them, else read from ``crosses`` and
    ``lengths``; the corners are gathered where they are taken or the weights need the edges.
    """
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


@kernel(parallel=True)
def _sums_kernel(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    fused: bool,
    terms: FloatArray,
    chunk: int,
    sums: FloatArray,
    progress: IndexArray,
    bad: IndexArray,
    workers: int,
) -> None:
    """Every vertex's sum, chunk by chunk of ``chunk`` faces: the workers take the terms of a
    chunk's blocks (:func:`_block_terms`) into one of the ``len(terms) // chunk`` slots of
    ``terms``, and one of them, the adder, adds each chunk's terms into ``sums`` in face order
    (:func:`_add_terms`) as soon as all its blocks are written, while the others go on to the
    next chunks' terms. The adder takes terms too when it waits for none.

    ``progress`` (int64, zeros, 2 + 2 chunks): the ticket that makes the first worker the
    adder, the number of chunks added, then each chunk's next block to take and its blocks
    written. A worker takes a chunk's blocks only once the chunk that last used its slot has
    been added. An index out of range sets ``bad[0]`` (the sums are then not to be used).
    """
    count = len(faces)
    chunks = (count + chunk - 1) // chunk
    slots = len(terms) // chunk
    added = progress[1:2]
    for _ in prange(workers):
        corners = np.empty((BLOCK, 9))
        adder = claim(progress[0:1]) == 0
        for c in range(chunks):
            first = c * chunk
            stop = min(first + chunk, count)
            blocks = (stop - first + BLOCK - 1) // BLOCK
            at = (c % slots) * chunk
            slot = terms[at : at + chunk]
            taken = progress[2 + c : 3 + c]
            written = progress[2 + chunks + c : 3 + chunks + c]
            while peek(added) < c - slots + 1:  # the slot's last chunk is still being added
                pass
            block = claim(taken)
            while block < blocks:
                start = first + block * BLOCK
                if not _block_terms(
                    code, points, factor, faces[:stop], crosses, lengths, degenerate, fused,
                    first, start, corners, slot,
                ):  # fmt: skip
                    bad[0] = 1
                bump(written)
                block = claim(taken)
            if adder:
                while peek(written) < blocks:  # another worker's last blocks of the chunk
                    pass
                if bad[0] == 0:
                    _add_terms(faces[:stop], first, slot, sums)
                bump(added)


@kernel()
def _add_terms(faces: IndexArray, first: int, terms: FloatArray, sums: FloatArray) -> None:
    """Add the terms of faces ``first`` on (see :func:`_block_terms`) into their
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
    """``sums[vertex] += (x, y, z, w)``, element by element (through a view of the row it is
    slower)."""
    sums[vertex, 0] += x
    sums[vertex, 1] += y
    sums[vertex, 2] += z
    sums[vertex, 3] += w


@kernel()
def _normalise_row(sums: FloatArray, row: int) -> tuple[float, float, float, bool]:
    """Row ``row`` of ``sums`` as :func:`normalise_kernel` writes it: the unit normal (zero
    where it cancels) and whether it is missing."""
    x, y, z, total = sums[row, 0], sums[row, 1], sums[row, 2], sums[row, 3]
    square = x * x + y * y + z * z
    cancel = _CANCELLED * total
    missing = square <= cancel * cancel
    length = math.inf if missing else math.sqrt(square)  # x / inf is an exact zero
    return x / length + 0.0, y / length + 0.0, z / length + 0.0, missing  # -0.0 becomes 0.0


@kernel()
def normalise_kernel(sums: FloatArray, normals: FloatArray, missing: BoolArray) -> None:
    """Unit rows of ``sums[:, :3]``, or zero where they cancel against ``sums[:, 3]``.

    ``normals`` may share memory with ``sums``: row i is read before rows up to i are
    written, as (n, 3) is packed more densely than (n, 4). (Into the same memory, on one
    core: on a large mesh a separate (n, 3) array normalised on two cores takes longer, its
    fresh memory costing more than the second core saves; many rows are
    normalised on every core into the same memory by :func:`normalise_packed_kernel`.)
    """
    for row in range(len(sums)):
        normals[row, 0], normals[row, 1], normals[row, 2], missing[row] = _normalise_row(sums, row)


@kernel()
def last_block_under(stop: int, size: int) -> int:
    """The block (of ``size`` rows) of the last sums row that the packed rows before ``stop``
    lie over: packed row i takes bytes 24 i to 24 i + 23 of the memory, sums row j bytes 32 j to
    32 j + 31, so the byte 24 stop - 1 lies in sums row (24 stop - 1) // 32 = (3 stop - 1) // 4."""
    return (3 * stop - 1) // 4 // size


#: Rows per task of :func:`normalise_packed_kernel` (512 KiB of sums), and from how many rows
#: it is used instead of :func:`normalise_kernel`.
PACK_BLOCK = 1 << 14
PACK_FROM = 4 * PACK_BLOCK


@kernel(parallel=True)
def normalise_packed_kernel(
    sums: FloatArray,
    packed: FloatArray,
    missing: BoolArray,
    read: IndexArray,
    size: int,
    counter: IndexArray,
    workers: int,
) -> None:
    """:func:`normalise_kernel` into ``packed``, the first ``3 * len(sums)`` doubles of the
    memory of ``sums`` seen as (n, 3), on every core, block by block of ``size`` rows.

    A worker claims the next block, normalises its rows into a buffer of its own and marks
    the block read (``read``, one flag a block); it then writes the buffer into the block's
    packed rows once every block whose sums those rows overwrite has been read. The packed
    rows of block b lie over the sums of rows up to 3/4 of the block's end: blocks before b,
    claimed before it and never waiting to be read, or b itself, already in the buffer. The
    bits are :func:`normalise_kernel`'s; each row's arithmetic is the same.
    """
    count = len(sums)
    blocks = (count + size - 1) // size
    for _ in prange(workers):
        rows = np.empty((size, 3))
        known = 0  # the blocks before this one are known to be read
        block = claim(counter)
        while block < blocks:
            first = block * size
            stop = min(first + size, count)
            for row in range(first, stop):
                x, y, z, gone = _normalise_row(sums, row)
                rows[row - first, 0], rows[row - first, 1], rows[row - first, 2] = x, y, z
                missing[row] = gone
            bump(read[block : block + 1])
            needed = min(last_block_under(stop, size), block - 1)  # this one is in ``rows``
            while known <= needed:
                while peek(read[known : known + 1]) == 0:
                    pass
                known += 1
            for row in range(first, stop):
                packed[row, 0] = rows[row - first, 0]
                packed[row, 1] = rows[row - first, 1]
                packed[row, 2] = rows[row - first, 2]
            block = claim(counter)


def smooth(geometry: FaceGeometry | CheckedMesh, weighting: str) -> tuple[FloatArray, BoolArray]:
    """Vertex normals and their mask, from the face geometry, or from a checked mesh whose
    cross products are taken as they are needed (the same bits, none of them kept).

    Chunk by chunk, the faces' terms are taken on every core while one of them adds the
    chunks taken in face order (:data:`CHUNK`, :func:`_sums_kernel`). The sums are (n, 4) and
    the normals are packed into the same memory as (n, 3).
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
    bad = np.zeros(1, dtype=np.int64)
    announce_compiling()
    chunk = max(1, min(len(faces), CHUNK))
    terms = np.empty((SLOTS * chunk, columns))
    progress = np.zeros(2 + 2 * ((len(faces) + chunk - 1) // chunk), dtype=np.int64)
    with PARALLEL_KERNELS:
        _sums_kernel(
            code, mesh.points, mesh.factor, faces, crosses, lengths, degenerate, fused, terms,
            chunk, sums, progress, bad, workers()[1],
        )  # fmt: skip
    if bad[0]:
        refuse_faces(faces, count)
    normals = sums.reshape(-1)[: 3 * count].reshape(count, 3)
    missing = np.empty(count, dtype=bool)
    if count < PACK_FROM:
        normalise_kernel(sums, normals, missing)
    else:
        read = np.zeros((count + PACK_BLOCK - 1) // PACK_BLOCK, dtype=np.int64)
        with PARALLEL_KERNELS:
            normalise_packed_kernel(sums, normals, missing, read, PACK_BLOCK, *workers())
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
    weighting : {"angle", "area", "uniform", "max"}
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
