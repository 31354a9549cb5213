"""A .zip holding one mesh file and its neighbours, and the guards against zip bombs."""

from __future__ import annotations

import contextlib
import io
import json
import random
import time
import zipfile

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.files import MeshFileError, archive, expansion, read_mesh, read_mesh_files
from tests.hostile_archives import HOSTILE, directory_of, zip64_claim
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
    assert mesh.notes[0] == (
        "Read model/model.gltf with model/gltf_buffer_0.bin and model/gltf_buffer_1.bin from "
        "the .zip file; not needed for the geometry: model/texture.png."
    )


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


def test_a_zip_bomb_is_stopped_as_it_unpacks() -> None:
    data = zipped({"big.obj": b"\0" * 10_000_000})  # about 10 kB deflated
    with (
        expansion.expanding(len(data), most=20 * 2**20) as budget,
        pytest.raises(expansion.ExpansionTooLarge) as error,
    ):
        read_mesh(data)
    assert error.value.status_code == 413
    assert "unpacking big.obj from the .zip file would take about" in str(error.value)
    assert budget.used <= budget.limit  # charged a chunk at a time, never past the limit


def test_members_charge_the_memory_their_format_takes() -> None:
    obj = ("mtllib cube.mtl\n" + CUBE_OBJ).encode()
    data = zipped({"cube.obj": obj, "cube.mtl": b"newmtl a\n" * 1000})
    with expansion.expanding(len(data)) as budget:
        read_mesh(data)
    assert budget.used == len(obj) * archive.MEMORY_PER_BYTE["obj"]  # the .mtl was not read


def test_too_many_members(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(archive, "MAX_MEMBERS", 3)
    data = zipped({f"{index}.txt": b"" for index in range(4)})
    with pytest.raises(MeshFileError, match=r"The \.zip file lists 4 members; at most 3") as error:
        read_mesh(data)
    assert error.value.status_code == 413


def test_a_directory_of_400001_entries_is_refused_before_it_is_parsed() -> None:
    started = time.perf_counter()
    for data in (zip64_claim(400_001), (HOSTILE / "zip_many_entries.zip").read_bytes()):
        with pytest.raises(MeshFileError) as error:
            read_mesh(data, "many.zip")
        assert error.value.status_code == 413
        assert str(error.value) == "The .zip file lists 400,001 members; at most 1,000."
    assert time.perf_counter() - started < 1


def test_a_real_directory_of_100001_entries_is_refused_at_once() -> None:
    data = directory_of(100_001)  # its 16-bit count wraps to 34,465, still too many
    assert len(zipfile.ZipFile(io.BytesIO(directory_of(3))).infolist()) == 3  # a real zip
    started = time.perf_counter()
    with pytest.raises(MeshFileError, match="lists 34,465 members; at most 1,000"):
        read_mesh(data, "many.zip")
    assert time.perf_counter() - started < 1


def test_a_directory_stating_fewer_entries_than_it_holds_is_counted() -> None:
    """zipfile reads the directory by its size, whatever its count says: the records are
    counted, a thousand and one at most."""
    started = time.perf_counter()
    with pytest.raises(MeshFileError, match="lists more than 1,000 members; at most 1,000"):
        read_mesh(directory_of(100_001, stated=1), "many.zip")
    assert time.perf_counter() - started < 1
    assert archive.listed_members(directory_of(5, stated=1)) == (1, 5)
    assert archive.listed_members(b"PK\x03\x04 no end") is None


def test_an_encrypted_member_is_named_in_our_words() -> None:
    data = bytearray(_zip_of("cube.obj", CUBE_OBJ.encode()))
    directory = data.rindex(b"PK\x01\x02")
    data[directory + 8] |= 1  # the directory's flag: encrypted
    with pytest.raises(MeshFileError) as error:
        read_mesh(bytes(data), "cube.zip")
    assert str(error.value) == (
        "The member cube.obj of the .zip file could not be unpacked: it is encrypted."
    )


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"PK\x03\x04" + b"\0" * 40, "it is not a zip archive, or its end is missing"),
        (directory_of(2)[:-30] + directory_of(2)[-22:], "its directory or headers are damaged"),
    ],
)
def test_an_archive_that_cannot_be_opened_says_why_in_our_words(data: bytes, reason: str) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, "x.zip")
    assert str(error.value) == f"The .zip file could not be opened: {reason}."


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
    assert "Box0.bin" in str(error.value) and "together in one request, or in a .zip" in str(
        error.value
    )


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


