"""Vertex and corner normals of a triangle mesh: weighted averages of its face normals.

Each corner (one vertex of one face) gives its face's unit normal a weight:

- ``"uniform"``: 1, the plain mean of the incident face normals;
- ``"area"``: the face's area (the sum of the raw cross products);
- ``"angle"``: the corner's angle (Thuermer and Wuethrich 1998), computed stably as
  ``atan2(|n|, p . q)`` for the corner's edges p and q, with the face's most accurate |n|;
- ``"max"``: sin(angle) / (|p| |q|), i.e. |p x q| / (|p|**2 |q|**2) (Nelson Max 1999,
  "Weights for computing vertex normals from facet normals"), exact when the vertex and
  its neighbours lie on a sphere.

The sums are one pass over the faces compiled with numba (see :mod:`mesh_normal.faces`) that
adds each face's weighted normal into its three vertices; each sum is normalised once.
Degenerate faces (see :mod:`mesh_normal.faces`) weigh nothing. A vertex in no usable face, or
whose sum cancels (at most ``MESH_CANCELLED_SUM`` of its total weight), gets a zero row and
``True`` in the ``missing`` mask; nothing is NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real
from typing import Literal

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from mesh_normal.faces import (
    _BLOCK,
    PARALLEL_KERNELS,
    Edges,
    FaceGeometry,
    Vector,
    _dot,
    check_mesh,
    face_cross,
    face_edges,
    face_geometry,
    face_normals,
    gather,
    scaling,
    take_rows,
    unit_normals,
)
from mesh_normal.tolerances import MESH_CANCELLED_SUM, MESH_CREASE_SLACK, MESH_PAIR_CHUNK
from mesh_normal.topology import VertexCorners, vertex_corners

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]
Weighting = Literal["uniform", "area", "angle", "max"]

WEIGHTINGS: tuple[Weighting, ...] = ("uniform", "area", "angle", "max")
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


@dataclass(frozen=True, slots=True)
class CornerNormals:
    """One normal for each corner of each of ``m`` faces.

    Attributes
    ----------
    normals : (m, 3, 3) float64
        ``normals[f, k]`` is the unit normal at corner k (vertex ``faces[f, k]``) of face f;
        zero rows where ``missing``.
    missing : (m, 3) bool
        The face is degenerate, or the weighted sum at that corner cancels.
    """

    normals: FloatArray
    missing: BoolArray

    def __len__(self) -> int:
        return len(self.missing)


def _weighting_code(weighting: str) -> int:
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting must be one of {', '.join(WEIGHTINGS)}, not {weighting!r}.")
    return WEIGHTINGS.index(weighting)


@njit(cache=True, error_model="numpy")
def _weights(code: int, edges: Edges, length: float) -> Vector:
    """The weights at corners 0, 1, 2 of a usable face (``code`` indexes ``WEIGHTINGS``).

    Corner k lies between edge k - 1 (arriving) and edge k (leaving).
    """
    if code == 0:  # uniform
        return 1.0, 1.0, 1.0
    if code == 1:  # area
        return length, length, length
    e0, e1, e2 = edges
    if code == 2:  # angle: atan2(|n|, p . q) for the corner's edges p, q
        return (
            math.atan2(length, -_dot(e2, e0)),
            math.atan2(length, -_dot(e0, e1)),
            math.atan2(length, -_dot(e1, e2)),
        )
    s0, s1, s2 = _dot(e0, e0), _dot(e1, e1), _dot(e2, e2)  # max: |n| / (|p|**2 |q|**2)
    return length / (s2 * s0), length / (s0 * s1), length / (s1 * s2)


@njit(cache=True, error_model="numpy")
def _weights_kernel(
    code: int, edges: FloatArray, length: FloatArray, degenerate: BoolArray, weights: FloatArray
) -> None:
    for face in range(len(length)):
        sides = (
            (edges[0, 0, face], edges[1, 0, face], edges[2, 0, face]),
            (edges[0, 1, face], edges[1, 1, face], edges[2, 1, face]),
            (edges[0, 2, face], edges[1, 2, face], edges[2, 2, face]),
        )
        weight = (0.0, 0.0, 0.0) if degenerate[face] else _weights(code, sides, length[face])
        for k in range(3):
            weights[k, face] = weight[k]


def corner_weights(geometry: FaceGeometry, weighting: str) -> FloatArray:
    """The weight of each face's normal at each of its corners.

    Parameters
    ----------
    geometry : FaceGeometry
        From :func:`mesh_normal.faces.face_geometry`.
    weighting : {"uniform", "area", "angle", "max"}
        See the module docstring.

    Returns
    -------
    (3, m) float64
        ``weights[k, f]`` for corner k of face f; zero for degenerate faces.
    """
    code = _weighting_code(weighting)
    weights = np.empty((3, len(geometry.length)))
    _weights_kernel(code, geometry.edges, geometry.length, geometry.degenerate, weights)
    return weights


#: The faces are summed in this many halves (in parallel where there are cores), each into
#: its own (n, 4) buffer, and the buffers are added in a fixed order: the result has the same
#: bits on every machine, whatever its number of cores.
_CHUNKS = 2


@njit(cache=True, error_model="numpy", parallel=True)
def _vertex_sums_kernel(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    sums: FloatArray,
    spare: FloatArray,
) -> None:
    """Add each usable face's weighted unit normal and its weight into its vertices' rows.

    ``sums`` and ``spare`` are (n, 4) zeros: the sum of weighted normals and the sum of
    weights side by side, so that each corner updates one cache line. The first half of the
    faces (in whole blocks) goes into ``sums``, the rest into ``spare``; the caller adds
    ``spare`` to ``sums``.
    """
    half = (len(faces) + 2 * _BLOCK - 1) // (2 * _BLOCK) * _BLOCK
    for chunk in prange(_CHUNKS):
        if chunk == 0:
            _accumulate(code, points, factor, faces, 0, half, sums)
        else:
            _accumulate(code, points, factor, faces, half, len(faces), spare)


@njit(cache=True, error_model="numpy")
def _accumulate(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    first: int,
    stop: int,
    sums: FloatArray,
) -> None:
    """The sums of faces ``first`` to ``stop`` (``first`` a multiple of the block size)."""
    corners = np.empty((_BLOCK, 9))
    for start in range(first, stop, _BLOCK):
        for row in range(gather(points, factor, faces[:stop], start, corners)):
            edges = face_edges(corners, row)
            normal, square, flat = face_cross(edges)
            if flat:
                continue
            length = math.sqrt(square)
            if code == 1:  # area: the cross product itself is the unit normal times |n|
                for k in range(3):
                    _add_raw(sums[faces[start + row, k]], length, normal)
                continue
            x, y, z = normal[0] / length, normal[1] / length, normal[2] / length
            w0, w1, w2 = _weights(code, edges, length)
            _add(sums[faces[start + row, 0]], w0, x, y, z)
            _add(sums[faces[start + row, 1]], w1, x, y, z)
            _add(sums[faces[start + row, 2]], w2, x, y, z)


@njit(cache=True, error_model="numpy")
def _add_raw(total: FloatArray, weight: float, normal: Vector) -> None:
    """Area weighting: add n (not weight * n / |n|, which would round twice more)."""
    total[0] += normal[0]
    total[1] += normal[1]
    total[2] += normal[2]
    total[3] += weight


@njit(cache=True, error_model="numpy")
def _add(total: FloatArray, weight: float, x: float, y: float, z: float) -> None:
    total[0] += weight * x
    total[1] += weight * y
    total[2] += weight * z
    total[3] += weight


@njit(cache=True, error_model="numpy")
def _normalise_kernel(sums: FloatArray, normals: FloatArray, missing: BoolArray) -> None:
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


def _normalised(sums: FloatArray, totals: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Unit rows of ``sums`` (r, 3) and where a row cancels against its total ``totals`` (r,)."""
    both = np.concatenate([sums, totals[:, None]], axis=1)
    missing = np.empty(len(totals), dtype=bool)
    _normalise_kernel(both, sums, missing)
    return sums, missing


