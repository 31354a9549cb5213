"""Bad input: every refusal is a 4xx whose body is exactly {"error": one sentence, "field": ...}.

The field is named as the user wrote it: ``ax`` in a query string, ``a[0]`` in a JSON body and
``triangles[3][1][2]`` in a batch. Never a 500.
"""

from __future__ import annotations

import json

import pytest

from app.calculator.params import label
from tests.conftest import EXAMPLE_QUERY, assert_error

VALID = {"a": [0, 0, 0], "b": [1, 0, 0], "c": [0, 1, 0], "swap_winding": False}
JSON = {"content-type": "application/json"}
LIMIT = 64 * 1024


def with_value(path: tuple[str, int], literal: str) -> bytes:
    """VALID as JSON text, with one coordinate replaced by ``literal`` (any JSON-ish text)."""
    point, index = path
    values = [json.dumps(x) for x in VALID[point]]
    values[index] = literal
    body = {key: value for key, value in VALID.items() if key != point}
    text = json.dumps(body)[:-1] + f', "{point}": [{", ".join(values)}]}}'
    return text.encode()


# --- POST /api/normal: one bad value --------------------------------------------------------------


@pytest.mark.parametrize(
    ("path", "literal", "words"),
    [
        (("a", 0), '"1"', ["a[0]", "JSON number", "string '1'"]),
        (("b", 1), '"abc"', ["b[1]", "JSON number"]),
        (("c", 2), "true", ["c[2]", "boolean"]),
        (("a", 2), "false", ["a[2]", "boolean"]),
        (("b", 0), "null", ["b[0]", "null"]),
        (("c", 0), "NaN", ["c[0]", "finite"]),
        (("c", 1), "Infinity", ["c[1]", "finite"]),
        (("a", 1), "-Infinity", ["a[1]", "finite"]),
        (("b", 2), "1e400", ["b[2]", "double range"]),
        (("b", 2), "-1e400", ["b[2]", "double range"]),
        (("a", 0), "1" + "0" * 400, ["a[0]", "double range"]),  # an integer literal that big
        (("c", 2), "1.7976931348623159e308", ["c[2]", "double range"]),  # rounds to infinity
        (("a", 0), "[1]", ["a[0]", "JSON number"]),
        (("a", 0), '{"x": 1}', ["a[0]", "JSON number"]),
    ],
)
def test_bad_coordinate(client, path, literal: str, words: list[str]) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=with_value(path, literal), headers=JSON)
    assert_error(response, 422, f"{path[0]}[{path[1]}]", *words)


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        ({"a": [0, 0]}, "a", ["exactly 3 numbers", "not 2"]),  # a missing coordinate
        ({"b": [1, 0, 0, 0]}, "b", ["exactly 3 numbers", "not 4"]),
        ({"c": []}, "c", ["exactly 3 numbers", "not 0"]),
        ({"a": 5}, "a", ["must be a list"]),
        ({"a": "0,0,0"}, "a", ["must be a list"]),
        ({"b": {"x": 1, "y": 0, "z": 0}}, "b", ["must be a list"]),
        ({"b": None}, "b", ["must be a list", "null"]),
        ({"swap_winding": "yes"}, "swap_winding", ["true or false"]),
        ({"swap_winding": None}, "swap_winding", ["true or false"]),
        ({"d": [1, 2, 3]}, "d", ["not a field"]),  # unknown extra field, named
        ({"Swap_winding": True}, "Swap_winding", ["not a field"]),
    ],
)
def test_bad_point_or_field(client, change, field: str, words: list[str]) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", json={**VALID, **change})
    assert_error(response, 422, field, *words)


@pytest.mark.parametrize("point", ["a", "b", "c"])
def test_missing_point(client, point: str) -> None:  # type: ignore[no-untyped-def]
    body = {key: value for key, value in VALID.items() if key != point}
    assert_error(client.post("/api/normal", json=body), 422, point, "missing")


@pytest.mark.parametrize("name", ["query", "body", "path"])
def test_unknown_field_named_like_a_location(client, name: str) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", json={**VALID, name: 1})
    assert_error(response, 422, name, "not a field")


# --- POST /api/normal: a bad body ---------------------------------------------------------------


