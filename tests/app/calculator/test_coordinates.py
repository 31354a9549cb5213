"""app/calculator/coordinates.py, and what the API makes of decimal commas and fractions."""

from __future__ import annotations

import time
from fractions import Fraction

import pytest

from app.calculator.coordinates import Coordinate, parse_coordinate
from app.calculator.params import read_triangle
from app.web.errors import ApiError
from tests.conftest import EXAMPLE_QUERY, assert_error

ZERO = dict.fromkeys(EXAMPLE_QUERY, "0")


def read(text: str) -> Coordinate:
    return parse_coordinate("A.x", "ax", text)


@pytest.mark.parametrize(
    ("text", "value", "exact"),
    [
        ("2,5", 2.5, Fraction(5, 2)),
        ("-0,125", -0.125, Fraction(-1, 8)),
        ("1,5e3", 1500.0, Fraction(1500)),
        ("0.1", 0.1, Fraction(1, 10)),  # the exact decimal, not the double's binary value
        (" 7 ", 7.0, Fraction(7)),
        ("1e30", 1e30, Fraction(10**30)),
        ("1e-31", 1e-31, None),  # beyond ±30: only its double
        ("1e-99999999", 0.0, None),  # and never a Fraction of 10**99999999
    ],
)
def test_decimals(text: str, value: float, exact: Fraction | None) -> None:
    coordinate = read(text)
    assert coordinate == Coordinate(value, exact, fraction=False)


@pytest.mark.parametrize(
    ("text", "exact"),
    [
        ("1/3", Fraction(1, 3)),
        ("-2/7", Fraction(-2, 7)),
        ("1.5/2", Fraction(3, 4)),
        ("1,5/2", Fraction(3, 4)),
        (" 3 / -4 ", Fraction(-3, 4)),
        ("+6/4", Fraction(3, 2)),
        ("1e30/3e-30", Fraction(10**60, 3)),
        ("0/5", Fraction(0)),
    ],
)
def test_fractions_are_exact(text: str, exact: Fraction) -> None:
    coordinate = read(text)
    assert coordinate.fraction is True
    assert coordinate.exact == exact
    assert coordinate.value == float(exact)  # its nearest double


@pytest.mark.parametrize("text", ["1e-99999999/3", "1/1e99999999", "1e" + "9" * 60])
def test_huge_exponents_are_answered_at_once(text: str) -> None:
    start = time.perf_counter()
    with pytest.raises(ApiError) as raised:
        read(text)
    assert time.perf_counter() - start < 1.0  # Fraction("1e-99999999") would not finish
    assert raised.value.field == "ax"


# --- The API computes exactly when a coordinate is a fraction ----------------------------------


def get(client, **values: str):  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**ZERO, **values})
    assert response.status_code == 200, response.text
    return response.json()


def test_a_decimal_comma_means_a_point(client) -> None:  # type: ignore[no-untyped-def]
    comma = get(client, bx="2,5", cy="1,5")
    point = get(client, bx="2.5", cy="1.5")
    assert comma == point
    assert comma["normal"] == [0.0, 0.0, 3.75]


def test_fractions_give_the_correctly_rounded_exact_normal(client) -> None:  # type: ignore[no-untyped-def]
    body = get(client, bx="1/3", cy="1/15")
    assert body["b"] == [1 / 3, 0.0, 0.0]
    assert body["c"] == [0.0, 1 / 15, 0.0]
    assert body["normal"] == [0.0, 0.0, 0.022222222222222223]  # 1/45, rounded once
    assert body["normal"][2] == float(Fraction(1, 45))
    # On the doubles of 1/3 and 1/15 the exact product rounds to the next double down.
    doubles = get(client, bx=repr(1 / 3), cy=repr(1 / 15))
    assert doubles["normal"] == [0.0, 0.0, 0.02222222222222222]


def test_fractions_on_one_line_are_exactly_degenerate(client) -> None:  # type: ignore[no-untyped-def]
    # B = (1/3, 1, 0) lies on the line from A = 0 to C = (1, 3, 0); as doubles it does not.
    body = get(client, bx="1/3", by="1", cx="1", cy="3")
    assert body["degenerate"] is True and body["normal"] == [0.0, 0.0, 0.0]
    assert "one line" in body["message"]
    doubles = get(client, bx=repr(1 / 3), by="1", cx="1", cy="3")
    assert doubles["degenerate"] is False


def test_decimals_beside_a_fraction_are_their_doubles(client) -> None:  # type: ignore[no-untyped-def]
    # With bx a fraction, 0.1 and 0.7 are still the doubles they denote: the answer is the
    # decimal-only one, and stays so when the fraction is replaced by its (exact) decimal.
    mixed = get(client, ax="0.1", by="0.7", cz="3", bx="1/2")
    plain = get(client, ax="0.1", by="0.7", cz="3", bx="0.5")
    assert mixed == plain


def test_read_triangle_keeps_each_exact_value() -> None:
    parsed = read_triangle({**ZERO, "ax": "0.1", "ay": "1/3", "az": "1e-40", "bx": "2,5"})
    assert parsed.valid
    assert parsed.exact["ax"] == Fraction(1, 10)
    assert parsed.exact["ay"] == Fraction(1, 3)
    assert "az" not in parsed.exact  # exponent beyond ±30
    assert parsed.exact["bx"] == Fraction(5, 2)
    assert parsed.fractions == ["ay"]
    assert parsed.numbers["ay"] == 1 / 3


def test_division_by_zero_names_the_field(client) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal", params={**ZERO, "by": "2/0"})
    body = assert_error(response, 422, "by", "B.y", "divides by zero")
    assert body["error"] == "B.y divides by zero; a fraction's denominator must not be 0."
