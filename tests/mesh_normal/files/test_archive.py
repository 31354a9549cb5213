"""A .zip holding one mesh file and its neighbours, and the guards against zip bombs."""

from __future__ import annotations

import contextlib
import io
import json
import random
import zipfile

import numpy as np
import pytest
import trimesh

from mesh_normal.files import MeshFileError, archive, read_mesh
from tests.meshes import CUBE_OBJ
from tests.paths import DATA


def zipped(members: dict[str, bytes], method: int = zipfile.ZIP_DEFLATED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as file:
        for name, data in members.items():
            file.writestr(name, data)
    return buffer.getvalue()


def gltf_with_bins() -> dict[str, bytes]:
    """A box as a .gltf with its buffers in separate .bin files, as exporters write it."""
    files = trimesh.Scene(trimesh.creation.box()).export(file_type="gltf")
    assert any(name.endswith(".bin") for name in files)
    return files


def test_gltf_with_its_bin_in_a_folder() -> None:
    members = {f"model/{name}": data for name, data in gltf_with_bins().items()}
    members["model/texture.png"] = b"\x89PNG not read"
    mesh = read_mesh(zipped(members), "model.zip")
    assert mesh.format == "gltf" and len(mesh.faces) == 12
    np.testing.assert_allclose(np.abs(mesh.vertices), 0.5)
    assert mesh.notes[0] == "Read model/model.gltf from the .zip file."


def test_gltf_without_its_bin_says_so() -> None:
    members = {name: data for name, data in gltf_with_bins().items() if name.endswith(".gltf")}
    with pytest.raises(MeshFileError) as error:
        read_mesh(zipped(members))
    assert error.value.status_code == 400 and "which is not in the .zip" in str(error.value)


def test_obj_with_its_mtl() -> None:
    members = {"cube.obj": ("mtllib cube.mtl\n" + CUBE_OBJ).encode(), "cube.mtl": b"newmtl a\n"}
    mesh = read_mesh(zipped(members), "cube.zip")
    assert mesh.format == "obj" and len(mesh.faces) == 12


def test_a_stored_glb_is_read_too() -> None:
    data = zipped({"box.glb": trimesh.creation.box().export(file_type="glb")}, zipfile.ZIP_STORED)
    assert len(read_mesh(data).faces) == 12


@pytest.mark.parametrize(
    ("members", "message"),
    [
        ({"readme.txt": b"hi", "__MACOSX/._a.obj": b"x"}, "holds no mesh file"),
        ({"a.obj": CUBE_OBJ.encode(), "b/c.stl": b"solid"}, "holds 2 mesh files (a.obj, b/c.stl)"),
        ({"../evil.obj": CUBE_OBJ.encode()}, "names a member outside itself: ../evil.obj"),
        ({"/etc/evil.obj": CUBE_OBJ.encode()}, "names a member outside itself"),
    ],
)
def test_refused_archives(members: dict[str, bytes], message: str) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(zipped(members), "x.zip")
    assert error.value.status_code == 400 and message in str(error.value)


def test_a_broken_zip_is_a_400() -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(b"PK\x03\x04" + b"\0" * 40, "x.zip")
    assert error.value.status_code == 400 and "could not be opened" in str(error.value)


def test_a_zip_bomb_is_refused_before_it_unpacks() -> None:
    data = zipped({"big.obj": b"\0" * 10_000_000})  # about 10 kB deflated
    with pytest.raises(MeshFileError, match="would unpack to 10,000,000 bytes"):
        read_mesh(data)


def test_too_many_members(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(archive, "MAX_MEMBERS", 3)
    data = zipped({f"{index}.txt": b"" for index in range(4)})
    with pytest.raises(MeshFileError, match="holds 4 members; at most 3"):
        read_mesh(data)


def test_members_larger_than_they_state_are_cut_off() -> None:
    data = zipped({"a.obj": b"0123456789"})
    with zipfile.ZipFile(io.BytesIO(data)) as file:
        budget = archive.Budget(5)
        with pytest.raises(MeshFileError, match="more than its members state"):
            budget.read(file, file.infolist()[0])


GLTF = DATA / "gltf"


def zip_of(*names: str) -> bytes:
    return zipped({name: (GLTF / name).read_bytes() for name in names})


def test_real_gltf_with_its_bin() -> None:
    mesh = read_mesh(zip_of("Box.gltf", "Box0.bin"), "box.zip")
    assert (mesh.format, len(mesh.faces)) == ("gltf", 12)
    np.testing.assert_allclose(np.abs(mesh.vertices), 0.5)
    assert trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).volume == pytest.approx(1)


def test_real_gltf_alone_names_its_bin() -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh((GLTF / "Box.gltf").read_bytes(), "Box.gltf")
    assert error.value.status_code == 400
    assert "Box0.bin" in str(error.value) and "send a .zip" in str(error.value)


@pytest.mark.parametrize(("gltf", "faces"), [("BoxDraco.gltf", 12), ("DracoSparseMesh.gltf", 102)])
def test_real_draco(gltf: str, faces: int) -> None:
    header = json.loads((GLTF / gltf).read_bytes())
    buffers = [buffer["uri"] for buffer in header["buffers"]]
    mesh = read_mesh(zip_of(gltf, *buffers), "draco.zip")
    assert len(mesh.faces) == faces
    position = header["accessors"][header["meshes"][0]["primitives"][0]["attributes"]["POSITION"]]
    np.testing.assert_allclose(mesh.vertices.min(axis=0), position["min"], rtol=1e-3)
    np.testing.assert_allclose(mesh.vertices.max(axis=0), position["max"], rtol=1e-3)
    assert trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).area_faces.min() > 0


def test_real_meshopt_is_a_415_naming_it() -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(GLTF / "BoxMeshopt.glb")
    assert error.value.status_code == 415
    assert "This glTF needs EXT_meshopt_compression, which is not supported" in str(error.value)


def test_the_unpack_limit() -> None:
    assert archive.unpack_limit(100) == 1 << 20  # a small file may compress very well
    assert archive.unpack_limit(1_000_000) == 50_000_000
    assert archive.unpack_limit(1 << 30) == 1 << 30


def _zip_of(name: str, data: bytes, method: int = zipfile.ZIP_DEFLATED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as archive:
        archive.writestr(name, data)
    return buffer.getvalue()


def test_a_damaged_member_is_a_400_naming_it() -> None:
    damaged = bytearray(_zip_of("cube.obj", CUBE_OBJ.encode()))
    damaged[40] ^= 0xFF  # inside the deflate stream
    with pytest.raises(MeshFileError, match=r"The member cube\.obj of the archive could not be"):
        read_mesh(bytes(damaged), "cube.zip")


def test_mutated_archives_never_raise_anything_but_the_file_error() -> None:
    good = _zip_of("cube.obj", CUBE_OBJ.encode())
    rng = random.Random(1)
    for _ in range(500):
        mutated = bytearray(good)
        for _ in range(rng.randint(1, 4)):
            mutated[rng.randrange(len(mutated))] = rng.randrange(256)
        with contextlib.suppress(MeshFileError):
            read_mesh(bytes(mutated), "cube.zip")


def test_a_zip_inside_a_zip_is_refused_at_any_depth() -> None:
    archive = _zip_of("cube.obj", CUBE_OBJ.encode())
    for _ in range(400):  # each level would get a budget of its own
        archive = _zip_of("m.obj", archive, zipfile.ZIP_STORED)
    with pytest.raises(MeshFileError, match=r"m\.obj of the \.zip file is itself a \.zip"):
        read_mesh(archive, "deep.zip")
