from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import trimesh

import mesh_normal as mn
from mesh_normal.files import (
    SUFFIXES,
    LoadedMesh,
    MeshFileError,
    read_mesh,
    read_mesh_files,
    write_mesh,
)
from tests.meshes import TETRA_FACES, TETRA_OBJ, TETRA_VERTICES, ascii_stl
from tests.paths import DATA

SAMPLES = {
    name: (DATA / name).read_bytes()
    for name in ("sphere.ply", "ant.ply", "nut.ply", "airplane.ply", "cube.obj", "cow.obj")
}
SAMPLES["tetra.stl"] = write_mesh(TETRA_VERTICES, TETRA_FACES, "stl")
SAMPLES["ascii.stl"] = ascii_stl(TETRA_VERTICES[TETRA_FACES], np.zeros((4, 3)))
SAMPLES["tetra.off"] = (
    b"OFF\n4 4 0\n"
    + b"".join(f"{x} {y} {z}\n".encode() for x, y, z in TETRA_VERTICES)
    + b"".join(f"3 {a} {b} {c}\n".encode() for a, b, c in TETRA_FACES)
)
SAMPLES["box.glb"] = trimesh.creation.box().export(file_type="glb")


def test_suffixes() -> None:
    assert SUFFIXES == {
        ".stl": "stl",
        ".obj": "obj",
        ".ply": "ply",
        ".off": "off",
        ".glb": "glb",
        ".gltf": "gltf",
        ".3mf": "3mf",
    }


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_format_from_the_bytes_alone(name: str) -> None:
    mesh = read_mesh(SAMPLES[name])
    assert mesh.format == SUFFIXES["." + name.rsplit(".", 1)[1]]
    assert mesh.faces.dtype == np.intp and mesh.vertices.dtype == np.float64


def test_content_wins_over_a_wrong_name_with_a_note() -> None:
    mesh = read_mesh(SAMPLES["sphere.ply"], "sphere.stl")
    assert mesh.format == "ply"
    assert mesh.notes[0] == "The file is named as STL but holds PLY; it was read as PLY."


@pytest.mark.parametrize(
    ("data", "filename", "message", "status"),
    [
        (b"", "a.stl", "The file is empty (0 bytes).", 400),
        (b"", None, "The file is empty (0 bytes).", 400),
        (b"hello world", "notes.txt", "The format of this .txt file is not supported", 415),
        (bytes(range(256)) * 4, None, "The file's format was not recognised", 415),
        (bytes(range(256)) * 4, "x.ply", "PLY header has no 'end_header'", 400),
        (b"\x00" * 10, "x.glb", "could not be read as GLB", 400),
    ],
)
def test_unreadable(data: bytes, filename: str | None, message: str, status: int) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, filename)
    assert message in str(error.value)
    assert error.value.status_code == status