def _zip_of(name: str, data: bytes, method: int = zipfile.ZIP_DEFLATED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as archive:
        archive.writestr(name, data)
    return buffer.getvalue()


def test_a_damaged_member_is_a_400_naming_it() -> None:
    damaged = bytearray(_zip_of("cube.obj", CUBE_OBJ.encode()))
    damaged[40] ^= 0xFF  # inside the deflate stream
    with pytest.raises(MeshFileError, match=r"The member cube\.obj of the \.zip file could not be"):
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


# --- Several files sent one by one: read as the members of one .zip ---------------------------


def box_files() -> list[tuple[str | None, bytes]]:
    return [(name, (GLTF / name).read_bytes()) for name in ("Box.gltf", "Box0.bin")]


MTL = b"newmtl red\nKd 1 0 0\n"


def test_several_files_are_read_as_the_zip_of_them() -> None:
    files = box_files()
    mesh = read_mesh_files(files)
    zipped_mesh = read_mesh(zip_of("Box.gltf", "Box0.bin"), "box.zip")
    assert (mesh.format, len(mesh.faces)) == ("gltf", 12)
    np.testing.assert_array_equal(mesh.vertices, zipped_mesh.vertices)
    np.testing.assert_array_equal(mesh.faces, zipped_mesh.faces)
    assert mesh.notes[0] == "Read Box.gltf with Box0.bin from the 2 files sent."
    assert mesh.files == zipped_mesh.files == ("Box.gltf", "Box0.bin")
    assert zipped_mesh.notes[0] == "Read Box.gltf with Box0.bin from the .zip file."
    assert mesh.notes[1:] == zipped_mesh.notes[1:]


@given(st.permutations(range(4)))
@settings(max_examples=24, deadline=None)
def test_the_order_of_the_files_does_not_matter(order: list[int]) -> None:
    files = [*box_files(), ("notes.txt", b"hi"), ("Box.png", b"\x89PNG")]
    mesh = read_mesh_files([files[index] for index in order])
    assert len(mesh.faces) == 12
    assert mesh.notes[0].startswith("Read Box.gltf with Box0.bin from the 4 files sent; ")
    assert "not needed for the geometry: " in mesh.notes[0]


def test_obj_with_its_mtl_sent_as_two_files() -> None:
    obj = ("mtllib model.mtl\nusemtl red\n" + CUBE_OBJ).encode()
    mesh = read_mesh_files([("model.mtl", MTL), ("model.obj", obj)])
    assert (mesh.format, len(mesh.faces), mesh.files) == ("obj", 12, ("model.obj",))
    assert mesh.notes[0] == (
        "Read model.obj from the 2 files sent; not needed for the geometry: model.mtl."
    )


def test_one_file_alone_is_read_as_read_mesh_reads_it() -> None:
    data = zip_of("Box.gltf", "Box0.bin")
    alone = read_mesh_files([("box.zip", data)])
    assert alone.notes == read_mesh(data, "box.zip").notes
    assert read_mesh_files([(None, CUBE_OBJ.encode())]).notes == read_mesh(CUBE_OBJ.encode()).notes


def test_files_in_a_folder_find_each_other_as_in_a_zip() -> None:
    files = [(f"model/{name}", data) for name, data in box_files()]
    assert len(read_mesh_files(files).faces) == 12
    misplaced = [files[0], ("other/Box0.bin", files[1][1])]
    with pytest.raises(MeshFileError, match=r"refers to the separate file model/Box0\.bin"):
        read_mesh_files(misplaced)


@pytest.mark.parametrize(
    ("files", "message"),
    [
        ([("Box.gltf", b"{}"), ("Box.gltf", b"{}")], "Two of the files sent are named Box.gltf"),
        ([("a/b.bin", b""), ("a//./b.bin", b"")], "Two of the files sent are named a/b.bin"),
        ([("Box.gltf", b""), ("../Box0.bin", b"")], "named outside its folder: ../Box0.bin"),
        ([("/etc/Box.gltf", b""), ("x.bin", b"")], "named outside its folder: /etc/Box.gltf"),
        ([("C:\\x\\a.obj", b""), ("x.bin", b"")], "named outside its folder: C:/x/a.obj"),
        ([("a.obj", b""), ("", b"x")], "File 2 of the 2 sent has no name"),
        ([("a.obj", b""), ("b\n.bin", b"")], "A file name holds control characters: 'b\\n.bin'"),
        ([("a.obj", b""), ("b.zip", b"PK\x05\x06")], "b.zip is a .zip among several files"),
        ([("a.obj", _zip_of("c.obj", b"")), ("x.mtl", b"")], "a.obj is a .zip among several"),
        ([("readme.txt", b"hi"), ("x.bin", b"")], "The 2 files sent hold no mesh file"),
        ([("a.obj", b""), ("b.stl", b"")], "The 2 files sent hold 2 mesh files (a.obj, b.stl)"),
        ([("Box.gltf", (GLTF / "Box.gltf").read_bytes()), ("notes.txt", b"")], "Box0.bin, which"),
        ([], "No file was sent"),
    ],
)
def test_refused_files(files: list[tuple[str | None, bytes]], message: str) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh_files(files)
    assert error.value.status_code == 400 and message in str(error.value)
    sentence = str(error.value)
    assert sentence.endswith(".") and ". " not in sentence[:-1]


def test_too_many_files(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(archive, "MAX_MEMBERS", 3)
    with pytest.raises(MeshFileError, match="4 files were sent; at most 3 at once"):
        read_mesh_files([(f"{index}.txt", b"") for index in range(4)])


def test_a_zip_naming_a_member_twice_is_refused() -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as file:
        file.writestr("a.obj", CUBE_OBJ)
        with pytest.warns(UserWarning, match="Duplicate"):
            file.writestr("a.obj", "v 0 0 0\n")
    with pytest.raises(MeshFileError, match=r"holds two members named a\.obj"):
        read_mesh(buffer.getvalue(), "twice.zip")


NAMES = st.sampled_from(
    ["Box.gltf", "Box0.bin", "a.obj", "a.mtl", "x.zip", "../b.bin", "/c.stl", "d\\e.ply", ""]
) | st.text(max_size=12)
CONTENTS = st.sampled_from(
    [(GLTF / "Box.gltf").read_bytes(), (GLTF / "Box0.bin").read_bytes(), CUBE_OBJ.encode(), b""]
) | st.binary(max_size=64)


@given(st.lists(st.tuples(NAMES, CONTENTS), max_size=5))
@settings(max_examples=300, deadline=None)
def test_any_files_give_a_mesh_or_one_file_error(files: list[tuple[str, bytes]]) -> None:
    try:
        mesh = read_mesh_files(files)
    except MeshFileError as error:
        refused = error
    else:
        refused = None
        assert len(mesh.faces) > 0
        if len(files) > 1:
            assert mesh.files and mesh.notes[0].startswith(f"Read {mesh.files[0]}")
    if refused is not None:
        assert 400 <= refused.status_code < 500
        assert str(refused).endswith(".") and "\n" not in str(refused)
