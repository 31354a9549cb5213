"""The app's OpenAPI version is the library's one __version__."""

from __future__ import annotations

from fastapi.testclient import TestClient

import mesh_normal


def test_openapi_version_is_the_package_version(client: TestClient) -> None:
    info = client.get("/openapi.json").json()["info"]
    assert info["version"] == mesh_normal.__version__
    assert info["title"] == "Mesh Normal Calculator"