@pytest.mark.parametrize(
    "text",
    [
        b'{"a": [0, 0, 0], "b": [1, 0, 0], "c": [0, 1, 0]',
        b"{'a': [0, 0, 0]}",
        b"{",
        b"[1, 2,]",
        b'{"a": [0, 0, 0],}',
        b"\xff\xfe",
    ],
)
def test_malformed_json_is_400(client, text: bytes) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=text, headers=JSON)
    assert_error(response, 400, None, "not valid JSON")


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (b"[1, 2]", ["JSON object", "list of 2"]),
        (b'"x"', ["JSON object", "string"]),
        (b"1", ["JSON object"]),
        (b"null", ["JSON object", "null"]),
        (b"true", ["JSON object"]),
        (b"", ["JSON object"]),
        (b"  \n", ["JSON object"]),
    ],
)
def test_body_that_is_not_an_object(client, text: bytes, words: list[str]) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=text, headers=JSON)
    assert_error(response, 422, None, *words)


@pytest.mark.parametrize("content_type", [None, "text/plain", "application/x-www-form-urlencoded"])
@pytest.mark.parametrize("route", ["/api/normal", "/api/normals"])
def test_body_without_json_content_type(client, content_type: str | None, route: str) -> None:  # type: ignore[no-untyped-def]
    body = VALID if route == "/api/normal" else {"triangles": [TRIANGLE]}
    headers = {} if content_type is None else {"content-type": content_type}
    response = client.post(route, content=json.dumps(body).encode(), headers=headers)
    assert response.request.headers.get("content-type") == content_type
    assert_error(response, 415, None, "Content-Type: application/json")


@pytest.mark.parametrize("route", ["/api/normal", "/api/normals"])
def test_no_body_at_all(client, route: str) -> None:  # type: ignore[no-untyped-def]
    assert_error(client.post(route), 415, None, "Content-Type: application/json")
    empty = client.post(route, content=b"", headers={"content-type": "application/json"})
    assert_error(empty, 422, None, "JSON object")


# --- Oversized bodies (413, before anything is parsed) --------------------------------------------


def padded(size: int) -> bytes:
    """A valid request body of exactly ``size`` bytes (JSON allows trailing whitespace)."""
    text = json.dumps(VALID).encode()
    return text + b" " * (size - len(text))


def test_body_at_the_limit_is_accepted(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=padded(LIMIT), headers=JSON)
    assert response.status_code == 200, response.text
    assert response.json()["normal"] == [0.0, 0.0, 1.0]


def test_oversized_body_with_content_length(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=padded(LIMIT + 1), headers=JSON)
    assert response.request.headers["content-length"] == str(LIMIT + 1)
    assert_error(response, 413, None, "64 KB")


def test_oversized_body_of_nonsense(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=b"x" * (LIMIT * 4), headers=JSON)
    assert_error(response, 413, None, "larger than")


def chunks(total: int, size: int = 4096):  # type: ignore[no-untyped-def]
    body = padded(total)
    for start in range(0, total, size):
        yield body[start : start + size]


def test_oversized_chunked_body(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=chunks(LIMIT + 1), headers=JSON)
    assert response.request.headers.get("transfer-encoding") == "chunked"
    assert "content-length" not in response.request.headers
    assert_error(response, 413, None, "64 KB")