def _smooth(points: FloatArray, faces: IndexArray, weighting: str) -> tuple[FloatArray, BoolArray]:
    """Vertex normals and their mask for checked arrays.

    The sums are (n, 4) and the normals are packed into the same memory as (n, 3).
    """
    code = _weighting_code(weighting)
    points, factor, _ = scaling(points)
    count = len(points)
    sums, spare = np.zeros((count, 4)), np.zeros((count, 4))
    with PARALLEL_KERNELS:
        _vertex_sums_kernel(code, points, factor, faces, sums, spare)
    sums += spare
    del spare
    normals = sums.reshape(-1)[: 3 * count].reshape(count, 3)
    missing = np.empty(count, dtype=bool)
    _normalise_kernel(sums, normals, missing)
    return normals, missing


def vertex_normals(
    vertices: ArrayLike, faces: ArrayLike, weighting: Weighting = "angle"
) -> VertexNormals:
    """Return the weighted average of the face normals around each vertex.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
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
    points, indices = check_mesh(vertices, faces)
    return VertexNormals(*_smooth(points, indices, weighting))


def compile_kernels() -> None:
    """Compile every mesh kernel now (into numba's cache), e.g. while building an image."""
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    faces = np.array([[0, 1, 2]])
    face_normals(vertices, faces)
    corner_normals(vertices, faces, 30.0)  # vertex normals, face geometry and weights too
    from mesh_normal.orientation import orient  # imported here: orientation imports this package

    orient(vertices, faces)


def _crease_cosine(crease_angle: float) -> float:
    if isinstance(crease_angle, bool) or not isinstance(crease_angle, Real):
        raise ValueError("crease_angle must be a number of degrees.")
    angle = float(crease_angle)
    if not 0.0 <= angle <= 180.0:  # also rejects NaN
        raise ValueError(f"crease_angle must be between 0 and 180 degrees, not {crease_angle}.")
    return math.cos(math.radians(angle)) - MESH_CREASE_SLACK


def corner_normals(
    vertices: ArrayLike,
    faces: ArrayLike,
    crease_angle: float = 30.0,
    weighting: Weighting = "angle",
) -> CornerNormals:
    """Return normals per face corner: smooth across gentle edges, sharp across creases.

    The normal at corner k of face f (vertex v = ``faces[f, k]``) is the weighted average
    of the normals of the faces g around v whose normal is within ``crease_angle`` of f's:
    ``dot(n_f, n_g) >= cos(crease_angle)`` (f itself always counts). This is a per-vertex
    rule, like "Auto Smooth" by angle between face normals; Blender's "Smooth by Angle"
    instead marks edges whose dihedral angle exceeds the crease as sharp and averages over
    the edge-connected fan of faces between sharp edges. The two agree wherever the faces
    around a vertex are either all within the crease of each other or split into fans by
    the sharp edges (a cube, a cylinder's rim), and differ when a face is reached only
    through a chain of small angles. A crease of 180 gives the vertex normals; 0 gives
    the face normals (faces with exactly the same normal still join).

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
    faces : (m, 3) int
        Indices into ``vertices``.
    crease_angle : float
        In degrees, from 0 to 180.
    weighting : {"uniform", "area", "angle", "max"}
        As for :func:`vertex_normals`.

    Returns
    -------
    CornerNormals
        ``normals`` (m, 3, 3) float64 and the ``missing`` (m, 3) bool mask; corners of
        degenerate faces are missing.

    Notes
    -----
    A vertex whose faces are all within half the crease of its vertex normal has all of
    them within the crease of each other, so its corners take the vertex normal at the
    cost of one dot product each. Only the other vertices compare their corners pair by
    pair: time there grows with the square of a vertex's corner count, and memory is
    bounded by ``MESH_PAIR_CHUNK``.
    """
    threshold = _crease_cosine(crease_angle)
    points, indices = check_mesh(vertices, faces)
    smooth, cancelled = _smooth(points, indices, weighting)
    geometry = face_geometry(points, indices)
    unit = unit_normals(geometry)
    weights = corner_weights(geometry, weighting)
    normals, missing = take_rows(smooth, indices), cancelled[indices]
    if float(crease_angle) < 180.0:
        # Faces within half the crease of their vertex normal are all within the crease of
        # each other (the slack keeps that true after rounding): such a vertex's corners are
        # its vertex normal. Only the others need their corners compared pair by pair.
        half = math.cos(math.radians(crease_angle) / 2) + MESH_CREASE_SLACK
        near = np.einsum("fka,af->fk", normals, unit) >= half
        near[geometry.degenerate] = True  # weighs nothing either way
        creased = np.zeros(len(points), dtype=bool)
        creased[indices[~near]] = True
        corners = np.flatnonzero(creased[indices].ravel())
        if len(corners):
            groups = vertex_corners(indices, len(points), corners)
            found, lost = _creased(unit, weights.T.ravel(), groups, threshold)
            _put_rows(normals.reshape(-1, 3), groups.order, found)
            missing.reshape(-1)[groups.order] = lost
    normals[geometry.degenerate] = 0.0
    missing[geometry.degenerate] = True
    return CornerNormals(normals, missing)


def _put_rows(array: FloatArray, index: IndexArray, values: FloatArray) -> None:
    """``array[index] = values`` for C-contiguous (k, 3) float64 arrays, as in take_rows."""
    rows = np.dtype((np.void, 24))
    array.view(rows).reshape(len(array)).put(index, values.view(rows).reshape(len(values)))


def _creased(
    unit: FloatArray, weights: FloatArray, groups: VertexCorners, threshold: float
) -> tuple[FloatArray, BoolArray]:
    """Corner normals by comparing every pair of corners around each vertex.

    ``unit`` is (3, m) and ``weights`` (3 m,) by corner id; the results are in the order of
    ``groups.order``. Vertices with the same number of corners d are done together as
    (vertices, d, d) blocks of dot products, at most ``MESH_PAIR_CHUNK`` pairs at a time; a
    vertex with more than that many pairs is done a block of its corners at a time.
    """
    order = groups.order
    normal = take_rows(np.ascontiguousarray(unit.T), order // 3)  # in sorted corner order
    weight = weights[order]
    counts = groups.counts
    sums = np.empty_like(normal)
    totals = np.empty_like(weight)
    for size in np.unique(counts[counts > 0]).tolist():
        firsts = groups.starts[:-1][counts == size]
        step = MESH_PAIR_CHUNK // (size * size)
        for chunk in range(0, len(firsts), step) if step else ():
            at = firsts[chunk : chunk + step, None] + np.arange(size)  # (vertices, d)
            around = take_rows(normal, at)  # (vertices, d, 3)
            within = np.matmul(around, around.transpose(0, 2, 1)) >= threshold
            weight_in = within * weight[at][:, None, :]  # (vertices, d mine, d theirs)
            _put_rows(sums, at.ravel(), np.matmul(weight_in, around).reshape(-1, 3))
            totals[at] = weight_in.sum(axis=2)
        rows = max(1, MESH_PAIR_CHUNK // size)
        for first in firsts.tolist() if not step else ():
            around, theirs = normal[first : first + size], weight[first : first + size]
            for row in range(first, first + size, rows):
                mine = normal[row : min(row + rows, first + size)]
                weight_in = (mine @ around.T >= threshold) * theirs  # (rows, d)
                sums[row : row + len(mine)] = weight_in @ around
                totals[row : row + len(mine)] = weight_in.sum(axis=1)
    return _normalised(sums, totals)
