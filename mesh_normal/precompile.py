"""Compile every mesh kernel ahead of use: for an image build or a server's start-up."""

from __future__ import annotations

import numpy as np

from mesh_normal.corners import corner_normals, corner_weights
from mesh_normal.faces import face_geometry, face_normals
from mesh_normal.files.polygons import triangulate
from mesh_normal.orientation import orient
from mesh_normal.points import point_normals
from mesh_normal.points.pcd import lzf_decompress
from mesh_normal.vertices import vertex_normals


def compile_kernels() -> None:
    """Compile every mesh kernel now (into numba's cache), e.g. while building an image."""

    # Two tetrahedra, one inside the other: the winding-number kernel for nested shells.
    tetrahedron = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    sides = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    orient(
        np.concatenate([tetrahedron, 0.1 + 0.2 * tetrahedron]), np.concatenate([sides, sides + 4])
    )
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    faces = np.array([[0, 1, 2]])
    geometry = face_geometry(vertices, faces)
    face_normals(geometry)
    vertex_normals(geometry)  # one kernel for every weighting
    corner_normals(geometry, crease_angle=30.0)
    corner_weights(geometry, "angle")  # corner_normals needs them only at creased vertices
    orient(geometry)
    triangulate(
        np.array([4]), np.arange(4), np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    )
    # Point clouds: the neighbourhood kernel (k nearest and within a radius take the same
    # types) and the signs down the spanning tree.
    point_normals(np.random.default_rng(0).normal(size=(40, 3)), k=10)
    lzf_decompress(b"\x00a", 1)  # binary_compressed PCD: one literal byte
