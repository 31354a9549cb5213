"""POST /api/normal (JSON body) and GET /api/normal (the page's query string, its JSON twin)."""

from __future__ import annotations

import json
import math
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.calculator.params import read_triangle
from app.calculator.presets import COORDINATE_FIELDS
from mesh_normal.triangle.normal import rational_triangle_normal
from tests.conftest import EXAMPLE_QUERY

RESULT_KEYS = {
    "a",
    "b",
    "c",
    "order",
    "u",
    "v",
    "normal",
    "magnitude",
    "unit_normal",
    "area",
    "degenerate",
    "plane",
    "plane_reason",
    "angle",
    "angle_reason",
    "exact",
    "exact_reason",
}

#: A sliver a naive float cross product calls flat: n_z = 2**-53 - 2**-105 exactly.
SLIVER = ([0.0, 0.0, 0.0], [1 + 2**-52, 1.0, 0.0], [1.0, 1 - 2**-53, 0.0])
SLIVER_NZ = 2**-53 - 2**-105


def strict_json(text: str):  # type: ignore[no-untyped-def]
    """Parse JSON the way a browser does: NaN, Infinity and -Infinity are not JSON."""

    def refuse(constant: str):  # type: ignore[no-untyped-def]
        raise AssertionError(f"non-JSON constant {constant} in {text[:200]}")

    return json.loads(text, parse_constant=refuse)


def post(client, a, b, c, swap=False):  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", json={"a": a, "b": b, "c": c, "swap_winding": swap})
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "application/json"
    return strict_json(response.text)


def query_for(a, b, c, **extra: str) -> dict[str, str]:  # type: ignore[no-untyped-def]
    values = [*a, *b, *c]
    names = ["ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz"]
    return {**{name: repr(float(x)) for name, x in zip(names, values, strict=True)}, **extra}


def hexes(values):  # type: ignore[no-untyped-def]
    return [None if x is None else float.hex(x) for x in values]


# --- POST /api/normal ---------------------------------------------------------------------------


def test_post_normal_returns_every_field(client) -> None:  # type: ignore[no-untyped-def]
    body = post(client, [1, 0, 0], [0, 2, 0], [0, 0, 3])
    assert set(body) == RESULT_KEYS  # no message: there is nothing to say
    assert body["a"] == [1.0, 0.0, 0.0]
    assert body["b"] == [0.0, 2.0, 0.0]
    assert body["c"] == [0.0, 0.0, 3.0]
    assert body["order"] == "ABC"
    assert body["u"] == [-1.0, 2.0, 0.0]
    assert body["v"] == [-1.0, 0.0, 3.0]
    assert body["normal"] == [6.0, 3.0, 2.0]
    assert body["magnitude"] == 7.0
    assert body["unit_normal"] == [6 / 7, 3 / 7, 2 / 7]  # each correctly rounded
    assert body["area"] == 3.5
    assert body["degenerate"] is False


def test_points_come_back_as_given(client) -> None:  # type: ignore[no-untyped-def]
    a, b, c = [0.1, -2.5e-300, 3e300], [-0.0, 7.0, 1e-5], [123456789.125, 0.3, -4.0]
    body = post(client, a, b, c)
    assert hexes(body["a"]) == hexes(a)
    assert hexes(body["b"]) == hexes(b)
    assert hexes(body["c"]) == hexes(c)


def test_swap_winding_uses_acb_and_flips_the_normal(client) -> None:  # type: ignore[no-untyped-def]
    plain = post(client, [1, 0, 0], [0, 2, 0], [0, 0, 3])
    swapped = post(client, [1, 0, 0], [0, 2, 0], [0, 0, 3], swap=True)
    assert swapped["order"] == "ACB"
    assert swapped["a"] == plain["a"] and swapped["b"] == plain["b"]
    assert swapped["u"] == plain["v"] and swapped["v"] == plain["u"]
    assert swapped["normal"] == [-x for x in plain["normal"]]
    assert swapped["unit_normal"] == [-x for x in plain["unit_normal"]]
    assert swapped["magnitude"] == plain["magnitude"]
    assert swapped["area"] == plain["area"]