def outcome(data: bytes, filename: str | None) -> LoadedMesh | MeshFileError:
    try:
        return read_mesh(data, filename)
    except MeshFileError as error:
        assert str(error) and error.status_code in (400, 415)  # noqa: PT017 (either outcome)
        return error


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_truncated_and_garbled_files_give_a_mesh_or_a_mesh_file_error(name: str) -> None:
    data = SAMPLES[name]
    rng = np.random.default_rng(len(data))
    cuts = sorted({*rng.integers(0, len(data), 25).tolist(), 1, 4, 80, 84, 100, len(data) - 1})
    for cut in cuts:
        for filename in (name, None):
            result = outcome(data[:cut], filename)
            if isinstance(result, LoadedMesh):
                assert np.isfinite(result.vertices).all()
                assert result.faces.min() >= 0 and result.faces.max() < len(result.vertices)
    for _ in range(25):
        garbled = np.frombuffer(data, dtype=np.uint8).copy()
        garbled[rng.integers(0, len(data), 8)] = rng.integers(0, 256, 8)
        outcome(garbled.tobytes(), name)
        outcome(garbled[: len(garbled) // 2].tobytes(), None)


def test_the_reader_s_arrays_are_read_only_and_trusted() -> None:
    mesh = read_mesh(TETRA_OBJ.encode(), "t.obj")
    assert mesh.from_reader
    assert not mesh.vertices.flags.writeable and not mesh.faces.flags.writeable
    checked = mesh.checked()
    assert checked.vertices is mesh.vertices and checked.faces is mesh.faces  # not checked again


def test_a_mesh_built_by_hand_is_checked_before_the_core_trusts_it() -> None:
    faces = np.array([[0, 1, 2], [0, 1, 10**7]])
    mesh = LoadedMesh(vertices=TETRA_VERTICES, faces=faces, format="obj", source_faces=2)
    with pytest.raises(ValueError, match="refers to vertex 10000000"):
        mesh.checked()
    with pytest.raises(ValueError, match="refers to vertex 10000000"):
        mn.analyse(mesh)


# --- Memory running out is the server's, never the file's (no 400 blaming the file) ---------


def _out_of_memory(*_: object, **__: object) -> None:
    raise MemoryError


@pytest.mark.parametrize(
    ("name", "module", "allocation"),
    [
        ("cow.obj", "mesh_normal.files.obj", "scan_obj"),
        ("sphere.ply", "mesh_normal.files.ply", "binary_items"),
        ("tetra.off", "mesh_normal.files.off", "triangulate"),
        ("ascii.stl", "mesh_normal.files.stl", "weld"),
        ("box.glb", "trimesh.exchange.gltf", "load_gltf"),
    ],
)
def test_memory_error_inside_a_reader_propagates(
    monkeypatch: pytest.MonkeyPatch, name: str, module: str, allocation: str
) -> None:
    monkeypatch.setattr(f"{module}.{allocation}", _out_of_memory)
    with pytest.raises(MemoryError):
        read_mesh(SAMPLES[name], name)


def test_memory_error_inside_a_zipped_gltf_propagates(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("trimesh.exchange.gltf.load_gltf", _out_of_memory)
    gltf = trimesh.creation.box().export(file_type="gltf")
    files = [(name, data) for name, data in gltf.items()]
    with pytest.raises(MemoryError):
        read_mesh_files(files)


def test_memory_error_in_draco_propagates(monkeypatch: pytest.MonkeyPatch) -> None:
    import DracoPy

    data = trimesh.Scene(trimesh.creation.box()).export(file_type="glb", extension_draco=True)
    monkeypatch.setattr(DracoPy, "decode", _out_of_memory)
    with pytest.raises(MemoryError):
        read_mesh(data, "box.glb")


def _same_mesh(one: LoadedMesh, two: LoadedMesh) -> None:
    assert one.notes == two.notes and one.format == two.format
    for name in ("vertices", "faces", "file_face_normals"):
        first, second = getattr(one, name), getattr(two, name)
        assert (first is None) == (second is None)
        if first is not None:
            assert first.dtype == second.dtype and first.tobytes() == second.tobytes()


@pytest.mark.parametrize("name", ["teapot.stl", "soup.stl"])
@pytest.mark.parametrize("suffix", [".stl", ".obj"])
def test_a_large_binary_stl_path_is_mapped_and_reads_as_its_bytes(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, name: str, suffix: str
) -> None:
    from mesh_normal.files import read as read_module

    data = (DATA / name).read_bytes()
    assert read_module.is_binary(data)
    path = tmp_path / f"mesh{suffix}"
    path.write_bytes(data)
    mapped = []
    real = read_module.read_mapped
    monkeypatch.setattr(read_module, "MAPPED_BYTES", 1)
    monkeypatch.setattr(read_module, "read_mapped", lambda *a: mapped.append(1) or real(*a))
    _same_mesh(read_mesh(path), read_mesh(data, path.name))
    assert mapped == [1]


@pytest.mark.parametrize(
    "change",
    [
        lambda data: data + b"\0",  # the length is not the header's count
        lambda data: b"PK\x03\x04" + data[4:],  # a zip's start: read as bytes
        lambda data: b"\xef\xbb\xbf" + data[3:],  # a byte order mark
    ],
)
def test_a_path_that_is_not_plainly_a_binary_stl_is_read_as_bytes(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, change: Callable[[bytes], bytes]
) -> None:
    from mesh_normal.files import read as read_module

    data = change((DATA / "soup.stl").read_bytes())
    path = tmp_path / "mesh.stl"
    path.write_bytes(data)
    monkeypatch.setattr(read_module, "MAPPED_BYTES", 1)
    assert read_module.mapped_binary_stl(path) is None
    assert read_module.mapped_binary_stl(tmp_path / "missing.stl") is None
