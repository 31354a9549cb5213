"""Corner normals of a triangle mesh: smooth across gentle edges, sharp across creases.

A corner is one vertex of one face. Its normal is the weighted average (as for the vertex
normals of :mod:`mesh_normal.vertices`, with the same weightings) of the normals of the faces
around its vertex that are within the crease angle of its own face's normal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np
from numpy.typing import ArrayLike

from mesh_normal.faces import FaceGeometry, MeshInput, checked_input, face_geometry
from mesh_normal.kernels import BLOCK, face_edges, gather, kernel
from mesh_normal.tolerances import MESH_CREASE_SLACK, MESH_PAIR_CHUNK
from mesh_normal.topology import VertexCorners, vertex_corners
from mesh_normal.types import BoolArray, FloatArray, IndexArray
from mesh_normal.vertices import Weighting, face_weights, normalise_kernel, smooth, weighting_code


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


def corner_normals(
    vertices: MeshInput,
    faces: ArrayLike | None = None,
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
    vertices : (n, 3) float64, CheckedMesh or FaceGeometry
        Finite coordinates, or an already checked mesh or its geometry (then ``faces`` is
        None: ``corner_normals(geometry, crease_angle=45)``).
    faces : (m, 3) int
        Indices into ``vertices``.
    crease_angle : float
        In degrees, from 0 to 180.
    weighting : {"uniform", "area", "angle", "max"}
        As for :func:`mesh_normal.vertices.vertex_normals`.

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
    source = checked_input(vertices, faces)
    weighting_code(weighting)
    geometry = face_geometry(source)
    smooth_normals, cancelled = smooth(geometry, weighting)
    indices, vertex_count = geometry.mesh.faces, len(geometry.mesh.vertices)
    normals, missing = take_rows(smooth_normals, indices), cancelled[indices]
    if float(crease_angle) < 180.0:
        # Faces within half the crease of their vertex normal are all within the crease of
        # each other (the slack keeps that true after rounding): such a vertex's corners are
        # its vertex normal. Only the others need their corners compared pair by pair.
        half = math.cos(math.radians(crease_angle) / 2) + MESH_CREASE_SLACK
        near = np.empty(indices.shape, dtype=bool)
        for corner in range(3):  # a column at a time: 8 bytes a face, not 24, at once
            dots = np.einsum("fa,fa->f", normals[:, corner], geometry.normals)
            np.greater_equal(dots, half, out=near[:, corner])
        near[geometry.degenerate] = True  # weighs nothing either way
        creased = np.zeros(vertex_count, dtype=bool)
        creased[indices[~near]] = True
        corners = np.flatnonzero(creased[indices].ravel())
        if len(corners):
            groups = vertex_corners(indices, vertex_count, corners)
            weights = corner_weights(geometry, weighting).T.ravel()  # only where creased
            found, lost = _creased(geometry.normals, weights, groups, threshold)
            put_rows(normals.reshape(-1, 3), groups.order, found)
            missing.reshape(-1)[groups.order] = lost
    normals[geometry.degenerate] = 0.0
    missing[geometry.degenerate] = True
    return CornerNormals(normals, missing)


def _crease_cosine(crease_angle: float) -> float:
    if isinstance(crease_angle, bool) or not isinstance(crease_angle, Real):
        raise ValueError("crease_angle must be a number of degrees.")
    angle = float(crease_angle)
    if not 0.0 <= angle <= 180.0:  # also rejects NaN
        raise ValueError(f"crease_angle must be between 0 and 180 degrees, not {crease_angle}.")
    return math.cos(math.radians(angle)) - MESH_CREASE_SLACK


@kernel()
def _weights_kernel(
    code: int,
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    weights: FloatArray,
) -> None:
    corners = np.empty((BLOCK, 9))
    for start in range(0, len(faces), BLOCK):
        for row in range(gather(points, factor, faces, start, corners)):
            face = start + row
            weight = (
                (0.0, 0.0, 0.0)
                if degenerate[face]
                else face_weights(code, face_edges(corners, row), lengths[face])
            )
            for k in range(3):
                weights[k, face] = weight[k]


def corner_weights(geometry: FaceGeometry, weighting: str) -> FloatArray:
    """The weight of each face's normal at each of its corners.

    Parameters
    ----------
    geometry : FaceGeometry
        From :func:`mesh_normal.faces.face_geometry`.
    weighting : {"uniform", "area", "angle", "max"}
        See :mod:`mesh_normal.vertices`.

    Returns
    -------
    (3, m) float64
        ``weights[k, f]`` for corner k of face f; zero for degenerate faces.
    """
    code = weighting_code(weighting)
    mesh = geometry.mesh
    weights = np.empty((3, len(geometry)))
    _weights_kernel(
        code, mesh.points, mesh.factor, mesh.faces, geometry.lengths, geometry.degenerate, weights
    )
    return weights


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


def put_rows(array: FloatArray, index: IndexArray, values: FloatArray) -> None:
    """``array[index] = values`` for C-contiguous (k, 3) float64 arrays, as in take_rows."""
    rows = np.dtype((np.void, 24))
    array.view(rows).reshape(len(array)).put(index, values.view(rows).reshape(len(values)))


def _normalised(sums: FloatArray, totals: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Unit rows of ``sums`` (r, 3) and where a row cancels against its total ``totals`` (r,)."""
    both = np.concatenate([sums, totals[:, None]], axis=1)
    missing = np.empty(len(totals), dtype=bool)
    normalise_kernel(both, sums, missing)
    return sums, missing


def _creased(
    unit: FloatArray, weights: FloatArray, groups: VertexCorners, threshold: float
) -> tuple[FloatArray, BoolArray]:
    """Corner normals by comparing every pair of corners around each vertex.

    ``unit`` is (m, 3) and ``weights`` (3 m,) by corner id; the results are in the order of
    ``groups.order``. Vertices with the same number of corners d are done together as
    (vertices, d, d) blocks of dot products, at most ``MESH_PAIR_CHUNK`` pairs at a time; a
    vertex with more than that many pairs is done a block of its corners at a time.
    """
    order = groups.order
    normal = take_rows(unit, order // 3)  # in sorted corner order
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
            put_rows(sums, at.ravel(), np.matmul(weight_in, around).reshape(-1, 3))
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
