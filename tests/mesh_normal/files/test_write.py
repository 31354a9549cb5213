from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mesh_normal import face_normals
from mesh_normal.files import MeshFileError, read_mesh, write_mesh
from mesh_normal.files.write import unkept
from tests.meshes import TETRA_FACES, TETRA_VERTICES

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


@pytest.mark.parametrize("suffix", [".ply", ".stl", ".obj", ".OBJ"])
def test_write_to_a_path_takes_the_format_from_the_suffix(tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"tetra{suffix}"
    assert write_mesh(TETRA_VERTICES, TETRA_FACES, path=path) is None
    assert path.read_bytes() == write_mesh(TETRA_VERTICES, TETRA_FACES, suffix[1:].lower())
    assert read_mesh(path).format == suffix[1:].lower()


def test_write_to_a_str_path_with_a_format_that_overrides_the_suffix(tmp_path: Path) -> None:
    path = tmp_path / "tetra.data"
    write_mesh(TETRA_VERTICES, TETRA_FACES, "stl", path=str(path))
    assert path.read_bytes() == write_mesh(TETRA_VERTICES, TETRA_FACES, "stl")


def test_write_replaces_an_existing_file(tmp_path: Path) -> None:
    path = tmp_path / "tetra.obj"
    path.write_bytes(b"old" * 10_000)
    write_mesh(TETRA_VERTICES, TETRA_FACES, path=path)
    assert path.read_bytes() == write_mesh(TETRA_VERTICES, TETRA_FACES, "obj")


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("tetra.3mf", "Cannot write '3mf' files; the formats are ply, stl, obj, off, glb."),
        ("tetra.dat", "The format cannot be told from the name 'tetra.dat'"),
        ("tetra", "The format cannot be told from the name 'tetra'"),
    ],
)
def test_a_path_without_a_writable_suffix(tmp_path: Path, name: str, message: str) -> None:
    with pytest.raises(MeshFileError) as error:
        write_mesh(TETRA_VERTICES, TETRA_FACES, path=tmp_path / name)
    assert str(error.value).startswith(message)
    assert error.value.status_code == 415
    assert not (tmp_path / name).exists()


def test_neither_format_nor_path_is_a_type_error() -> None:
    with pytest.raises(TypeError, match="a file_format or a path"):
        write_mesh(TETRA_VERTICES, TETRA_FACES)  # type: ignore[call-overload]


def test_a_bad_mesh_writes_no_file(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="refers to vertex 9"):
        write_mesh(TETRA_VERTICES, [[0, 1, 9]], path=tmp_path / "bad.ply")
    assert not (tmp_path / "bad.ply").exists()


def test_a_missing_folder_is_python_s_os_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        write_mesh(TETRA_VERTICES, TETRA_FACES, path=tmp_path / "no" / "such.ply")


def test_a_format_and_a_suffix_that_disagree_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "tetra.stl"
    with pytest.raises(MeshFileError, match=r"'tetra\.stl' names STL but the file_format is 'ply'"):
        write_mesh(TETRA_VERTICES, TETRA_FACES, "ply", path=path)
    assert not path.exists()


def test_a_failed_write_leaves_the_old_file_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "tetra.ply"
    path.write_bytes(b"the old file")

    def half_then_full_disk(self: Path, data: bytes) -> int:
        with open(self, "wb") as file:
            file.write(data[: len(data) // 2])
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_bytes", half_then_full_disk)
    with pytest.raises(OSError, match="No space left"):
        write_mesh(TETRA_VERTICES, TETRA_FACES, path=path)
    assert path.read_bytes() == b"the old file"
    assert sorted(item.name for item in tmp_path.iterdir()) == ["tetra.ply"]  # no temporary left


def test_two_objects_or_more_are_named_as_left_out() -> None:
    """Every file written is one mesh; one object is the mesh itself."""
    assert (
        unkept("stl", None, objects=0)
        == unkept("stl", None, objects=1)
        == unkept("obj", None)
        == []
    )
    assert unkept("ply", None, objects=2) == [
        "the division into 2 objects (the PLY written is one mesh)"
    ]
    colours = np.zeros((4, 3), dtype=np.uint8)
    assert unkept("stl", colours, objects=1_000) == [
        "vertex colours (STL holds none)",
        "the division into 1,000 objects (the STL written is one mesh)",
    ]
