"""Corner normals of a triangle mesh: smooth across gentle edges, sharp across creases.

A corner is one vertex of one face. Its normal is the weighted average (as for the vertex
normals of :mod:`mesh_normal.mesh.vertices`, with the same weightings) of the normals of the faces
around its vertex that are within the crease angle of its own face's normal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np
from numpy.typing import ArrayLike

import mesh_normal._core as _core
from mesh_normal.mesh.checks import refuse_faces
from mesh_normal.mesh.faces import FaceGeometry, MeshInput, checked_input, face_geometry
from mesh_normal.mesh.topology import VertexCorners, vertex_corners
from mesh_normal.mesh.vertices import Weighting, normalised, smooth, weighting_code
from mesh_normal.tolerances import MESH_CORNER_BLOCK, MESH_CREASE_SLACK, MESH_PAIR_CHUNK
from mesh_normal.types import BoolArray, FloatArray, IndexArray


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
    vertices : (n, 3) float64, a mesh or FaceGeometry
        Finite coordinates; or a mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes
        it (read_mesh's, a ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista) or its
        geometry (then ``faces`` is
        None: ``corner_normals(geometry, crease_angle=45)``).
    faces : (m, 3) int
        Indices into ``vertices``.
    crease_angle : float
        In degrees, from 0 to 180.
    weighting : {"angle", "area", "uniform", "max"}
        As for :func:`mesh_normal.mesh.vertices.vertex_normals`.

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
    blocks = corner_blocks(vertices, faces, crease_angle, weighting)
    return CornerNormals(blocks.block(0, len(blocks)), blocks.missing)


@dataclass(frozen=True, slots=True)
class CornerBlocks:
    """The corner normals of ``m`` faces, made a block of faces at a time.

    Everything they are made of but the (m, 3, 3) result: 72 bytes a face that a writer
    (:mod:`mesh_normal.files.normals`) need never hold whole. ``block(0, m)`` is
    :func:`corner_normals`'s array, and any split into blocks gives the same bits.

    Attributes
    ----------
    faces : (m, 3) int
        The checked faces.
    smooth : (n, 3) float64
        The vertex normals, which every corner away from a crease takes.
    degenerate : (m,) bool
        Faces whose corners are zero.
    creased : (c,) intp
        Ids (3 f + k) of the corners at creased vertices, increasing.
    creased_normals : (c, 3) float64
        Their normals, compared pair by pair around their vertex.
    missing : (m, 3) bool
        As :attr:`CornerNormals.missing`.
    """

    faces: IndexArray
    smooth: FloatArray
    degenerate: BoolArray
    creased: IndexArray
    creased_normals: FloatArray
    missing: BoolArray

    def __len__(self) -> int:
        return len(self.missing)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self), 3, 3)

    def block(self, start: int, stop: int) -> FloatArray:
        """(k, 3, 3) float64: the corner normals of faces ``start`` to ``stop``."""
        normals = take_rows(self.smooth, self.faces[start:stop])
        low, high = np.searchsorted(self.creased, (3 * start, 3 * stop)).tolist()
        put_rows(
            normals.reshape(-1, 3),
            self.creased[low:high] - 3 * start,
            self.creased_normals[low:high],
        )
        normals[self.degenerate[start:stop]] = 0.0
        return normals


def corner_blocks(
    vertices: MeshInput,
    faces: ArrayLike | None = None,
    crease_angle: float = 30.0,
    weighting: Weighting = "angle",
    rows: int = MESH_CORNER_BLOCK,
) -> CornerBlocks:
    """What :func:`corner_normals` computes, ready to be taken a block of faces at a time.

    Parameters and the rule are :func:`corner_normals`'s; ``rows`` is how many faces the
    search for creased vertices takes at a time (any number gives the same result). Peak
    memory is the face geometry, the vertex normals and the few bytes a face of the masks,
    plus about 100 bytes for each corner at a creased vertex.
    """
    threshold = _crease_cosine(crease_angle)
    source = checked_input(vertices, faces)
    weighting_code(weighting)
    if isinstance(source, FaceGeometry):
        geometry = source
        smooth_normals, cancelled = smooth(geometry, weighting)
    else:
        # The vertex normals first, in the pass that takes the cross products as it goes (the
        # same bits): its two (n, 4) sums are never held beside the geometry's products.
        smooth_normals, cancelled = smooth(source, weighting)
        geometry = face_geometry(source)
    indices, vertex_count = geometry.mesh.faces, len(geometry.mesh.vertices)
    missing = cancelled[indices]
    creased_ids = np.empty(0, dtype=np.intp)
    creased_normals = np.empty((0, 3))
    if float(crease_angle) < 180.0:
        creased = _creased_vertices(geometry, smooth_normals, crease_angle, rows)
        corners = _creased_corners(creased, indices, rows)
        if len(corners):
            groups = vertex_corners(indices, vertex_count, corners)
            # Only the creased corners' weights, in sorted corner order (corner id 3 f + k
            # is row k of face f): no (3 m,) copy of every corner's.
            weights = corner_weights(geometry, weighting)[groups.order % 3, groups.order // 3]
            unit = geometry.unit_normals(groups.order // 3)  # in sorted corner order
            found, lost = _creased(unit, weights, groups, threshold)
            missing.reshape(-1)[groups.order] = lost
            # ``corners`` is increasing and ``order`` a permutation of it: put the normals
            # in corner order, so that a block finds its own by bisection.
            creased_ids, creased_normals = corners, np.empty_like(found)
            put_rows(creased_normals, np.searchsorted(corners, groups.order), found)
    missing[geometry.degenerate] = True
    return CornerBlocks(
        indices, smooth_normals, geometry.degenerate, creased_ids, creased_normals, missing
    )


def _creased_corners(creased: BoolArray, indices: IndexArray, rows: int) -> IndexArray:
    """The ids 3 f + k of the corners at a creased vertex, increasing: a block of faces at a
    time (no (m, 3) mask), none at all when no vertex is creased."""
    if not creased.any():
        return np.empty(0, dtype=np.intp)
    found = [
        np.flatnonzero(creased[indices[start : start + rows]].ravel()) + 3 * start
        for start in range(0, len(indices), rows)
    ]
    return np.concatenate(found) if found else np.empty(0, dtype=np.intp)


def _creased_vertices(
    geometry: FaceGeometry, smooth_normals: FloatArray, crease_angle: float, rows: int
) -> BoolArray:
    """(n,) bool: the vertices with a corner not within half the crease of their normal.

    Faces within half the crease of their vertex normal are all within the crease of each
    other (the slack keeps that true after rounding): such a vertex's corners are its vertex
    normal. Only the others need their corners compared pair by pair. A block of faces at a
    time, so that neither their unit normals nor their corners' are whole in memory.
    """
    indices = geometry.mesh.faces
    half = math.cos(math.radians(crease_angle) / 2) + MESH_CREASE_SLACK
    creased = np.zeros(len(geometry.mesh.vertices), dtype=bool)
    for start in range(0, len(indices), rows):
        block = slice(start, start + rows)
        normals = take_rows(smooth_normals, indices[block])
        unit = geometry.unit_normals(block)
        near = np.empty(normals.shape[:2], dtype=bool)
        for corner in range(3):
            dots = np.einsum("fa,fa->f", normals[:, corner], unit)
            np.greater_equal(dots, half, out=near[:, corner])
        near[geometry.degenerate[block]] = True  # weighs nothing either way
        creased[indices[block][~near]] = True
    return creased


def _crease_cosine(crease_angle: float) -> float:
    if isinstance(crease_angle, bool) or not isinstance(crease_angle, Real):
        raise ValueError("crease_angle must be a number of degrees.")
    angle = float(crease_angle)
    if not 0.0 <= angle <= 180.0:  # also rejects NaN
        raise ValueError(f"crease_angle must be between 0 and 180 degrees, not {crease_angle}.")
    return math.cos(math.radians(angle)) - MESH_CREASE_SLACK


def corner_weights(geometry: FaceGeometry, weighting: str) -> FloatArray:
    """The weight of each face's normal at each of its corners.

    Parameters
    ----------
    geometry : FaceGeometry
        From :func:`mesh_normal.mesh.faces.face_geometry`.
    weighting : {"uniform", "area", "angle", "max"}
        See :mod:`mesh_normal.mesh.vertices`.

    Returns
    -------
    (3, m) float64
        ``weights[k, f]`` for corner k of face f; zero for degenerate faces.
    """
    code = weighting_code(weighting)
    mesh = geometry.mesh
    weights = np.empty((3, len(geometry)))
    if not _core.corner_weights(
        code, mesh.points, mesh.factor, mesh.faces, geometry.lengths, geometry.degenerate, weights
    ):
        refuse_faces(mesh.faces, len(mesh.points))
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
    return normalised(np.concatenate([sums, totals[:, None]], axis=1))


def _creased(
    unit: FloatArray, weights: FloatArray, groups: VertexCorners, threshold: float
) -> tuple[FloatArray, BoolArray]:
    """Corner normals by comparing every pair of corners around each vertex.

    ``unit`` is (c, 3), the unit normals of the faces of the corners in ``groups.order``, in
    that order, and ``weights`` their weights in that order; the results are in that order
    too.
    Vertices with the same number of corners d are done together as (vertices, d, d) blocks
    of dot products, at most ``MESH_PAIR_CHUNK`` pairs at a time; a vertex with more than that
    many pairs is done a block of its corners at a time.
    """
    normal, weight = unit, weights
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
