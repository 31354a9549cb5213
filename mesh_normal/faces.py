"""Normals and areas of the faces of a triangle mesh, in float64.

A mesh is ``vertices``, an (n, 3) array of points, and ``faces``, an (m, 3) array of indices
into it. Face ``[a, b, c]`` has the normal n = (B - A) x (C - A) of
:func:`mesh_normal.triangle.triangle_normal`: it points to the side from which A, B, C run
counter-clockwise, |n| is twice the face's area, and reversing the face negates it.

Precision. The cross product is a float64 product of edges (each a correctly rounded
difference), so it is within about 6 eps |p| |q| of the exact one, where p and q are the two
edges it was taken from and eps = 2**-53. It is first taken at corner A; where the sine of
that angle is small (``MESH_RECOMPUTE_SINE``) it is taken again at the face's largest
corner, between its two shortest edges, where that error is smallest. A needle (one tiny
angle) therefore keeps an accurate normal, and only a flat sliver loses it.

Degenerate faces. A face is degenerate when the sine of its largest corner angle is at most
``MESH_DEGENERATE_SINE`` (2**-37): its normal is then rounding noise. This covers repeated
indices, coincident points and collinear points. The test is relative (|n| against |p| |q|),
so it gives the same verdict in any unit, unlike an absolute threshold on |n|. Degenerate
faces get a zero normal, a zero area and ``True`` in the ``degenerate`` mask. Arrays are
always full length, in input order, and never NaN.

The vertices are first scaled by a power of two (exact) so that the largest |coordinate| is
about 1: only edges shorter than about 1e-71 times that coordinate then underflow (such faces
count as degenerate), and only areas beyond the double range (coordinates beyond about 1e154)
are infinite; nothing else overflows.

Compiled kernels. The per-face work is one loop compiled with numba (``@njit(cache=True)``:
compiled on first use, about 5 s once, then loaded from the cache; ``NUMBA_CACHE_DIR`` moves
the cache). It is the only implementation: NumPy alone measured 3-5 times slower than
Open3D, whose times are the target (see the README's mesh kernels section). So this part of
``mesh_normal`` is not pure NumPy. ``error_model="numpy"`` drops Python's zero-division checks
(no division here can be by zero, and IEEE rules apply); the face normals run their blocks
of faces on every core (``parallel=True``: blocks write disjoint rows, so the bits do not
depend on the number of cores).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from mesh_normal.tolerances import MESH_DEGENERATE_SINE, MESH_RECOMPUTE_SINE

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]
Vector = tuple[float, float, float]
Edges = tuple[Vector, Vector, Vector]


def check_mesh(vertices: ArrayLike, faces: ArrayLike) -> tuple[FloatArray, IndexArray]:
    """Convert and check a mesh up front, with a clear ``ValueError`` for the first problem.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates (any real dtype; converted to float64).
    faces : (m, 3) int
        Indices into ``vertices``, each in ``0 .. n - 1`` (any integer dtype).

    Returns
    -------
    vertices : (n, 3) float64
        C-contiguous; the input itself when it already is.
    faces : (m, 3) intp
        C-contiguous.
    """
    points = _as_vertices(vertices)
    return points, check_faces(faces, len(points))


def _as_vertices(vertices: ArrayLike) -> FloatArray:
    array = np.asarray(vertices)
    if array.size == 0 and array.ndim <= 2:
        array = array.reshape(0, 3)
    if array.dtype == np.bool_ or array.dtype.kind not in "iuf":
        raise ValueError(f"vertices must hold real numbers, not {array.dtype}.")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), not {array.shape}.")
    points = np.ascontiguousarray(array, dtype=np.float64)
    if not np.isfinite(points).all():  # .all(axis=1) first would take 25 times longer
        row = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise ValueError(f"vertices[{row}] has a coordinate that is not a finite number.")
    return points


def check_faces(faces: ArrayLike, vertex_count: int) -> IndexArray:
    """Convert and check faces alone, for ``vertex_count`` vertices (see :func:`check_mesh`).

    Parameters
    ----------
    faces : (m, 3) int
        Indices, each in ``0 .. vertex_count - 1`` (any integer dtype).
    vertex_count : int
        n, the number of vertices.

    Returns
    -------
    (m, 3) intp
        C-contiguous.
    """
    array = np.asarray(faces)
    if array.size == 0 and array.ndim <= 2:
        return np.empty((0, 3), dtype=np.intp)
    if array.dtype.kind not in "iu":
        raise ValueError(f"faces must hold integer vertex indices, not {array.dtype}.")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"faces must have shape (m, 3), not {array.shape}.")
    # One compiled pass for the usual dtype instead of two NumPy reductions.
    low, high = _index_range(array) if array.dtype == np.intp else (array.min(), array.max())
    if low < 0:
        row, column = np.argwhere(array < 0)[0]
        raise ValueError(f"faces[{row}] has a negative vertex index, {array[row, column]}.")
    if high >= vertex_count:
        row, column = np.argwhere(array >= vertex_count)[0]
        there = (
            f"there are only {vertex_count} vertices (indices 0 to {vertex_count - 1})"
            if vertex_count
            else "there are no vertices"
        )
        raise ValueError(f"faces[{row}] refers to vertex {array[row, column]}, but {there}.")
    return np.ascontiguousarray(array, dtype=np.intp)


@njit(cache=True, error_model="numpy")
def _index_range(faces: IndexArray) -> tuple[int, int]:
    low, high = 0, 0
    for index in faces.ravel():
        low, high = min(low, index), max(high, index)
    return low, high


@dataclass(frozen=True, slots=True)
class FaceNormals:
    """Full-length results for ``m`` faces, in input order.

    Attributes
    ----------
    normals : (m, 3) float64
        Unit normals; zero rows where ``degenerate``.
    areas : (m,) float64
        Areas, |(B - A) x (C - A)| / 2; zero where ``degenerate``.
    degenerate : (m,) bool
        The face has no usable normal (see the module docstring).
    """

    normals: FloatArray
    areas: FloatArray
    degenerate: BoolArray

    def __len__(self) -> int:
        return len(self.areas)


@dataclass(frozen=True, slots=True)
class FaceGeometry:
    """What the vertex and corner normals need of each face, component by component.

    All lengths are of the vertices scaled by ``2**-scale`` (exact), so that nothing
    over- or underflows; directions and angles are unaffected.

    Attributes
    ----------
    edges : (3, 3, m) float64
        ``edges[axis, k]``: component ``axis`` of the edge from corner k to corner k + 1
        (B - A, C - B, A - C). Corner k lies between edges k - 1 and k.
    squares : (3, m) float64
        Squared lengths of the three edges.
    normal : (3, m) float64
        (B - A) x (C - A), from the corner where it is most accurate; zero where degenerate.
    length : (m,) float64
        |normal|, twice the (scaled) area.
    degenerate : (m,) bool
        As :attr:`FaceNormals.degenerate`.
    scale : int
        The power of two the vertices were divided by.
    """

    edges: FloatArray
    squares: FloatArray
    normal: FloatArray
    length: FloatArray
    degenerate: BoolArray
    scale: int


def face_geometry(vertices: FloatArray, faces: IndexArray) -> FaceGeometry:
    """Edges, cross products and degenerate flags of checked arrays (see :func:`check_mesh`).

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
    faces : (m, 3) intp
        Indices in range.

    Returns
    -------
    FaceGeometry
        Component-major arrays, in face order.
    """
    points, factor, scale = scaling(vertices)
    count = len(faces)
    edges, squares, normal = np.empty((3, 3, count)), np.empty((3, count)), np.empty((3, count))
    length, degenerate = np.empty(count), np.empty(count, dtype=bool)
    _geometry_kernel(points, factor, faces, edges, squares, normal, length, degenerate)
    return FaceGeometry(edges, squares, normal, length, degenerate, scale)


def scaling(vertices: FloatArray) -> tuple[FloatArray, float, int]:
    """The power of two 2**scale that brings the largest |coordinate| into [0.5, 1).

    Products of up to four edge coordinates then neither over- nor underflow unless the
    edges are shorter than about 2**-237 (1e-71) times that coordinate. Wherever the
    unscaled values stay in the double range, scaling by a power of two changes no digit of
    any normal. The kernels multiply each coordinate they read by ``factor`` = 2**-scale,
    which rounds exactly as ``ldexp`` does; only when that factor is not a double (all
    coordinates below 2**-1022) are the points scaled here, into a copy.
    """
    largest = float(np.abs(vertices).max(initial=0.0))
    if largest == 0.0:
        return vertices, 1.0, 0
    scale = math.frexp(largest)[1]
    if scale < -1000:
        return np.ldexp(vertices, -scale), 1.0, scale
    return vertices, math.ldexp(1.0, -scale), scale


# The compiled kernels. Each goes through the faces in blocks: it first copies the scaled
# corners of a block of faces (independent loads, so their cache misses overlap), then
# does what the module docstring says for each face, through face_edges and face_cross.
# Constants are frozen at compile time.
_BLOCK = 512

#: Held while a parallel kernel runs. numba's thread pools (its "workqueue" layer, the one
#: left where neither OpenMP nor TBB is installed) abort the process when two threads launch
#: parallel work at once; the web server calls the kernels from several worker threads.
PARALLEL_KERNELS = threading.Lock()
_RECOMPUTE = MESH_RECOMPUTE_SINE**2
_DEGENERATE = MESH_DEGENERATE_SINE**2


@njit(cache=True, error_model="numpy")
def gather(
    points: FloatArray, factor: float, faces: IndexArray, start: int, corners: FloatArray
) -> int:
    """Copy A, B, C of faces ``start`` on, times ``factor``, into the rows of ``corners``.

    ``corners`` is (block, 9); returns how many rows were filled.
    """
    count = min(len(corners), len(faces) - start)
    for row in range(count):
        for k in range(3):
            vertex = faces[start + row, k]
            corners[row, 3 * k] = points[vertex, 0] * factor
            corners[row, 3 * k + 1] = points[vertex, 1] * factor
            corners[row, 3 * k + 2] = points[vertex, 2] * factor
    return count


@njit(cache=True, error_model="numpy")
def _dot(p: Vector, q: Vector) -> float:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


@njit(cache=True, error_model="numpy")
def _cross(p: Vector, q: Vector) -> Vector:
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


@njit(cache=True, error_model="numpy")
def face_edges(corners: FloatArray, row: int) -> Edges:
    """The edges B - A, C - B, A - C of one face: corner k lies between edges k - 1 and k."""
    ax, ay, az = corners[row, 0], corners[row, 1], corners[row, 2]
    bx, by, bz = corners[row, 3], corners[row, 4], corners[row, 5]
    cx, cy, cz = corners[row, 6], corners[row, 7], corners[row, 8]
    return (bx - ax, by - ay, bz - az), (cx - bx, cy - by, cz - bz), (ax - cx, ay - cy, az - cz)


@njit(cache=True, error_model="numpy")
def face_cross(edges: Edges) -> tuple[Vector, float, bool]:
    """(B - A) x (C - A) from its most accurate corner, its squared length, and the verdict.

    The product is taken at corner A; if that corner's sine is small, again at the largest
    corner (opposite the longest edge, edge k being opposite corner k + 2). There a sine
    of at most ``MESH_DEGENERATE_SINE`` makes the face degenerate: zero normal, ``True``.
    """
    normal = _cross(edges[2], edges[0])
    square = _dot(normal, normal)
    if square > _RECOMPUTE * _dot(edges[2], edges[2]) * _dot(edges[0], edges[0]):
        return normal, square, False
    e0, e1, e2 = edges
    s0, s1, s2 = _dot(e0, e0), _dot(e1, e1), _dot(e2, e2)
    # The two edges after the longest, by name: a tuple indexed at run time is slow.
    if s0 >= s1 and s0 >= s2:
        p, q, sp, sq = e1, e2, s1, s2
    elif s1 >= s2:
        p, q, sp, sq = e2, e0, s2, s0
    else:
        p, q, sp, sq = e0, e1, s0, s1
    normal = _cross(p, q)
    square = _dot(normal, normal)
    if square <= _DEGENERATE * sp * sq:
        return (0.0, 0.0, 0.0), 0.0, True
    return normal, square, False


@njit(cache=True, error_model="numpy", parallel=True)
def _face_normals_kernel(
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    normals: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
) -> None:
    blocks = (len(faces) + _BLOCK - 1) // _BLOCK
    for block in prange(blocks):  # blocks write disjoint rows: they run on every core
        corners = np.empty((_BLOCK, 9))
        start = block * _BLOCK
        for row in range(gather(points, factor, faces, start, corners)):
            face = start + row
            (x, y, z), square, flat = face_cross(face_edges(corners, row))
            length = math.sqrt(square)
            divisor = 1.0 if flat else length
            normals[face, 0] = x / divisor + 0.0  # -0.0 becomes 0.0
            normals[face, 1] = y / divisor + 0.0
            normals[face, 2] = z / divisor + 0.0
            lengths[face] = length
            degenerate[face] = flat


@njit(cache=True, error_model="numpy")
def _geometry_kernel(
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    edges: FloatArray,
    squares: FloatArray,
    normal: FloatArray,
    length: FloatArray,
    degenerate: BoolArray,
) -> None:
    corners = np.empty((_BLOCK, 9))
    for start in range(0, len(faces), _BLOCK):
        for row in range(gather(points, factor, faces, start, corners)):
            face = start + row
            sides = face_edges(corners, row)
            cross, square, flat = face_cross(sides)
            for k in range(3):  # a tuple indexed in a loop is slow, but this is not hot
                for axis in range(3):
                    edges[axis, k, face] = sides[k][axis]
                squares[k, face] = _dot(sides[k], sides[k])
                normal[k, face] = cross[k]
            length[face] = math.sqrt(square)
            degenerate[face] = flat


def take_rows(array: FloatArray, index: IndexArray) -> FloatArray:
    """``array[index]`` for a C-contiguous (k, 3) float64 array, several times faster.

    Parameters
    ----------
    array : (k, 3) float64
        C-contiguous.
    index : (...) intp
        Row numbers in range.

    Returns
    -------
    (..., 3) float64
        The rows, copied whole: each row is viewed as one 24-byte item for ``take``.
    """
    rows = array.view(np.dtype((np.void, 24))).reshape(len(array))
    return rows.take(index).view(np.float64).reshape(*np.shape(index), 3)


def unit_normals(geometry: FaceGeometry) -> FloatArray:
    """The unit normal of each face, component-major.

    Parameters
    ----------
    geometry : FaceGeometry
        From :func:`face_geometry`.

    Returns
    -------
    (3, m) float64
        ``normal / length``; zero columns where degenerate.
    """
    divisor = np.where(geometry.degenerate, 1.0, geometry.length)
    unit = geometry.normal / divisor
    unit += 0.0  # -0.0 becomes 0.0, as in the exact single-triangle path
    return unit


def face_normals(vertices: ArrayLike, faces: ArrayLike) -> FaceNormals:
    """Return the unit normal and the area of every face.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
    faces : (m, 3) int
        Indices into ``vertices``; face ``[a, b, c]`` has the normal (B - A) x (C - A).

    Returns
    -------
    FaceNormals
        ``normals`` (m, 3) float64, ``areas`` (m,) float64 and the ``degenerate`` (m,) bool
        mask, in input order; zero rows where degenerate.

    Examples
    --------
    >>> face_normals([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).normals
    array([[0., 0., 1.]])
    """
    points, indices = check_mesh(vertices, faces)
    points, factor, scale = scaling(points)
    count = len(indices)
    normals, areas, degenerate = np.empty((count, 3)), np.empty(count), np.empty(count, dtype=bool)
    with PARALLEL_KERNELS:
        _face_normals_kernel(points, factor, indices, normals, areas, degenerate)
    with np.errstate(over="ignore"):
        np.ldexp(areas, 2 * scale - 1, out=areas)
    return FaceNormals(normals, areas, degenerate)


def face_areas(vertices: ArrayLike, faces: ArrayLike) -> FloatArray:
    """Return the area of every face.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
    faces : (m, 3) int
        Indices into ``vertices``.

    Returns
    -------
    (m,) float64
        |(B - A) x (C - A)| / 2, in input order; zero for degenerate faces.
    """
    return face_normals(vertices, faces).areas
