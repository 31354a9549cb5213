"""The one table of formats, and what is derived from it."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

from mesh_normal.files import FORMATS, SUFFIXES, WRITABLE, read_mesh, write_mesh
from mesh_normal.files.formats import suffix_format
from tests.meshes import TETRA_FACES, TETRA_VERTICES
from tests.paths import ROOT


def test_the_table() -> None:
    assert list(FORMATS) == ["ply", "stl", "obj", "off", "glb", "gltf", "3mf"]
    assert [entry.title for entry in FORMATS.values()] == [
        "PLY",
        "STL",
        "OBJ",
        "OFF",
        "GLB",
        "glTF",
        "3MF",
    ]
    assert WRITABLE == ("ply", "stl", "obj", "off", "glb")
    assert FORMATS["stl"].media_type == "model/stl"
    assert FORMATS["obj"].media_type == "model/obj"
    assert FORMATS["glb"].media_type == "model/gltf-binary"
    assert FORMATS["3mf"].media_type == "model/3mf"


@pytest.mark.parametrize("name", sorted(FORMATS))
def test_every_format_has_its_reader_and_writer_in_its_module(name: str) -> None:
    entry = FORMATS[name]
    module = importlib.import_module(f"mesh_normal.files.{entry.module}")
    assert callable(getattr(module, f"read_{name}"))
    assert callable(getattr(module, f"write_{name}", None)) is entry.writable


@pytest.mark.parametrize("name", WRITABLE)
def test_each_writer_writes_what_its_reader_reads(name: str) -> None:
    data = write_mesh(TETRA_VERTICES, TETRA_FACES, name)
    mesh = FORMATS[name].read(data)
    corners = mesh.vertices[mesh.faces]  # STL welds: compare corners
    assert corners.tolist() == TETRA_VERTICES[TETRA_FACES].tolist()
    assert read_mesh(data).format == name


def test_a_format_without_a_writer_says_so() -> None:
    with pytest.raises(ValueError, match="3MF files cannot be written"):
        FORMATS["3mf"].write(TETRA_VERTICES, TETRA_FACES)


@pytest.mark.parametrize(
    ("filename", "expected"),
    [
        ("a.stl", "stl"),
        ("A.STL", "stl"),
        ("scene.v2.gltf", "gltf"),
        ("x.Ply", "ply"),
        ("notes.txt", None),
        ("obj", None),
        ("", None),
        (None, None),
    ],
)
def test_suffix_format(filename: str | None, expected: str | None) -> None:
    assert suffix_format(filename) == expected


def test_suffixes_come_from_the_table() -> None:
    assert {
        suffix: name for name, entry in FORMATS.items() for suffix in entry.suffixes
    } == SUFFIXES


def test_the_table_loads_neither_numpy_nor_a_reader() -> None:
    script = (
        "import sys\n"
        "from mesh_normal.files import FORMATS, SUFFIXES, WRITABLE\n"
        "print(sorted(name for name in sys.modules if name.startswith(('numpy', 'mesh_normal'))))"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert (
        completed.stdout.strip()
        == "['mesh_normal', 'mesh_normal._lazy', 'mesh_normal.files', 'mesh_normal.files.formats']"
    )
