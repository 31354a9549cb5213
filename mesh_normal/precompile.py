"""Compile every mesh kernel ahead of use: for an image build or a server's start-up.

numba compiles a kernel once for each signature it is called with, and an array's signature
includes whether it is read-only. The file readers give both kinds: an array made with
``np.frombuffer`` over the uploaded bytes is read-only, one parsed from text is not, and the
checks keep the caller's array when it already has the right type and layout. The mesh
kernels see only read-only views (:class:`~mesh_normal.checks.CheckedMesh` makes them), so
each is compiled once; the polygon kernels, which take a file's corners as the reader found
them, are compiled here for each combination. A job never compiles one at run time (in a
read-only container it would compile in memory, for seconds, in every worker;
``tests/app/mesh/test_warmup.py`` checks that the jobs on every test file need nothing else).
"""

from __future__ import annotations

import itertools
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from mesh_normal.bounds import column_bounds
from mesh_normal.collector import paused
from mesh_normal.corners import corner_normals, corner_weights
from mesh_normal.faces import face_geometry, face_normals
from mesh_normal.files.polygons import triangulate
from mesh_normal.files.stl import RECORD as STL_RECORD
from mesh_normal.files.text_kernels import ObjScanner, binary_items
from mesh_normal.files.weld import weld, weld_by_sort
from mesh_normal.kernels import load_numba, workers
from mesh_normal.orientation import _twinned_wide, orient
from mesh_normal.points import point_normals
from mesh_normal.points.pcd import lzf_decompress
from mesh_normal.stored_normals import Candidate, angles_between, unit_rows
from mesh_normal.topology import _wide_half_edges
from mesh_normal.types import FloatArray, IndexArray
from mesh_normal.vertices import vertex_normals

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
#: A square and a triangle as polygons (the polygon kernels run for four corners or more).
_POLYGONS = (
    np.array([4, 3]),
    np.array([0, 1, 2, 3, 0, 1, 4]),
    np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, -1, 0]]),
)
#: An OBJ chunk for the text kernel (files from ``obj.FAST_BYTES`` on): its bytes are read-only,
#: as are a binary PLY's for its list kernel (``ply.COMPILED_ITEMS`` items on).
_OBJ = b"v 0 0 0\nv 1.5 0 0\nv 0 1 0.12345678901234567\nvn 0 0 1\nf 1//1 2//1 3//1\n"


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
    counts, corners, points = _POLYGONS
    for read_only in itertools.product((False, True), repeat=3):
        triangulate(
            _kept(counts, read_only[0]), _kept(corners, read_only[1]), _kept(points, read_only[2])
        )
    # Point clouds: the neighbourhood kernel (k nearest and within a radius take the same
    # types) and the signs down the spanning tree; binary_compressed PCD's LZF (one literal).
    ObjScanner().scan(_OBJ, 0, len(_OBJ))
    for frozen in (False, True):  # a report's bounds, of the vertices as read
        column_bounds(_kept(points, frozen))
    for dtype in (np.float32, np.float64):  # binary STL corners, and text ones
        corners = np.array([[0.0, 0, 0], [1, 0, 0], [0, 0, 0]], dtype)
        weld(corners)
        weld_by_sort(corners)  # where a file crowds the table's slots
        weld(np.array(np.arange(192.0).reshape(64, 3), dtype))  # distinct points: it grows
    # A binary STL's corners, read where they lie in its records (a read-only view).
    weld(np.frombuffer(bytes(2 * STL_RECORD.itemsize), STL_RECORD)["corners"])
    binary_items(
        np.frombuffer(bytes(13), np.uint8), 1, 13, 4, True, True, True,
        np.empty((1, 3), np.int64), *workers(),
    )  # fmt: skip
    # A file's stored normals against ours (every row compared, and some).
    unit, usable = unit_rows(np.eye(3))
    angles_between(unit, usable, Candidate(np.eye(3), np.array([False, True, False])))
    point_normals(np.random.default_rng(0).normal(size=(40, 3)), k=10)
    lzf_decompress(b"\x00a", 1)


def _mesh_kernels(vertices: FloatArray, faces: IndexArray) -> None:
    geometry = face_geometry(vertices, faces)
    face_normals(geometry)
    face_normals(geometry.mesh)  # from a mesh: its own one-pass kernel
    vertex_normals(geometry)  # one kernel for every weighting, from a geometry or a mesh
    corner_normals(geometry, crease_angle=30.0)
    corner_weights(geometry, "angle")  # corner_normals needs them only at creased vertices
    orient(geometry)
    orient(geometry, weld=1e-6)
    # The sorts for more points than one key packs with a face (the Lucy size), on the faces
    # by position (read-only as the checks give them, or a new array where points repeat).
    for frozen in (False, True):
        points = _kept(np.asarray(faces, dtype=np.intp), frozen)
        valid = np.ones(len(points), dtype=bool)
        _wide_half_edges(points, valid, len(vertices))
        _twinned_wide(points, len(vertices))


def _kept(array: NDArray[Scalar], read_only: bool) -> NDArray[Scalar]:
    """A copy of ``array``, read-only if asked (as ``np.frombuffer`` gives one)."""
    copy = np.array(array)
    copy.flags.writeable = not read_only
    return copy
