"""What read_mesh reads: a path (str or os.PathLike), bytes-like objects, binary file objects."""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mesh_normal.files import LoadedMesh, MeshFileError, read_mesh
from tests.paths import DATA

COW = DATA / "cow.obj"
EXPECTED = read_mesh(COW.read_bytes(), "cow.obj")


def same(mesh: LoadedMesh) -> bool:
    return (
        mesh.format == "obj"
        and np.array_equal(mesh.vertices, EXPECTED.vertices)
        and np.array_equal(mesh.faces, EXPECTED.faces)
    )


class Named(os.PathLike[str]):
    """An os.PathLike that is not a pathlib.Path."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __fspath__(self) -> str:
        return str(self.path)


@pytest.mark.parametrize("make", [str, Path, Named], ids=["str", "Path", "PathLike"])
def test_a_path(make: Any) -> None:
    assert same(read_mesh(make(COW)))


@pytest.mark.parametrize("make", [bytes, bytearray, memoryview])
def test_bytes_like(make: Any) -> None:
    assert same(read_mesh(make(COW.read_bytes()), "cow.obj"))


def test_an_open_binary_file() -> None:
    with COW.open("rb") as file:
        assert same(read_mesh(file))


def test_a_bytes_io_and_a_non_seekable_reader() -> None:
    class Reader:
        def read(self) -> bytes:
            return COW.read_bytes()

    assert same(read_mesh(io.BytesIO(COW.read_bytes())))
    assert same(read_mesh(Reader()))


def ascii_ply() -> bytes:
    return (
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        b"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
        b"end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    )


def test_the_name_comes_from_the_path_or_the_file_object(tmp_path: Path) -> None:
    note = "The file is named as STL but holds PLY; it was read as PLY."
    path = tmp_path / "triangle.STL"
    path.write_bytes(ascii_ply())
    assert read_mesh(path).notes[0] == note  # the path's suffix, in any case
    with path.open("rb") as file:
        assert read_mesh(file).notes[0] == note
    assert note not in read_mesh(io.BytesIO(ascii_ply())).notes  # no name, no note
    assert "named as OBJ" in read_mesh(path, "triangle.obj").notes[0]  # filename wins


def test_the_name_tells_the_format_the_bytes_do_not(tmp_path: Path) -> None:
    path = tmp_path / "cube.obj"
    data = (
        b"# \0 (a NUL: not plain text, so not sniffed as OBJ)\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    )
    path.write_bytes(data)
    assert read_mesh(path).format == "obj"
    with pytest.raises(MeshFileError, match="not recognised"):
        read_mesh(io.BytesIO(data))


def test_a_file_descriptor_name_is_not_a_file_name(tmp_path: Path) -> None:
    path = tmp_path / "cow.obj"
    path.write_bytes(COW.read_bytes())
    descriptor = os.open(path, os.O_RDONLY)
    with open(descriptor, "rb") as file:  # its name is the int descriptor
        assert same(read_mesh(file))


def test_a_missing_file_is_python_s_file_not_found_error(tmp_path: Path) -> None:
    missing = tmp_path / "missing.obj"
    with pytest.raises(FileNotFoundError) as error:
        read_mesh(missing)
    assert error.value.filename == str(missing)
    with pytest.raises(FileNotFoundError):
        read_mesh(str(missing))


def test_a_directory_is_an_os_error(tmp_path: Path) -> None:
    with pytest.raises(IsADirectoryError):
        read_mesh(tmp_path)


def test_an_empty_file_on_disk_is_a_mesh_file_error(tmp_path: Path) -> None:
    path = tmp_path / "empty.stl"
    path.write_bytes(b"")
    with pytest.raises(MeshFileError, match="empty"):
        read_mesh(path)


def test_a_text_mode_file_is_a_type_error() -> None:
    with COW.open() as file, pytest.raises(TypeError, match=r"binary mode: open\(path, 'rb'\)"):
        read_mesh(file)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="binary mode"):
        read_mesh(io.StringIO("v 0 0 0"))  # type: ignore[arg-type]


def test_a_reader_that_gives_text_is_a_type_error() -> None:
    class TextReader:
        def read(self) -> str:
            return "v 0 0 0"

    with pytest.raises(TypeError, match="binary mode"):
        read_mesh(TextReader())  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("source", "named"),
    [(42, "int"), (None, "NoneType"), (["v 0 0 0"], "list"), (np.zeros(3), "ndarray")],
)
def test_another_type_is_a_type_error_naming_it(source: object, named: str) -> None:
    with pytest.raises(
        TypeError,
        match=rf"a path \(str or os.PathLike\), bytes or a binary file "
        rf"object, not {named}\.",
    ):
        read_mesh(source)  # type: ignore[arg-type]