def test_swap_winding_defaults_to_false(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post("/api/normal", json={"a": [0, 0, 0], "b": [1, 0, 0], "c": [0, 1, 0]})
    assert response.status_code == 200
    assert response.json()["order"] == "ABC"
    assert response.json()["normal"] == [0.0, 0.0, 1.0]


def test_sliver_is_exact_over_http(client) -> None:  # type: ignore[no-untyped-def]
    a, b, c = SLIVER
    naive_nz = b[0] * c[1] - b[1] * c[0]
    assert naive_nz == 0.0  # the float cross product would call it flat
    body = post(client, a, b, c)
    assert body["degenerate"] is False
    assert "message" not in body
    assert hexes(body["b"]) == hexes(b) and hexes(body["c"]) == hexes(c)
    assert hexes(body["normal"]) == hexes([0.0, 0.0, SLIVER_NZ])
    assert float.hex(body["magnitude"]) == float.hex(SLIVER_NZ)
    assert float.hex(body["area"]) == float.hex(SLIVER_NZ / 2)
    assert hexes(body["unit_normal"]) == hexes([0.0, 0.0, 1.0])


def test_sliver_is_exact_over_the_query_string(client) -> None:  # type: ignore[no-untyped-def]
    # Typed text is read as the decimal it is: 1.0000000000000002 * 0.9999999999999999 - 1.
    response = client.get("/api/normal", params=query_for(*SLIVER))
    assert response.status_code == 200, response.text
    body = strict_json(response.text)
    assert hexes(body["normal"]) == hexes([0.0, 0.0, float(Fraction(10**16 - 2, 10**32))])
    # |n|² = (10**16 - 2)**2 / 10**64 has 65 digits: too long to show.
    assert body["exact"] is None
    assert "more than 40 digits" in body["exact_reason"]
    assert hexes(body["unit_normal"]) == hexes([0.0, 0.0, 1.0])
    # The exact decimal expansions of the doubles give the doubles' answer.
    exact_text = "1.0000000000000002220446049250313080847263336181640625"
    cy_text = "0.99999999999999988897769753748434595763683319091796875"  # 1 - 2**-53
    response = client.get("/api/normal", params=query_for(*SLIVER, bx=exact_text, cy=cy_text))
    assert hexes(response.json()["normal"]) == hexes([0.0, 0.0, SLIVER_NZ])


def test_tiny_triangle_keeps_its_direction(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post(
        "/api/normal", json={"a": [0, 0, 0], "b": [1e-200, 0, 0], "c": [0, 1e-200, 0]}
    )
    assert response.status_code == 200
    assert "Infinity" not in response.text and "NaN" not in response.text
    body = strict_json(response.text)
    assert body["unit_normal"] == [0.0, 0.0, 1.0]
    assert body["degenerate"] is False
    assert body["magnitude"] is None and body["area"] is None
    assert body["normal"] == [0.0, 0.0, None]
    assert body["u"] == [1e-200, 0.0, 0.0] and body["v"] == [0.0, 1e-200, 0.0]
    message = body["message"]
    assert "smallest double" in message and "magnitude" in message and "area" in message


def test_huge_triangle_is_null_with_a_message(client) -> None:  # type: ignore[no-untyped-def]
    response = client.post(
        "/api/normal", json={"a": [0, 0, 0], "b": [1e200, 0, 0], "c": [0, 1e200, 0]}
    )
    assert response.status_code == 200
    assert "Infinity" not in response.text and "NaN" not in response.text
    body = strict_json(response.text)
    assert body["normal"] == [0.0, 0.0, None]
    assert body["magnitude"] is None and body["area"] is None
    assert body["unit_normal"] == [0.0, 0.0, 1.0]  # the direction is still exact
    assert body["degenerate"] is False
    assert "largest double" in body["message"]


def test_edges_beyond_the_double_range_are_null_too(client) -> None:  # type: ignore[no-untyped-def]
    big = 1.7976931348623157e308
    body = post(client, [-big, 0, 0], [big, 0, 0], [0, big, 0])
    assert body["u"][0] is None  # 2 * big does not fit a double
    assert body["unit_normal"] == [0.0, 0.0, 1.0]
    assert "u_x" in body["message"]


@pytest.mark.parametrize(
    ("a", "b", "c", "words"),
    [
        ([1, 2, 3], [1, 2, 3], [1, 2, 3], "All three points are the same"),
        ([0, 0, 0], [0, 0, 0], [1, 2, 3], "Points A and B coincide"),
        ([0, 0, 0], [1, 1, 1], [2, 2, 2], "lie on one line"),
        ([1e-300, 0, 0], [2e-300, 0, 0], [3e-300, 0, 0], "lie on one line"),
    ],
)
def test_degenerate_triangles(client, a, b, c, words) -> None:  # type: ignore[no-untyped-def]
    body = post(client, a, b, c)
    assert body["degenerate"] is True
    assert body["unit_normal"] is None
    assert body["normal"] == [0.0, 0.0, 0.0]
    assert body["magnitude"] == 0.0 and body["area"] == 0.0
    assert words in body["message"]


# --- GET /api/normal: the page's JSON twin ------------------------------------------------------


def test_get_normal_matches_post(client) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params=EXAMPLE_QUERY)
    assert response.status_code == 200
    assert response.headers["content-type"] == "application/json"
    assert response.json() == post(client, [1, 0, 0], [0, 2, 0], [0, 0, 3])


@pytest.mark.parametrize("value", ["on", "true", "1"])
def test_swap_on(client, value: str) -> None:  # type: ignore[no-untyped-def]
    body = client.get("/api/normal", params={**EXAMPLE_QUERY, "swap": value}).json()
    assert body["order"] == "ACB"
    assert body["normal"] == [-6.0, -3.0, -2.0]


@pytest.mark.parametrize("value", ["ON", "True", " on", "yes"])
def test_swap_takes_exactly_the_documented_words(client, value: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**EXAMPLE_QUERY, "swap": value})
    assert response.status_code == 422
    assert response.json()["field"] == "swap"


