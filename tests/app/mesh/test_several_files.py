"""Several files in one multipart request (the field ``file`` repeated): read as the members of
one .zip, on every route that takes a mesh; refused with one sentence where they cannot be."""

from __future__ import annotations

import io
import os
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.config import UPLOAD_FILES
from app.main import create_app
from mesh_normal.files import read_mesh
from tests.conftest import Page, assert_error
from tests.meshes import CUBE_OBJ, CUBE_ONE_FLIPPED_OBJ
from tests.paths import DATA

GLTF = DATA / "gltf"
BOX = [("file", (name, (GLTF / name).read_bytes())) for name in ("Box.gltf", "Box0.bin")]
BOX_BYTES = sum(len(data) for _, (_, data) in BOX)
MTL = b"newmtl red\nKd 1 0 0\n"


def obj_with_mtl(obj: str = CUBE_ONE_FLIPPED_OBJ) -> list[tuple[str, tuple[str, bytes]]]:
    text = "mtllib model.mtl\nusemtl red\n" + obj
    return [("file", ("model.obj", text.encode())), ("file", ("model.mtl", MTL))]


@pytest.mark.parametrize("order", [1, -1])
def test_a_gltf_with_its_bin(client: TestClient, order: int) -> None:
    response = client.post("/api/mesh", files=BOX[::order])
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["file"] == {"name": "Box.gltf", "format": "gltf", "bytes": BOX_BYTES}
    assert (report["faces"], report["orientation"]) == (12, "outward")
    assert report["notes"][0] == "Read Box.gltf with Box0.bin from the 2 files sent."


def test_the_same_report_as_the_zip_of_the_files(client: TestClient) -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for _, (name, data) in BOX:
            archive.writestr(name, data)
    zipped = client.post("/api/mesh", files={"file": ("box.zip", buffer.getvalue())}).json()
    several = client.post("/api/mesh", files=BOX).json()
    for key in ("file", "notes"):
        zipped.pop(key), several.pop(key)
    assert several == zipped


def test_an_obj_with_its_mtl(client: TestClient) -> None:
    report = client.post("/api/mesh", files=obj_with_mtl()).json()
    assert (report["file"]["name"], report["faces"], report["fix"]["faces_flipped"]) == (
        "model.obj",
        12,
        1,
    )
    assert report["notes"][0] == (
        "Read model.obj from the 2 files sent; not needed for the geometry: model.mtl."
    )


def test_the_fix_and_the_normals_take_several_files(client: TestClient) -> None:
    response = client.post("/api/mesh/fix", files=obj_with_mtl())
    assert response.status_code == 200, response.text
    assert response.headers["content-disposition"] == 'attachment; filename="model-fixed.obj"'
    assert response.headers["x-faces-flipped"] == "1"
    fixed = read_mesh(response.content, "fixed.obj")
    assert np.array_equal(fixed.vertices, read_mesh(CUBE_OBJ.encode(), "c.obj").vertices)
    response = client.post("/api/mesh/normals", params={"kind": "face"}, files=BOX)
    assert response.status_code == 200, response.text
    assert response.headers["content-disposition"].endswith('filename="Box-face-normals.json"')
    assert response.json()["shape"] == [12, 3]


@pytest.mark.parametrize(
    ("files", "status", "words"),
    [
        ([BOX[0], BOX[0]], 400, ("Two of the files sent are named Box.gltf",)),
        ([BOX[0], ("file", ("../Box0.bin", b""))], 400, ("outside its folder", "../Box0.bin")),
        ([BOX[0], ("file", ("/tmp/Box0.bin", b""))], 400, ("outside its folder", "/tmp/Box0.bin")),
        ([BOX[0], ("file", ("box.zip", b"PK\x05\x06" + b"\0" * 18))], 400, ("is a .zip among",)),
        ([BOX[0], ("file", ("notes.txt", b"hi"))], 400, ("Box0.bin", "not among the files sent")),
        ([("file", ("a.txt", b"x")), ("file", ("b.txt", b"y"))], 400, ("hold no mesh file",)),
        ([*BOX, ("file", ("cube.obj", CUBE_OBJ.encode()))], 400, ("hold 2 mesh files",)),
        ([("file", ("a.obj", b"")), ("file", ("a.mtl", MTL))], 400, ("empty",)),
    ],
)
def test_refused_with_one_sentence_on_every_route(
    client: TestClient, files: list[tuple[str, tuple[str, bytes]]], status: int, words: tuple[str]
) -> None:
    for path in ("/api/mesh", "/api/mesh/normals", "/api/mesh/fix"):
        assert_error(client.post(path, files=files), status, "file", *words)


