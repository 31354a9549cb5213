"""Static files: gzip when asked, cache headers, and the ?v=<hash> URLs that pages use."""

from __future__ import annotations

import gzip
import hashlib
from urllib.parse import parse_qs, urlsplit

import pytest

from app.web.static import STATIC_DIR, static_url
from tests.conftest import EXAMPLE_QUERY, Page

TEXT_ASSETS = [
    "js/calculator.js",
    "js/chart.js",
    "js/embed.js",
    "js/docs.js",
    "css/app.css",
    "img/favicon.svg",
    "vendor/swagger-ui/swagger-ui.css",
    "vendor/plotly/plotly-basic.min.js",
]
CONTENT_TYPES = {
    ".js": "text/javascript",
    ".css": "text/css",
    ".svg": "image/svg+xml",
    ".png": "image/png",
}
IMMUTABLE = "public, max-age=31536000, immutable"


def content_type(name: str) -> str:
    return CONTENT_TYPES[name[name.rindex(".") :]]


@pytest.mark.parametrize("name", TEXT_ASSETS)
def test_gzip_when_accepted(client, name: str) -> None:  # type: ignore[no-untyped-def]
    original = (STATIC_DIR / name).read_bytes()
    response = client.get(f"/static/{name}", headers={"accept-encoding": "gzip, deflate, br"})
    assert response.status_code == 200
    assert response.headers["content-encoding"] == "gzip"
    assert "accept-encoding" in response.headers["vary"].lower()
    assert response.headers["content-type"].startswith(content_type(name))
    assert response.content == original  # httpx undid the gzip
    assert int(response.headers["content-length"]) == len(gzip.compress(original, 9, mtime=0))
    if len(original) > 1024:  # (a tiny file may grow by gzip's header; that is harmless)
        assert int(response.headers["content-length"]) < len(original) / 2


@pytest.mark.parametrize("name", ["js/chart.js", "css/app.css"])
def test_no_gzip_unless_asked(client, name: str) -> None:  # type: ignore[no-untyped-def]
    original = (STATIC_DIR / name).read_bytes()
    response = client.get(f"/static/{name}", headers={"accept-encoding": "identity"})
    assert response.status_code == 200
    assert "content-encoding" not in response.headers
    assert response.content == original
    assert int(response.headers["content-length"]) == len(original)


def test_images_are_not_gzipped(client) -> None:  # type: ignore[no-untyped-def]
    name = "vendor/swagger-ui/favicon-32x32.png"
    response = client.get(f"/static/{name}", headers={"accept-encoding": "gzip"})
    assert response.status_code == 200
    assert "content-encoding" not in response.headers
    assert response.headers["content-type"] == "image/png"
    assert response.content == (STATIC_DIR / name).read_bytes()


def test_unversioned_urls_are_cached_briefly(client) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/static/js/chart.js")
    cache = response.headers["cache-control"]
    assert "max-age=300" in cache and "immutable" not in cache


@pytest.mark.parametrize("accept", ["gzip", "identity"])
def test_versioned_urls_are_cached_for_a_year(client, accept: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get(static_url("js/chart.js"), headers={"accept-encoding": accept})
    assert response.status_code == 200
    assert response.headers["cache-control"] == IMMUTABLE


def test_etag_revalidation(client) -> None:  # type: ignore[no-untyped-def]
    first = client.get("/static/css/app.css")
    etag = first.headers["etag"]
    again = client.get("/static/css/app.css", headers={"if-none-match": etag})
    assert again.status_code == 304
    assert again.content == b""


def page_assets(client) -> set[str]:  # type: ignore[no-untyped-def]
    """Every /static/ URL that the HTML pages reference."""
    urls: set[str] = set()
    for path, params in [
        ("/", None),
        ("/", EXAMPLE_QUERY),
        ("/embed", None),
        ("/docs", None),
        ("/nope", None),
        ("/", {"ax": "x"}),
    ]:
        html = Page(client.get(path, params=params).text)
        urls |= {url for url in html.urls() if url.startswith("/static/")}
    return urls


def test_hashed_urls_in_pages_resolve(client) -> None:  # type: ignore[no-untyped-def]
    urls = page_assets(client)
    assert len(urls) >= 8
    for url in urls:
        parts = urlsplit(url)
        version = parse_qs(parts.query)["v"]
        assert len(version) == 1, url
        file = STATIC_DIR / parts.path.removeprefix("/static/")
        assert version[0] == hashlib.sha256(file.read_bytes()).hexdigest()[:12], url
        response = client.get(url, headers={"accept-encoding": "gzip"})
        assert response.status_code == 200, url
        assert response.headers["cache-control"] == IMMUTABLE
        assert response.content == file.read_bytes()


@pytest.mark.parametrize(
    "path",
    [
        "/static/../app/config.py",
        "/static/%2e%2e/app/config.py",
        "/static/..%2fapp/config.py",
        "/static/%2e%2e%2f%2e%2e%2fetc/passwd",
        "/static/js/",
        "/static/js/nope.js",
    ],
)
def test_nothing_outside_the_static_folder(client, path: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get(path)
    assert response.status_code == 404
    assert "BODY_LIMITS" not in response.text and "root:" not in response.text