@pytest.mark.parametrize("value", [None, "", "off", "false", "0"])
def test_swap_off(client, value: str | None) -> None:  # type: ignore[no-untyped-def]
    params = EXAMPLE_QUERY if value is None else {**EXAMPLE_QUERY, "swap": value}
    body = client.get("/api/normal", params=params).json()
    assert body["order"] == "ABC"
    assert body["normal"] == [6.0, 3.0, 2.0]


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1.5", 1.5),
        ("-2e3", -2000.0),
        (".5", 0.5),
        ("5.", 5.0),
        ("+3", 3.0),
        ("1E2", 100.0),
        ("  7 ", 7.0),
        ("-0", -0.0),
        ("0.1", 0.1),
        ("1e-400", 0.0),
        ("1.7976931348623157e308", 1.7976931348623157e308),
    ],
)
def test_decimal_text_in_the_query(client, text: str, value: float) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**EXAMPLE_QUERY, "ay": text})
    assert response.status_code == 200, response.text
    assert float.hex(response.json()["a"][1]) == float.hex(value)


finite = st.floats(allow_nan=False, allow_infinity=False)
points = st.lists(finite, min_size=3, max_size=3)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(a=points, b=points, c=points, swap=st.booleans())
def test_any_finite_triangle(client, a, b, c, swap) -> None:  # type: ignore[no-untyped-def]
    """Any doubles: 200, valid JSON without NaN or Infinity, nulls explained, GET == POST."""
    body = post(client, a, b, c, swap)
    assert "Infinity" not in json.dumps(body) and "NaN" not in json.dumps(body)
    values = [*body["u"], *body["v"], *body["normal"], body["magnitude"], body["area"]]
    if body["degenerate"]:
        assert body["message"]
    else:  # a message exactly when some value is out of the double range
        assert ("message" in body) == (None in values), body
    assert (body["unit_normal"] is None) == body["degenerate"]
    if body["unit_normal"] is not None:
        assert math.isclose(math.hypot(*body["unit_normal"]), 1.0, rel_tol=1e-15)
    query = query_for(a, b, c, **({"swap": "on"} if swap else {}))
    twin = client.get("/api/normal", params=query)
    assert twin.status_code == 200
    # The GET twin reads the decimal text exactly: its result is that of the typed rationals
    # rounded once (the doubles' when an exponent is beyond ±30, as POST).
    got = strict_json(twin.text)
    texts = [query[name] for name in COORDINATE_FIELDS]
    keys = ("normal", "unit_normal", "magnitude", "area")
    if len(read_triangle(query).exact) == 9:
        x = [Fraction(text) for text in texts]
        points = (x[0], x[1], x[2]), (x[3], x[4], x[5]), (x[6], x[7], x[8])
        expected = rational_triangle_normal(*points, swap_winding=swap)
        assert [got[key] for key in keys] == [
            None if value is None else list(value) if isinstance(value, tuple) else value
            for value in (expected.normal, expected.unit_normal, expected.magnitude, expected.area)
        ]
    else:
        assert [got[key] for key in keys] == [body[key] for key in keys]
    if all(
        Fraction(text) == Fraction(value) for text, value in zip(texts, [*a, *b, *c], strict=True)
    ):
        # The same but for POST's hint on long exact forms (JSON numbers are doubles).
        assert (got["exact_reason"] is None) == (body["exact_reason"] is None)
        got["exact_reason"] = body["exact_reason"]
        assert json.dumps(got) == json.dumps(body)  # -0.0 and 0.0 differ here
