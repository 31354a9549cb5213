"""Meshes and assertions shared by the tests of the geometry core."""

from __future__ import annotations

import numpy as np
import trimesh

from tests.paths import DATA

SAMPLES = ("sphere.ply", "nut.ply", "ant.ply", "cube.obj")

TETRAHEDRON = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
TETRAHEDRON_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def load(name: str) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.load(DATA / name, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)


def unit(*xyz: float) -> np.ndarray:
    vector = np.array(xyz, dtype=np.float64)
    return vector / np.linalg.norm(vector)


def octahedron() -> tuple[np.ndarray, np.ndarray]:
    vertices = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
    )
    faces = []
    for x in (0, 1):
        for y in (2, 3):
            for z in (4, 5):
                corner = [x, y, z]
                if np.linalg.det(vertices[corner]) < 0:  # outward: positive orientation
                    corner = [x, z, y]
                faces.append(corner)
    return vertices, np.array(faces)


def assert_clean(*arrays: np.ndarray) -> None:
    for array in arrays:
        assert array.dtype == np.float64
        assert np.isfinite(array).all()


def assert_unit_or_zero(normals: np.ndarray, zero: np.ndarray) -> None:
    lengths = np.linalg.norm(normals, axis=-1)
    assert np.all(lengths[zero] == 0.0)
    assert np.allclose(lengths[~zero], 1.0, atol=4e-16, rtol=0)
