"""A .zip upload (a .gltf with its .bin), glTF the API refuses with a 415 naming why, and hostile
archives and 3MF packages refused with one sentence."""

from __future__ import annotations

import io
import json
import struct
import time
import zipfile

import pytest
import trimesh
from fastapi.testclient import TestClient

from tests.conftest import Page, assert_error
from tests.hostile_archives import HOSTILE


def test_a_zip_holding_gltf_and_bin(client: TestClient) -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in trimesh.Scene(trimesh.creation.box()).export(file_type="gltf").items():
            archive.writestr(name, data)
    response = client.post("/api/mesh", files={"file": ("box.zip", buffer.getvalue())})
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["file"]["format"] == "gltf" and report["faces"] == 12
    assert report["orientation"] == "outward"


def test_meshopt_is_a_415_naming_it(client: TestClient) -> None:
    text = json.dumps(
        {"asset": {"version": "2.0"}, "extensionsRequired": ["EXT_meshopt_compression"]}
    ).encode()
    text += b" " * (-len(text) % 4)
    data = struct.pack("<III", 0x46546C67, 2, 20 + len(text))
    data += struct.pack("<II", len(text), 0x4E4F534A) + text
    response = client.post("/api/mesh", files={"file": ("m.glb", data)})
    assert_error(response, 415, "file", "EXT_meshopt_compression", "not supported")


def test_the_form_accepts_zip(client: TestClient) -> None:
    field = Page(client.get("/mesh").text).one("input", id="mesh-file")
    assert ".zip" in (field["accept"] or "").split(",")


@pytest.mark.parametrize(
    ("name", "status", "words"),
    [
        ("zip_many_entries.zip", 413, "The .zip file lists 400,001 members; at most 1,000."),
        ("3mf_utf16_dtd.3mf", 400, "The 3MF file's XML declares a DTD (or entities)"),
        ("3mf_billion_laughs_utf16.3mf", 400, "The 3MF file's XML declares a DTD (or entities)"),
        ("3mf_in_zip.zip", 413, "expands too far: the 3MF file's XML elements would take"),
        ("3mf_2500_placements.3mf", 413, "the 3MF file's build, placing 5,100,000 triangles"),
    ],
)
def test_hostile_archives_are_refused_with_one_sentence(
    client: TestClient, name: str, status: int, words: str
) -> None:
    started = time.perf_counter()
    response = client.post("/api/mesh", files={"file": (name, (HOSTILE / name).read_bytes())})
    assert time.perf_counter() - started < 30  # unguarded, each stalls a worker or the server
    body = assert_error(response, status, "file", words)
    assert "ZipInfo" not in body["error"] and "<" not in body["error"]


def test_an_encrypted_member_is_a_400_in_our_words(client: TestClient) -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("cube.obj", "v 0 0 0\n")
    data = bytearray(buffer.getvalue())
    data[data.rindex(b"PK\x01\x02") + 8] |= 1  # the directory's flag: encrypted
    response = client.post("/api/mesh", files={"file": ("locked.zip", bytes(data))})
    assert_error(response, 400, "file", "The member cube.obj of the .zip file", "is encrypted")
