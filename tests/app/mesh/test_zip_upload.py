"""A .zip upload (a .gltf with its .bin), and glTF the API refuses with a 415 naming why."""

from __future__ import annotations

import io
import json
import struct
import zipfile

import trimesh
from fastapi.testclient import TestClient

from tests.conftest import Page, assert_error


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
