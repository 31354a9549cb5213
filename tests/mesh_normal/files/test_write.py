from __future__ import annotations

import numpy as np
import pytest

from mesh_normal import face_normals
from mesh_normal.files import MeshFileError, read_mesh, write_mesh
from tests.mesh_normal.files._meshes import TETRA_FACES, TETRA_VERTICES

RNG = np.random.default_rng(7)
VERTICES = RNG.standard_normal((50, 3)) * 10.0 ** RNG.integers(-30, 30, (50, 1))
FACES = RNG.integers(0, 50, (80, 3))


@pytest.mark.parametrize("file_format", ["ply", "obj"])
def test_round_trip_is_exact(file_format: str) -> None:
    mesh = read_mesh(write_mesh(VERTICES, FACES, file_format), f"m.{file_format}")
    np.testing.assert_array_equal(mesh.vertices, VERTICES)  # bit for bit, unused ones too
    np.testing.assert_array_equal(mesh.faces, FACES)


def test_stl_round_trip_is_float32_and_welded() -> None:
    mesh = read_mesh(write_mesh(TETRA_VERTICES, TETRA_FACES, "stl"), "m.stl")
    np.testing.assert_array_equal(mesh.vertices[mesh.faces], TETRA_VERTICES[TETRA_FACES])
    expected = face_normals(TETRA_VERTICES, TETRA_FACES).normals.astype(np.float32)
    np.testing.assert_array_equal(mesh.file_face_normals, expected)


def test_stl_header_does_not_start_with_solid() -> None:
    assert not write_mesh(TETRA_VERTICES, TETRA_FACES, "stl").startswith(b"solid")


def test_unknown_format() -> None:
    with pytest.raises(MeshFileError) as error:
        write_mesh(TETRA_VERTICES, TETRA_FACES, "fbx")
    assert error.value.status_code == 415


def test_bad_mesh_is_a_value_error() -> None:
    with pytest.raises(ValueError, match="refers to vertex 9"):
        write_mesh(TETRA_VERTICES, [[0, 1, 9]], "ply")