def test_a_file_without_a_name_among_several(client: TestClient) -> None:
    """As a browser sends a file input left empty: a part with ``filename=""``."""
    part = 'Content-Disposition: form-data; name="file"; filename="{}"\r\n\r\n'
    body = b"".join(
        b"--x\r\n" + part.format(name).encode() + data + b"\r\n"
        for name, data in (("Box.gltf", (GLTF / "Box.gltf").read_bytes()), ("", b""))
    )
    response = client.post(
        "/api/mesh",
        content=body + b"--x--\r\n",
        headers={"content-type": "multipart/form-data; boundary=x"},
    )
    assert_error(response, 400, "file", "File 2 of the 2 sent has no name")


def test_a_text_field_among_the_files(client: TestClient) -> None:
    response = client.post("/api/mesh", files=BOX, data={"file": "v 0 0 0"})
    assert_error(response, 422, "file", "must be a file, not a text field")


def test_more_files_than_the_cap(client: TestClient) -> None:
    files = [("file", (f"{index}.txt", b"")) for index in range(UPLOAD_FILES)]
    response = client.post("/api/mesh", files=[*files, BOX[0]])
    assert_error(response, 400, "file", f"At most {UPLOAD_FILES} files", ".zip")
    at_the_cap = client.post("/api/mesh", files=[*files[:-2], *BOX])
    assert at_the_cap.status_code == 200, at_the_cap.text
    assert at_the_cap.json()["notes"][0].endswith("0.txt, 1.txt, 2.txt, 3.txt, 4.txt and 93 more.")


@pytest.fixture(scope="module")
def small_limit() -> Iterator[TestClient]:
    with TestClient(create_app(upload_limit=4000), raise_server_exceptions=False) as client:
        yield client


def test_the_upload_limit_counts_every_file_together(small_limit: TestClient) -> None:
    assert small_limit.post("/api/mesh", files=obj_with_mtl()).status_code == 200
    padding = ("file", ("padding.txt", b"#" * 2000))
    body = assert_error(
        small_limit.post("/api/mesh", files=[*obj_with_mtl(), padding, padding]),
        413,
        None,
        "larger than",
    )
    assert "3.906 KB" in body["error"]


@pytest.mark.skipif(not Path("/proc/self/fd").exists(), reason="needs /proc")
def test_no_file_outlives_its_request(client: TestClient) -> None:
    """Files beyond 1 MB (Starlette's default spool) leave no file open afterwards."""
    big = ("file", ("big.txt", b"# padding past the spooling threshold\n" * 30_000))
    client.post("/api/mesh", files=obj_with_mtl())  # warm up
    before = set(os.listdir("/proc/self/fd"))
    for path in ("/api/mesh", "/mesh"):
        assert client.post(path, files=[*obj_with_mtl(), big, big]).status_code == 400  # twice
        assert client.post(path, files=[*obj_with_mtl(), big]).status_code == 200
    assert set(os.listdir("/proc/self/fd")) <= before


def test_the_page_takes_several_files_and_names_them(client: TestClient) -> None:
    form = Page(client.get("/mesh").text)
    field = form.one("input", id="mesh-file")
    assert "multiple" in field
    accepted = (field["accept"] or "").split(",")
    assert {".gltf", ".zip", ".bin", ".mtl"} <= set(accepted)  # the chooser offers the .bin too
    assert "a .gltf with its .bin, or an .obj with its .mtl, or a .zip" in form.text(
        "mesh-file-help"
    )
    response = client.post("/mesh", files=BOX)
    assert response.status_code == 200, response.text
    page = Page(response.text)
    assert page.text("mesh-files") == "Files: Box.gltf (read) · Box0.bin (read)"
    assert "Read Box.gltf with Box0.bin from the 2 files sent." in response.text
    assert page.text("mesh-curl") == "curl -F file=@Box.gltf -F file=@Box0.bin /api/mesh"


def test_the_page_lists_the_members_read_from_a_zip(client: TestClient) -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for _, (name, data) in BOX:
            archive.writestr(f"box/{name}", data)
        archive.writestr("box/box.png", b"\x89PNG")
    response = client.post("/mesh", files={"file": ("box.zip", buffer.getvalue())})
    page = Page(response.text)
    assert page.text("mesh-files") == "Files: box/Box.gltf (read) · box/Box0.bin (read)"
    assert "not needed for the geometry: box/box.png." in response.text
    one = Page(client.post("/mesh", files={"file": ("c.obj", CUBE_OBJ.encode())}).text)
    assert not one.find("p", id="mesh-files")  # one file read alone: nothing to list
