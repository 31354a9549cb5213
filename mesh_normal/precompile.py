"""Compile every mesh kernel ahead of use: for an image build or a server's start-up.

numba compiles a kernel once for each signature it is called with, and an array's signature
includes whether it is read-only. The file readers give both kinds: an array made with
``np.frombuffer`` over the uploaded bytes is read-only, one parsed from text is not, and the
checks keep the caller's array when it already has the right type and layout. The mesh
kernels see only read-only views (:class:`~mesh_normal.checks.CheckedMesh` makes them), so
each is compiled once. A job never compiles one at run time (in a
read-only container it would compile in memory, for seconds, in every worker;
``tests/app/mesh/test_warmup.py`` checks that the jobs on every test file need nothing else).
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from mesh_normal.bounds import column_bounds
from mesh_normal.collector import paused
from mesh_normal.corners import corner_normals, corner_weights
from mesh_normal.faces import face_geometry, face_normals
from mesh_normal.kernels import (
    coordinate_range,
    load_numba,
    sort_run,
    touch_kernel,
    unit_normals_kernel,
    workers,
)
from mesh_normal.orientation import orient
from mesh_normal.stored_normals import Candidate, angles_between, unit_rows
from mesh_normal.types import FloatArray, IndexArray
from mesh_normal.vertices import normalise_packed_kernel, vertex_normals

Scalar = TypeVar("Scalar", bound=np.generic)

#: Two tetrahedra, one inside the other (the winding-number kernel for nested shells), and an
#: open fan of three triangles (visibility decides an open patch).
_TETRAHEDRON = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
_SIDES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
_NESTED = (
    np.concatenate([_TETRAHEDRON, 0.1 + 0.2 * _TETRAHEDRON]),
    np.concatenate([_SIDES, _SIDES + 4]),
)
_OPEN = (_TETRAHEDRON, _SIDES[:3])
#: A few points, for the kernels of a report's bounds and the coordinate range.
_POINTS = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, -1, 0]])


def compile_kernels() -> None:
    """Compile every mesh kernel now (into numba's cache), e.g. while building an image; where
    the cache holds them already, load them (a server's workers, as they start). numba is
    loaded first: these calls are small enough to run in Python otherwise. The garbage
    collector is paused meanwhile (:mod:`mesh_normal.collector`)."""
    with paused():
        _compile_kernels()


def _compile_kernels() -> None:
    load_numba()
    for vertices, faces in (_NESTED, _OPEN):  # the checks give the kernels read-only views
        _mesh_kernels(vertices, faces)
    points = _POINTS
    sort_run(np.arange(20, 0, -1), 0, 20)  # called by no kernel, yet looked up as one
    # Point clouds: the neighbourhood kernel (k nearest and within a radius take the same
    # types) and the signs down the spanning tree; binary_compressed PCD's LZF (one literal).
    for frozen in (False, True):  # a report's bounds, of the vertices as read
        column_bounds(_kept(points, frozen))
    # A large mesh's checks and fresh outputs (the checks give read-only views).
    coordinate_range(_kept(points, True))
    touch_kernel(np.empty(1, np.uint8), *workers())
    crosses = np.zeros((1, 3))
    unit_normals_kernel(crosses, np.ones(1), np.zeros(1, bool), crosses, *workers())
    sums = np.ones((1, 4))  # many vertices' normals, packed into their sums' memory
    packed = sums.reshape(-1)[:3].reshape(1, 3)
    normalise_packed_kernel(sums, packed, np.empty(1, bool), np.zeros(1, np.int64), 1, *workers())
    # A file's stored normals against ours (every row compared, and some).
    unit, usable = unit_rows(np.eye(3))
    angles_between(unit, usable, Candidate(np.eye(3), np.array([False, True, False])))


def _mesh_kernels(vertices: FloatArray, faces: IndexArray) -> None:
    geometry = face_geometry(vertices, faces)
    face_normals(geometry)
    face_normals(geometry.mesh)  # from a mesh: its own one-pass kernel
    vertex_normals(geometry)  # one kernel for every weighting, from a geometry or a mesh
    corner_normals(geometry, crease_angle=30.0)
    corner_weights(geometry, "angle")  # corner_normals needs them only at creased vertices
    orient(geometry)
    orient(geometry, weld=1e-6)


def _kept(array: NDArray[Scalar], read_only: bool) -> NDArray[Scalar]:
    """A copy of ``array``, read-only if asked (as ``np.frombuffer`` gives one)."""
    copy = np.array(array)
    copy.flags.writeable = not read_only
    return copy
