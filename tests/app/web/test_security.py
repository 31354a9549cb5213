"""Security headers on every response, and the framing rules (only /embed may be framed)."""

from __future__ import annotations

import json
import warnings

import pytest

from app.main import create_app
from tests.conftest import EXAMPLE_QUERY

with warnings.catch_warnings():
    warnings.filterwarnings("ignore", message=r"Using `httpx` with `starlette\.testclient`")
    from fastapi.testclient import TestClient

JSON = {"content-type": "application/json"}
VALID = json.dumps({"a": [0, 0, 0], "b": [1, 0, 0], "c": [0, 1, 0]}).encode()


def csp(response) -> dict[str, list[str]]:  # type: ignore[no-untyped-def]
    """The Content-Security-Policy as {directive: [sources]}; exactly one such header."""
    headers = response.headers.get_list("content-security-policy")
    assert len(headers) == 1, headers
    policy: dict[str, list[str]] = {}
    for part in headers[0].split(";"):
        if part.strip():
            name, *sources = part.split()
            assert name.lower() not in policy, f"{name} twice"
            policy[name.lower()] = sources
    return policy


def big_chunks():  # type: ignore[no-untyped-def]
    for _ in range(20):
        yield b" " * 4096


#: (name, request) for a response of every kind the app produces.
REQUESTS = {
    "page": ("GET", "/", {}),
    "page with result": ("GET", "/", {"params": EXAMPLE_QUERY}),
    "page with bad input": ("GET", "/", {"params": {**EXAMPLE_QUERY, "ax": "x"}}),
    "docs": ("GET", "/docs", {}),
    "openapi": ("GET", "/openapi.json", {}),
    "static js": ("GET", "/static/js/chart.js", {}),
    "static css gzip": ("GET", "/static/css/app.css", {"headers": {"accept-encoding": "gzip"}}),
    "static vendor": ("GET", "/static/vendor/swagger-ui/swagger-ui-bundle.js", {}),
    "static 304": ("GET", "/static/img/favicon.svg", {"headers": {"if-none-match": "*"}}),
    "static 404": ("GET", "/static/nope.js", {}),
    "html 404": ("GET", "/nope", {}),
    "html 405": ("POST", "/", {}),
    "api 200 get": ("GET", "/api/normal", {"params": EXAMPLE_QUERY}),
    "api 200 post": ("POST", "/api/normal", {"content": VALID, "headers": JSON}),
    "api batch": ("POST", "/api/normals", {"json": {"triangles": []}}),
    "api chart": ("GET", "/api/chart", {"params": EXAMPLE_QUERY}),
    "api 422": ("GET", "/api/normal", {"params": {**EXAMPLE_QUERY, "ax": "x"}}),
    "api 400": ("POST", "/api/normal", {"content": b"{", "headers": JSON}),
    "api 413": ("POST", "/api/normal", {"content": b" " * 70_000, "headers": JSON}),
    "api 413 chunked": ("POST", "/api/normal", {"content": big_chunks, "headers": JSON}),
    "api 404": ("GET", "/api/nope", {}),
    "api 405": ("DELETE", "/api/normal", {}),
    "head": ("HEAD", "/", {}),
}


def send(client, method: str, path: str, options: dict):  # type: ignore[no-untyped-def]
    options = dict(options)
    if callable(options.get("content")):
        options["content"] = options["content"]()
    return client.request(method, path, **options)


def assert_security_headers(response, *, frameable: bool = False) -> None:  # type: ignore[no-untyped-def]
    headers = response.headers
    assert headers.get("x-content-type-options") == "nosniff"
    assert headers.get("referrer-policy") in {
        "no-referrer",
        "same-origin",
        "strict-origin",
        "strict-origin-when-cross-origin",
    }
    policy = csp(response)
    scripts = policy.get("script-src", policy.get("default-src"))
    assert scripts, policy
    assert "'unsafe-inline'" not in scripts
    assert "*" not in scripts and "data:" not in scripts and "http:" not in scripts
    assert policy.get("object-src") == ["'none'"]
    assert policy.get("base-uri") == ["'none'"]
    if frameable:
        assert policy["frame-ancestors"] == ["*"]
        assert "x-frame-options" not in headers
    else:
        assert policy["frame-ancestors"] == ["'none'"]
        assert headers.get_list("x-frame-options") == ["DENY"]


@pytest.mark.parametrize("name", list(REQUESTS))
def test_every_response_has_security_headers(client, name: str) -> None:  # type: ignore[no-untyped-def]
    method, path, options = REQUESTS[name]
    response = send(client, method, path, options)
    assert response.status_code < 500, response.text
    assert_security_headers(response)


@pytest.mark.parametrize(
    ("params", "status"),
    [
        ({}, 200),
        (EXAMPLE_QUERY, 200),
        ({**EXAMPLE_QUERY, "swap": "on"}, 200),
        ({**EXAMPLE_QUERY, "ax": "x"}, 422),
    ],
)
def test_embed_may_be_framed_by_anyone(client, params, status: int) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/embed", params=params)
    assert response.status_code == status
    assert_security_headers(response, frameable=True)


@pytest.mark.parametrize("path", ["/", "/docs", "/nope", "/embed/", "/embedded", "/api/chart"])
def test_other_paths_refuse_framing(client, path: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get(path, params=EXAMPLE_QUERY, follow_redirects=False)
    assert_security_headers(response, frameable=False)


@pytest.fixture(scope="module")
def crashing_client():  # type: ignore[no-untyped-def]
    """The real app plus two routes that fail, to see what an unexpected error looks like."""
    app = create_app()

    async def boom() -> None:
        raise RuntimeError("deliberate failure for the test")

    app.add_api_route("/api/boom", boom)
    app.add_api_route("/boom", boom, include_in_schema=False)
    with TestClient(app, raise_server_exceptions=False) as test_client:
        yield test_client


@pytest.mark.parametrize("path", ["/api/boom", "/boom"])
def test_a_crash_is_one_sentence_and_no_traceback(crashing_client, path: str) -> None:  # type: ignore[no-untyped-def]
    response = crashing_client.get(path)
    assert response.status_code == 500
    assert "deliberate failure" not in response.text and "Traceback" not in response.text
    if path.startswith("/api/"):
        assert response.json() == {"error": "Something went wrong on our side.", "field": None}
    else:
        assert "Something went wrong on our side." in response.text


@pytest.mark.parametrize("path", ["/api/boom", "/boom"])
def test_a_crash_has_security_headers_too(crashing_client, path: str) -> None:  # type: ignore[no-untyped-def]
    response = crashing_client.get(path)
    assert response.status_code == 500
    assert_security_headers(response)
