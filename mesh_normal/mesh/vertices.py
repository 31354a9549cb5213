"""Vertex normals of a triangle mesh: weighted averages of its face normals.

Each corner (one vertex of one face) gives its face's unit normal a weight:

- ``"uniform"``: 1, the plain mean of the incident face normals;
- ``"area"``: the face's area (the sum of the raw cross products);
- ``"angle"``: the corner's angle (Thuermer and Wuethrich 1998), computed stably as
  ``atan2(|n|, p . q)`` for the corner's edges p and q, with the face's most accurate |n|;
- ``"max"``: sin(angle) / (|p| |q|), i.e. |p x q| / (|p|**2 |q|**2) (Nelson Max 1999,
  "Weights for computing vertex normals from facet normals"), exact when the vertex and
  its neighbours lie on a sphere.

The sums are compiled (``mesh_normal._core``, ``cpp/faces.cpp``): every core takes a range of
the vertices and adds the faces' weighted normals (from their
:class:`~mesh_normal.mesh.faces.FaceGeometry`, or taken as it goes) into the sums of its own
vertices, in face order, so the bits are the same on any number of cores; each sum is
normalised once. Degenerate faces (see :mod:`mesh_normal.mesh.faces`) weigh nothing. A vertex in
no usable face, or whose sum cancels (at most ``MESH_CANCELLED_SUM`` of its total weight),
gets a zero row and ``True`` in the ``missing`` mask; nothing is NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import get_args

import numpy as np
from numpy.typing import ArrayLike

import mesh_normal._core as _core
from mesh_normal.choices import Weighting as Weighting
from mesh_normal.mesh.checks import CheckedMesh, refuse_faces
from mesh_normal.mesh.faces import FaceGeometry, MeshInput, kernel_ranged_input
from mesh_normal.types import BoolArray, FloatArray

WEIGHTINGS: tuple[Weighting, ...] = get_args(Weighting)


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


def smooth(geometry: FaceGeometry | CheckedMesh, weighting: str) -> tuple[FloatArray, BoolArray]:
    """Vertex normals and their mask, from the face geometry, or from a checked mesh whose
    cross products are taken as they are needed (the same bits, none of them kept).

    Every core adds the faces' terms into the sums of its own range of vertices, in face order
    (:func:`mesh_normal._core.vertex_sums`). The sums are (n, 4) and the normals are packed
    into the same memory as (n, 3).
    """
    code = weighting_code(weighting)
    if isinstance(geometry, FaceGeometry):
        mesh, fused = geometry.mesh, False
        crosses, lengths, degenerate = geometry.crosses, geometry.lengths, geometry.degenerate
    else:
        mesh, fused = geometry, True
        crosses, lengths, degenerate = _NO_CROSSES, _NO_LENGTHS, _NO_FLAGS
    count, faces = len(mesh.vertices), mesh.faces
    sums = _zero_rows(count)
    if not _core.vertex_sums(
        code, mesh.points, mesh.factor, faces, crosses, lengths, degenerate, fused, sums
    ):
        refuse_faces(faces, count)
    return normalised(sums)


def _zero_rows(count: int) -> FloatArray:
    """Zeros, (count, 4), starting on a 64-byte cache line (NumPy's own start 16 bytes past
    one): each row of 32 bytes then lies in one line, not every other row across two, and the
    kernel's scattered additions into them take a fifth less time."""
    whole = np.zeros(4 * count + 7)
    start = (-whole.ctypes.data % 64) // whole.itemsize
    return whole[start : start + 4 * count].reshape(count, 4)


def normalised(sums: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Unit rows of ``sums[:, :3]`` (n, 4), zero where they cancel against ``sums[:, 3]`` (at
    most ``MESH_CANCELLED_SUM`` of it), packed into the memory of ``sums`` as (n, 3); and where
    they cancel."""
    count = len(sums)
    missing = np.empty(count, dtype=bool)
    _core.normalise_sums(sums, missing)
    return sums.reshape(-1)[: 3 * count].reshape(count, 3), missing


#: What the fused pass is given for the arrays it does not read (the types of a geometry's).
_NO_CROSSES, _NO_LENGTHS = np.empty((0, 3)), np.empty(0)
_NO_FLAGS = np.empty(0, dtype=bool)


def vertex_normals(
    vertices: MeshInput, faces: ArrayLike | None = None, weighting: Weighting = "angle"
) -> VertexNormals:
    """Return the weighted average of the face normals around each vertex.

    Parameters
    ----------
    vertices : (n, 3) float64, a mesh or FaceGeometry
        Finite coordinates; or a mesh as :func:`~mesh_normal.mesh.checks.checked_mesh` takes
        it (read_mesh's, a ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista) or its
        geometry (then ``faces`` is
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
