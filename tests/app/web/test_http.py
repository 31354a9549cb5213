"""HTTP details: HEAD as GET, the Allow header of a 405, links never built from the Host header,
and an upload with no temporary folder to spool it (a 503 that says so)."""

from __future__ import annotations

import re
import tempfile

import pytest
from fastapi.testclient import TestClient

from app.main import create_app
from tests.conftest import EXAMPLE_QUERY, assert_error
from tests.meshes import CUBE_OBJ

GET_PATHS = ["/", "/mesh", "/embed", "/docs", "/static/css/app.css", "/api/normal", "/nowhere"]


@pytest.mark.parametrize("path", GET_PATHS)
def test_head_is_get_without_the_body(client: TestClient, path: str) -> None:
    params = EXAMPLE_QUERY if path == "/api/normal" else None
    got = client.get(path, params=params)
    head = client.head(path, params=params)
    assert head.status_code == got.status_code
    assert head.content == b""
    for name in ("content-type", "content-length", "content-security-policy"):
        assert head.headers.get(name) == got.headers.get(name), name


@pytest.mark.parametrize(
    ("method", "path", "allowed"),
    [
        ("POST", "/static/css/app.css", "GET, HEAD"),
        ("DELETE", "/static/vendor/nothing.js", "GET, HEAD"),
        ("DELETE", "/", "GET, HEAD"),
        ("PUT", "/mesh", "GET, HEAD, POST"),
        ("DELETE", "/api/normal", "GET, HEAD, POST"),
    ],
)
def test_a_405_names_the_methods_it_takes(
    client: TestClient, method: str, path: str, allowed: str
) -> None:
    response = client.request(method, path)
    assert response.status_code == 405
    assert response.headers["allow"] == allowed


FORGED = {"host": "attacker.example"}


def _absolute_links(text: str) -> set[str]:
    return set(re.findall(r"https?://[^\s\"'<>&]+", text.replace("&#34;", '"')))


def test_no_link_is_built_from_a_forged_host(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("MESH_PUBLIC_URL", raising=False)
    pages = [client.get(path, headers=FORGED).text for path in ("/", "/embed", "/partials")]
    pages.append(client.post("/mesh", files={"file": ("c.obj", CUBE_OBJ)}, headers=FORGED).text)
    for text in pages:
        assert "attacker.example" not in text
    index, embed, _, mesh = pages
    assert 'iframe src="/embed?ax=1' in index.replace("&#34;", '"').replace("&quot;", '"')
    assert 'href="/?ax=1' in embed
    assert "curl -F file=@c.obj /api/mesh" in mesh


def test_links_use_the_configured_public_url(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("MESH_PUBLIC_URL", "https://normals.example.org/")
    index = client.get("/", headers=FORGED).text
    embed = client.get("/embed", headers=FORGED).text
    mesh = client.post("/mesh", files={"file": ("c.obj", CUBE_OBJ)}, headers=FORGED).text
    assert "https://normals.example.org/embed?ax=1" in index
    assert 'href="https://normals.example.org/?ax=1' in embed
    assert "curl -F file=@c.obj https://normals.example.org/api/mesh" in mesh
    for text in (index, embed, mesh):
        assert "attacker.example" not in text
        assert {link.split("/")[2] for link in _absolute_links(text)} <= {"normals.example.org"}


@pytest.fixture
def no_temp_dir(monkeypatch: pytest.MonkeyPatch) -> None:
    """No folder tempfile may write: as on a read-only root without a tmpfs at /tmp."""
    monkeypatch.setattr(tempfile, "tempdir", None)
    monkeypatch.setattr(tempfile, "_candidate_tempdir_list", lambda: ["/nonexistent/tmp"])


def big_obj() -> bytes:
    """The cube padded with comments past Starlette's default 1 MB spool (a temporary file)."""
    return CUBE_OBJ.encode() + b"# a comment to pass the one megabyte spool size\n" * 23_000


@pytest.mark.usefixtures("no_temp_dir")
def test_without_a_temporary_folder_a_big_upload_is_still_read() -> None:
    # Uploads are kept in memory, as a raw body is: no temporary file to make.
    client = TestClient(create_app(), raise_server_exceptions=False)
    for path in ("/api/mesh", "/mesh"):
        big = client.post(path, files={"file": ("c.obj", big_obj())})
        assert big.status_code == 200, big.text
    assert client.post("/api/mesh", files={"file": ("c.obj", big_obj())}).json()["faces"] == 12


@pytest.mark.usefixtures("no_temp_dir")
def test_without_a_temporary_folder_what_needs_one_is_a_503_that_says_so() -> None:
    app = create_app()

    @app.get("/api/test-temporary-file")
    def temporary() -> None:
        tempfile.TemporaryFile().close()

    response = TestClient(app, raise_server_exceptions=False).get("/api/test-temporary-file")
    assert_error(response, 503, None, "writable temporary folder", "/tmp")


def test_other_missing_files_are_still_a_crash() -> None:
    tempfile.gettempdir()  # this machine has a temporary folder
    app = create_app()

    @app.get("/api/test-missing-file")
    def missing() -> None:
        raise FileNotFoundError(2, "No such file or directory", "/srv/missing")

    response = TestClient(app, raise_server_exceptions=False).get("/api/test-missing-file")
    assert_error(response, 500, None, "Something went wrong on our side")