def test_chunked_body_at_the_limit_is_accepted(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", content=chunks(LIMIT), headers=JSON)
    assert response.request.headers.get("transfer-encoding") == "chunked"
    assert response.status_code == 200, response.text


def test_oversized_body_on_a_page_path_is_refused_too(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/", content=b"x" * (LIMIT + 1))
    assert_error(response, 413, None, "larger than")


# --- POST /api/normals: errors inside a batch ---------------------------------------------------

TRIANGLE = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


def batch_with(index: tuple[int, ...], value) -> dict:  # type: ignore[no-untyped-def]
    triangles = [json.loads(json.dumps(TRIANGLE)) for _ in range(5)]
    target = triangles
    for step in index[:-1]:
        target = target[step]
    target[index[-1]] = value
    return {"triangles": triangles}


@pytest.mark.parametrize(
    ("index", "value", "field", "words"),
    [
        ((3, 1, 2), "1", "triangles[3][1][2]", ["JSON number"]),
        ((3, 1, 2), True, "triangles[3][1][2]", ["boolean"]),
        ((0, 0, 0), None, "triangles[0][0][0]", ["null"]),
        ((4, 2), [1, 2], "triangles[4][2]", ["exactly 3 numbers", "not 2"]),
        ((4, 2), [1, 2, 3, 4], "triangles[4][2]", ["exactly 3 numbers", "not 4"]),
        ((2,), [[0, 0, 0], [1, 0, 0]], "triangles[2]", ["exactly 3 points", "not 2"]),
        ((2,), [], "triangles[2]", ["exactly 3 points"]),
        ((1,), "abc", "triangles[1]", ["must be a list"]),
    ],
)
def test_bad_value_in_a_batch(client, index, value, field: str, words: list[str]) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normals", json=batch_with(index, value))
    assert_error(response, 422, field, *words)


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity", "1e400"])
def test_non_finite_in_a_batch(client, literal: str) -> None:  # type: ignore[no-untyped-def]
    text = json.dumps(batch_with((3, 1, 2), 12345)).replace("12345", literal)
    response = client.post("/api/normals", content=text.encode(), headers=JSON)
    assert_error(response, 422, "triangles[3][1][2]", "finite")


@pytest.mark.parametrize(
    ("body", "field", "words"),
    [
        ({}, "triangles", ["missing"]),
        ({"triangles": "x"}, "triangles", ["must be a list"]),
        ({"triangles": None}, "triangles", ["must be a list"]),
        ({"triangles": [TRIANGLE], "swap_winding": "no"}, "swap_winding", ["true or false"]),
        ({"triangles": [TRIANGLE], "extra": 1}, "extra", ["not a field"]),
        ([TRIANGLE], None, ["JSON object"]),
    ],
)
def test_bad_batch_body(client, body, field: str | None, words: list[str]) -> None:  # type: ignore[no-untyped-def]
    assert_error(client.post("/api/normals", json=body), 422, field, *words)


def test_malformed_batch_json(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normals", content=b'{"triangles": [[[0,0,0]', headers=JSON)
    assert_error(response, 400, None, "not valid JSON")


def test_oversized_batch_body(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normals", content=b" " * (48 * 1024 * 1024 + 1), headers=JSON)
    assert_error(response, 413, None, "48 MB")


# --- GET /api/normal and /api/chart: query strings ---------------------------------------------

BAD_TEXT = [
    ("abc", "must be a number"),
    ("1e999", "double range"),
    ("-1e999", "double range"),
    ("0x10", "must be a number"),
    ("nan", "must be a number"),
    ("NaN", "must be a number"),
    ("inf", "must be a number"),
    ("-inf", "must be a number"),
    ("Infinity", "must be a number"),
    ("1,5,2", "must be a number"),
    (",5", "must be a number"),
    ("1,000", "thousands separator"),
    ("-12,500", "thousands separator"),
    ("1/0", "divides by zero"),
    ("-2/0.0", "divides by zero"),
    ("1/2/3", "must be a number"),
    ("/3", "must be a number"),
    ("1/", "must be a number"),
    ("1e999999/3", "exponent beyond ±30"),
    ("1/1e-99999999", "exponent beyond ±30"),
    ("1e30/1e-300", "exponent beyond ±30"),
    ("1e999999", "double range"),
    ("1_000", "must be a number"),
    ("1e", "must be a number"),
    ("e5", "must be a number"),
    ("--1", "must be a number"),
    ("1.2.3", "must be a number"),
    ("1" * 65, "longer than"),
    ("<script>", "must be a number"),
]


@pytest.mark.parametrize("route", ["/api/normal", "/api/chart"])
@pytest.mark.parametrize(("text", "word"), BAD_TEXT)
@pytest.mark.parametrize("name", ["ax", "cz"])
def test_bad_query_value(client, route: str, text: str, word: str, name: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get(route, params={**EXAMPLE_QUERY, name: text})
    body = assert_error(response, 422, name, label(name), word)
    assert not body["error"].startswith(name)  # "B.y", never "by", in the sentence
    assert len(body["error"]) < 200  # a long value is not echoed whole


@pytest.mark.parametrize("text", ["\uff11", "\u0661\u0662", "\u0967.5"])
def test_non_ascii_digits_are_refused(client, text: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**EXAMPLE_QUERY, "ax": text})
    assert_error(response, 422, "ax", "must be a number")


@pytest.mark.parametrize("route", ["/api/normal", "/api/chart"])
@pytest.mark.parametrize("name", ["ax", "by", "cz"])
def test_missing_query_value(client, route: str, name: str) -> None:  # type: ignore[no-untyped-def]
    params = {key: value for key, value in EXAMPLE_QUERY.items() if key != name}
    assert_error(client.get(route, params=params), 422, name, label(name), "missing")


@pytest.mark.parametrize("blank", ["", "   ", "\t"])
def test_blank_query_value_is_missing(client, blank: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**EXAMPLE_QUERY, "by": blank})
    body = assert_error(response, 422, "by")
    assert body["error"] == "B.y is missing."


def test_no_query_at_all(client) -> None:  # type: ignore[no-untyped-def]
    body = assert_error(client.get("/api/normal"), 422, "ax")
    assert body["error"] == "All nine coordinates, A.x to C.z, are missing."


def test_a_wrong_value_is_named_before_the_missing_ones(client) -> None:  # type: ignore[no-untyped-def]
    body = assert_error(client.get("/api/normal?ax=abc"), 422, "ax")
    assert body["error"] == "A.x must be a number such as 1.5, -2e3 or 1/3, not 'abc'."
    # Also when the wrong value comes after the missing ones in the form's order.
    body = assert_error(client.get("/api/normal?cz=1e999&ax=1"), 422, "cz")
    assert body["error"] == "C.z is beyond the double range (about ±1.8e308)."
    body = assert_error(client.get("/api/normal?ax=1&swap=maybe"), 422, "swap", "on, true or 1")


def test_missing_fields_are_grouped_in_one_sentence(client) -> None:  # type: ignore[no-untyped-def]
    params = {k: v for k, v in EXAMPLE_QUERY.items() if k not in ("bx", "by", "cz")}
    body = assert_error(client.get("/api/normal", params=params), 422, "bx")
    assert body["error"] == "B.x, B.y and C.z are missing."
    params = {k: v for k, v in EXAMPLE_QUERY.items() if k not in ("ay", "cx")}
    body = assert_error(client.get("/api/chart", params=params), 422, "ay")
    assert body["error"] == "A.y and C.x are missing."


@pytest.mark.parametrize("route", ["/api/normal", "/api/chart"])
@pytest.mark.parametrize("value", ["yes", "2", "maybe", "checked", "onn"])
def test_bad_swap(client, route: str, value: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get(route, params={**EXAMPLE_QUERY, "swap": value})
    assert_error(response, 422, "swap", "on, true or 1")


def test_first_bad_field_is_named(client) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**EXAMPLE_QUERY, "bx": "x", "cz": "y"})
    assert_error(response, 422, "bx")


# --- Routing errors on API paths ----------------------------------------------------------------


def test_unknown_api_path_is_json_404(client) -> None:  # type: ignore[no-untyped-def]
    assert_error(client.get("/api/nope"), 404, None, "no page")


@pytest.mark.parametrize(
    ("method", "path"),
    [
        ("DELETE", "/api/normal"),
        ("PUT", "/api/normals"),
        ("POST", "/api/chart"),
        ("GET", "/api/normals"),
    ],
)
def test_wrong_method_is_json_405(client, method: str, path: str) -> None:  # type: ignore[no-untyped-def]
    response = client.request(method, path)
    assert_error(response, 405, None, "method")
    assert response.headers["allow"]


@pytest.mark.parametrize("method", ["DELETE", "OPTIONS"])
def test_405_allow_header_lists_every_method(client, method: str) -> None:  # type: ignore[no-untyped-def]
    response = client.request(method, "/api/normal")
    assert response.status_code == 405
    allowed = {part.strip() for part in response.headers["allow"].split(",")}
    assert {"GET", "POST"} <= allowed, response.headers["allow"]
