"""Normals and areas of the faces of a triangle mesh, in float64.

A mesh is ``vertices``, an (n, 3) array of points, and ``faces``, an (m, 3) array of indices
into it. Face ``[a, b, c]`` has the normal n = (B - A) x (C - A) of
:func:`app.core.triangle.triangle_normal`: it points to the side from which A, B, C run
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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.core.tolerances import MESH_DEGENERATE_SINE, MESH_RECOMPUTE_SINE

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]


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
    return points, _as_faces(faces, len(points))


def _as_vertices(vertices: ArrayLike) -> FloatArray:
    array = np.asarray(vertices)
    if array.size == 0 and array.ndim <= 2:
        array = array.reshape(0, 3)
    if array.dtype == np.bool_ or array.dtype.kind not in "iuf":
        raise ValueError(f"vertices must hold real numbers, not {array.dtype}.")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), not {array.shape}.")
    points = np.ascontiguousarray(array, dtype=np.float64)
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        row = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"vertices[{row}] has a coordinate that is not a finite number.")
    return points


def _as_faces(faces: ArrayLike, vertex_count: int) -> IndexArray:
    array = np.asarray(faces)
    if array.size == 0 and array.ndim <= 2:
        return np.empty((0, 3), dtype=np.intp)
    if array.dtype.kind not in "iu":
        raise ValueError(f"faces must hold integer vertex indices, not {array.dtype}.")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"faces must have shape (m, 3), not {array.shape}.")
    if array.dtype.kind == "i" and array.min() < 0:
        row, column = np.argwhere(array < 0)[0]
        raise ValueError(f"faces[{row}] has a negative vertex index, {array[row, column]}.")
    if array.max() >= vertex_count:
        row, column = np.argwhere(array >= vertex_count)[0]
        there = (f"there are only {vertex_count} vertices (indices 0 to {vertex_count - 1})"
                 if vertex_count else "there are no vertices")
        raise ValueError(f"faces[{row}] refers to vertex {array[row, column]}, but {there}.")
    return np.ascontiguousarray(array, dtype=np.intp)


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
    points, scale = _scaled(vertices)
    # Gather per axis from a contiguous column: three small random-access tables, not one big.
    columns = np.ascontiguousarray(points.T)
    corner_indices = np.ascontiguousarray(faces.T)
    edges = np.empty((3, 3, len(faces)))
    for axis in range(3):
        a, b, c = columns[axis].take(corner_indices)
        np.subtract(b, a, out=edges[axis, 0])
        np.subtract(c, b, out=edges[axis, 1])
        np.subtract(a, c, out=edges[axis, 2])
    squares = np.einsum("akm,akm->km", edges, edges)
    normal = _cross(edges[:, 2], edges[:, 0])  # at corner A: (A - C) x (B - A)
    square = _dot(normal, normal)
    # Where corner A's sine is small, redo the product at the largest corner.
    redo = np.flatnonzero(square <= MESH_RECOMPUTE_SINE**2 * squares[2] * squares[0])
    degenerate = np.zeros(len(faces), dtype=bool)
    if len(redo):
        _recompute(edges, squares, normal, square, degenerate, redo)
    length = np.sqrt(square)
    return FaceGeometry(edges, squares, normal, length, degenerate, scale)


def _scaled(vertices: FloatArray) -> tuple[FloatArray, int]:
    """Divide by a power of two (exact) so that the largest |coordinate| is in [0.5, 1).

    Products of up to four edge coordinates then neither over- nor underflow unless the
    edges are shorter than about 2**-237 (1e-71) times that coordinate. Wherever the
    unscaled values stay in the double range, scaling by a power of two changes no digit of
    any normal.
    """
    largest = float(np.abs(vertices).max(initial=0.0))
    if largest == 0.0:
        return vertices, 0
    scale = int(np.frexp(largest)[1])
    return np.ldexp(vertices, -scale), scale


def _recompute(
    edges: FloatArray,
    squares: FloatArray,
    normal: FloatArray,
    square: FloatArray,
    degenerate: BoolArray,
    rows: IndexArray,
) -> None:
    """Retake the cross product of ``rows`` at their largest corner and judge them, in place."""
    sub_edges = edges[:, :, rows]
    sub_squares = squares[:, rows]
    # The largest corner is opposite the longest edge: edge k is opposite corner k + 2.
    corner = (np.argmax(sub_squares, axis=0) + 2) % 3
    before, after = (corner + 2) % 3, corner
    pick = np.arange(len(rows))
    cross = _cross(sub_edges[:, before, pick], sub_edges[:, after, pick])
    cross_square = _dot(cross, cross)
    limit = MESH_DEGENERATE_SINE**2 * sub_squares[before, pick] * sub_squares[after, pick]
    flat = cross_square <= limit
    cross[:, flat] = 0.0
    cross_square[flat] = 0.0
    normal[:, rows] = cross
    square[rows] = cross_square
    degenerate[rows] = flat


def _cross(p: FloatArray, q: FloatArray) -> FloatArray:
    """p x q for (3, m) component arrays, written out: faster than np.cross on (m, 3)."""
    n = np.empty_like(p)
    np.multiply(p[1], q[2], out=n[0])
    n[0] -= p[2] * q[1]
    np.multiply(p[2], q[0], out=n[1])
    n[1] -= p[0] * q[2]
    np.multiply(p[0], q[1], out=n[2])
    n[2] -= p[1] * q[0]
    return n


def _dot(p: FloatArray, q: FloatArray) -> FloatArray:
    """Row-wise p . q for (3, m) component arrays."""
    total = p[0] * q[0]
    total += p[1] * q[1]
    total += p[2] * q[2]
    return total


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
    geometry = face_geometry(points, indices)
    normals = np.ascontiguousarray(unit_normals(geometry).T)
    with np.errstate(over="ignore"):
        areas = np.ldexp(geometry.length, 2 * geometry.scale - 1)
    return FaceNormals(normals, areas, geometry.degenerate)


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
