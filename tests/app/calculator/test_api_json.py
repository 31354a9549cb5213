"""The calculator's JSON bodies: a key given twice and an integer of more than 4,300 digits."""

from __future__ import annotations

import pytest

from tests.conftest import assert_error

JSON = {"content-type": "application/json"}
TRIANGLE = b'"a": [1, 0, 0], "b": [0, 1, 0], "c": [0, 0, 1]'


@pytest.mark.parametrize(
    ("route", "body", "key"),
    [
        ("/api/normal", b"{" + TRIANGLE + b', "a": [2, 0, 0]}', "a"),
        ("/api/normal", b"{" + TRIANGLE + b', "\\u0063" : [0, 0, 2]}', "c"),  # the same key
        ("/api/normal", b"{" + TRIANGLE + b', "a": "not a point"}', "a"),  # before its type
        (
            "/api/normal",
            b"{" + TRIANGLE + b', "swap_winding": true, "swap_winding": false}',
            "swap_winding",
        ),
        (
            "/api/normals",
            b'{"triangles": [[[1,0,0],[0,1,0],[0,0,1]]], "triangles": []}',
            "triangles",
        ),
    ],
)
def test_a_key_given_twice_is_a_422_naming_it(client, route: str, body: bytes, key: str) -> None:  # type: ignore[no-untyped-def]
    response = client.post(route, content=body, headers=JSON)
    assert_error(response, 422, key, "given twice", key)


def test_the_same_key_in_two_objects_is_fine(client) -> None:  # type: ignore[no-untyped-def]
    body = b'{"triangles": [[[1,0,0],[0,1,0],[0,0,1]], [[0,0,0],[1,0,0],[0,1,0]]]}'
    assert client.post("/api/normals", content=body, headers=JSON).status_code == 200
    text = b'{"a": [1, 0, 0], "b": [0, 1, 0], "c": [0, 0, 1], "swap_winding": false}'
    assert client.post("/api/normal", content=text, headers=JSON).status_code == 200


@pytest.mark.parametrize("sign", ["", "-"])
@pytest.mark.parametrize("route", ["/api/normal", "/api/normals"])
def test_an_integer_of_5000_digits_is_out_of_range_like_1e400(
    client, route: str, sign: str
) -> None:  # type: ignore[no-untyped-def]
    number = sign.encode() + b"1" * 5000
    point = b"[" + number + b", 0, 0]"
    body = (
        b'{"a": ' + point + b', "b": [0, 1, 0], "c": [0, 0, 1]}'
        if route == "/api/normal"
        else b'{"triangles": [[' + point + b", [0, 1, 0], [0, 0, 1]]]}"
    )
    response = client.post(route, content=body, headers=JSON)
    assert_error(response, 422, None, "beyond the double range", "line 1 column")
