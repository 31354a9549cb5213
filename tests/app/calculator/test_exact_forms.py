"""Exact forms, the plane and the angle: by hand, as properties, in the JSON, CSV and page."""

from __future__ import annotations

import csv
import io
import math
import sys
from fractions import Fraction
from math import gcd, lcm

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.calculator.calculation import DOUBLES_HINT, calculation_payload, from_doubles, from_typed
from app.calculator.exact_forms import (
    MAX_DIGITS,
    TOO_LONG,
    RationalPoint,
    Surd,
    double_values,
    equation_text,
    exact_values,
    surd_json,
    surd_text,
)
from app.calculator.params import read_triangle
from app.calculator.payloads import CSV_COLUMNS
from app.calculator.plane_angle import NO_PLANE
from app.calculator.presets import COORDINATE_FIELDS
from app.web.formatting import js_number
from app.web.jsonio import json_bytes
from mesh_normal.triangle.exact import ratio_sqrt, square_root
from mesh_normal.triangle.normal import exact_triangle
from tests.conftest import Page
from tests.mesh_normal._reference import round_or_none
from tests.mesh_normal.triangle.test_normal import assert_matches_reference

RIGHT = {"ax": "0", "ay": "0", "az": "0", "bx": "1", "by": "0", "bz": "0", "cx": "0", "cy": "1"}
RIGHT = {**RIGHT, "cz": "0"}
#: n = (-9/2, -13/2, 3), |n|² = 71.5, |n| = √71.5 = √286 / 2.
HALVES = {"ax": "0", "ay": "0", "az": "0", "bx": "1", "by": "0", "bz": "1.5", "cx": "0"}
HALVES = {**HALVES, "cy": "3", "cz": "6.5"}


def rational_json(x: Fraction) -> dict[str, str]:
    """The oracle: a Fraction's own reduction and text."""
    return {"text": str(x), "numerator": str(x.numerator), "denominator": str(x.denominator)}


def integer_plane(coefficients: tuple[Fraction, Fraction, Fraction, Fraction]) -> list[int]:
    """The oracle: a, b, c, d scaled by one positive factor to coprime integers."""
    scale = lcm(*(value.denominator for value in coefficients))
    integers = [int(value * scale) for value in coefficients]
    common = gcd(*integers)
    return [value // common for value in integers]


def payload_for(query: dict[str, str]) -> dict:  # type: ignore[type-arg]
    parsed = read_triangle(query)
    assert not parsed.errors
    return calculation_payload(from_typed(parsed))


def texts(items: list[dict[str, str]] | None) -> list[str] | None:
    return None if items is None else [item["text"] for item in items]


# --- By hand ------------------------------------------------------------------------------------


def test_unit_right_triangle() -> None:
    body = payload_for(RIGHT)
    assert texts(body["exact"]["normal"]) == ["0", "0", "1"]
    assert body["exact"]["magnitude"] == {"text": "1", "coefficient": "1", "radicand": "1"}
    assert body["exact"]["area"]["text"] == "1/2"
    assert texts(body["exact"]["unit_normal"]) == ["0", "0", "1"]
    assert body["plane"]["equation"] == "z = 0"
    assert [body["plane"][key] for key in "abcd"] == [0.0, 0.0, 1.0, 0.0]
    assert body["plane"]["exact"]["equation"] == "z = 0"
    assert body["angle"] == {"degrees": 90.0, "radians": math.pi / 2}
    assert body["plane_reason"] is None and body["angle_reason"] is None
    assert body["exact_reason"] is None


def test_halves_give_a_simplified_surd() -> None:
    body = payload_for(HALVES)
    exact = body["exact"]
    assert texts(exact["normal"]) == ["-9/2", "-13/2", "3"]
    assert exact["normal"][0] == {"text": "-9/2", "numerator": "-9", "denominator": "2"}
    assert exact["magnitude_squared"]["text"] == "143/2"  # 71.5
    assert exact["magnitude"] == {"text": "√286 / 2", "coefficient": "1/2", "radicand": "286"}
    assert exact["area"]["text"] == "√286 / 4"
    # -4.5 / (√286 / 2) = -9 / √286 = -9√286 / 286.
    assert texts(exact["unit_normal"]) == ["-9√286 / 286", "-√286 / 22", "3√286 / 143"]
    assert body["magnitude"] == math.sqrt(71.5)
    assert body["plane"]["equation"] == "-4.5x - 6.5y + 3z = 0"
    assert body["plane"]["exact"]["equation"] == "-9x - 13y + 6z = 0"


def test_decimals_are_read_exactly() -> None:
    # 0.1, 0.3 and 0.6 in doubles are not on one line; as decimals they are.
    query = {**RIGHT, "ax": "0.1", "bx": "0.2", "by": "0.3", "cx": "0.3", "cy": "0.6"}
    body = payload_for(query)
    assert texts(body["exact"]["u"]) == ["1/10", "3/10", "0"]
    assert body["degenerate"] is True and body["normal"] == [0.0, 0.0, 0.0]
    assert body["exact"]["unit_normal"] is None and body["exact"]["magnitude"]["text"] == "0"
    assert body["plane"] is None and "no plane" in body["plane_reason"]
    assert body["angle"] == {"degrees": 0.0, "radians": 0.0}  # u and v point the same way


def test_plane_offset_and_scaling() -> None:
    # A = (1, 0, 0), B = (0, 2, 0), C = (0, 0, 3): n = (6, 3, 2), n · A = 6.
    query = {**RIGHT, "ax": "1", "bx": "0", "by": "2", "cy": "0", "cz": "3"}
    body = payload_for(query)
    assert body["plane"]["equation"] == "6x + 3y + 2z = 6"
    assert body["exact"]["magnitude"]["text"] == "7"
    # A tenth of that: n = (3/50, 3/100, 1/50), n · A = 3/500; scaled to coprime integers.
    tenth = {**RIGHT, "ax": "0.1", "bx": "0", "by": "0.2", "cy": "0", "cz": "0.3"}
    plane = payload_for(tenth)["plane"]
    assert texts([plane["exact"][key] for key in "abcd"]) == ["3/50", "3/100", "1/50", "3/500"]
    assert plane["exact"]["equation"] == "30x + 15y + 10z = 3"
    assert plane["equation"] == "0.06x + 0.03y + 0.02z = 0.006"


def test_angles_near_0_and_180_degrees() -> None:
    opposite = {**RIGHT, "bx": "1", "cx": "-2", "cy": "0"}
    assert payload_for(opposite)["angle"]["degrees"] == 180.0
    sliver = {**RIGHT, "bx": "1", "cx": "1", "cy": "1e-20"}
    angle = payload_for(sliver)["angle"]
    assert angle["radians"] == 1e-20 and angle["degrees"] == math.degrees(1e-20)


def test_a_zero_edge_has_no_angle() -> None:
    body = payload_for({**RIGHT, "bx": "0"})  # B = A
    assert body["angle"] is None
    assert body["angle_reason"] == (
        "u has zero length (points A and B coincide), so the angle between u and v is undefined."
    )
    swapped = payload_for({**RIGHT, "bx": "0", "swap": "on"})
    assert swapped["angle"] is None and swapped["angle_reason"].startswith("v has zero length")


def test_huge_values_keep_a_plane_direction_and_an_angle() -> None:
    # 1e200 has an exponent beyond ±30: the doubles are used and the exact forms left out.
    body = payload_for({**RIGHT, "bx": "1e200", "cy": "1e200"})
    assert body["exact"] is None and "bx, cy have an exponent beyond ±30" in body["exact_reason"]
    assert body["plane"]["c"] is None and body["plane"]["equation"] is None
    assert body["angle"]["degrees"] == 90.0


def test_huge_exponent_text_is_never_made_a_fraction() -> None:
    parsed = read_triangle({**RIGHT, "ax": "1e-99999999"})  # Fraction() of it never ends
    assert "ax" not in parsed.exact and parsed.numbers["ax"] == 0.0
    assert parsed.exact["bx"] == 1 and read_triangle({**RIGHT, "ax": "2.5e-30"}).exact["ax"] == (
        Fraction(25, 10**31)
    )


def test_long_integers_are_left_out() -> None:
    many = "1.00000000000000000000000000001"  # 30 decimals: |n|² needs 61 digits
    body = payload_for({**RIGHT, "bx": many})
    assert body["exact"] is None
    assert body["exact_reason"] == (
        "The exact forms are left out: their integers would have more than 40 digits."
    )
    assert body["plane"]["exact"] is None and body["plane"]["equation"] is not None


def test_json_numbers_use_the_doubles_exact_values() -> None:
    body = calculation_payload(from_doubles([0.0, 0, 0], [0.5, 0, 0], [0, 0.25, 0]))
    assert body["exact"]["magnitude"]["text"] == "1/8"
    tenth = calculation_payload(from_doubles([0.0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]))
    assert tenth["exact"] is None and "GET /api/normal reads decimal text" in tenth["exact_reason"]


@pytest.mark.parametrize(
    ("surd", "text"),
    [
        (Surd(Fraction(1, 2), 286), "√286 / 2"),
        (Surd(Fraction(-9, 286), 286), "-9√286 / 286"),
        (Surd(Fraction(3), 2), "3√2"),
        (Surd(Fraction(-1), 5), "-√5"),
        (Surd(Fraction(-5, 2), 1), "-5/2"),
        (Surd(Fraction(0), 7), "0"),
    ],
)
def test_surd_text(surd: Surd, text: str) -> None:
    assert surd_text(surd) == text


# --- Properties ---------------------------------------------------------------------------------

decimal_text = st.builds(
    lambda digits, point, sign: f"{sign}{digits[:point]}.{digits[point:]}".rstrip("."),
    st.text("0123456789", min_size=1, max_size=6).map(lambda t: "0" + t),
    st.integers(1, 6),
    st.sampled_from(["", "-"]),
)
queries = st.fixed_dictionaries(dict.fromkeys(COORDINATE_FIELDS, decimal_text))


def parse(item: dict[str, str]) -> Fraction:
    return Fraction(int(item["numerator"]), int(item["denominator"]))


def surd_value(item: dict[str, str]) -> tuple[Fraction, int]:
    return Fraction(item["coefficient"]), int(item["radicand"])


def within_an_ulp(exact: float, rounded: float) -> bool:
    """``rounded`` is ``exact`` or one of its two neighbouring doubles."""
    return rounded == exact or math.nextafter(exact, rounded) == rounded


@settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow])
@given(query=queries, swap=st.booleans())
def test_exact_forms_agree_with_the_rounded_values(query: dict[str, str], swap: bool) -> None:
    body = payload_for({**query, **({"swap": "on"} if swap else {})})
    exact = body["exact"]
    if exact is None:
        assert "40 digits" in body["exact_reason"]
        return
    n = [parse(item) for item in exact["normal"]]
    assert parse(exact["magnitude_squared"]) == sum(x * x for x in n)  # |n|² = n · n exactly
    coefficient, radicand = surd_value(exact["magnitude"])
    assert coefficient * coefficient * radicand == sum(x * x for x in n)
    assert [float(x) for x in n] == body["normal"]  # each rounded once
    # Rounding the exact forms once gives the rounded values, within 1 ulp.
    assert within_an_ulp(Surd(coefficient, radicand).rounded(), body["magnitude"])
    area = surd_value(exact["area"])
    assert within_an_ulp(Surd(*area).rounded(), body["area"])
    if exact["unit_normal"] is not None:
        units = [surd_value(item) for item in exact["unit_normal"]]
        assert sum(c * c * r for c, r in units) == 1  # a unit vector, exactly
        for (c, r), value in zip(units, body["unit_normal"], strict=True):
            assert within_an_ulp(Surd(c, r).rounded(), value)
        plane = body["plane"]["exact"]
        assert [parse(plane[key]) for key in "abc"] == n
        a = [Fraction(query[name]) for name in ("ax", "ay", "az")]
        assert parse(plane["d"]) == sum(x * y for x, y in zip(n, a, strict=True))
    angle = body["angle"]
    assert (angle is None) == (body["angle_reason"] is not None)
    if angle is not None:
        assert 0.0 <= angle["degrees"] <= 180.0 and not math.isnan(angle["radians"])


def test_exact_surd_rounds_to_the_rounded_magnitude() -> None:
    surd = Surd(Fraction(1, 2), 286)
    assert surd.rounded() == math.sqrt(71.5) == payload_for(HALVES)["magnitude"]


# --- The integers against plain Fractions ------------------------------------------------------
# The exact path holds its values as integers over one denominator; here every field it feeds
# is computed again the plain way, in Fractions (as the path once did), and must be the same
# JSON to the last bit (the sign of zero included).

TINY = 5e-324  # the smallest subnormal
special = st.sampled_from(
    [0.0, -0.0, TINY, -TINY, sys.float_info.min, -sys.float_info.min, sys.float_info.max, -1e300]
)
#: Eighths, and zeros of both signs: exact values short enough for the exact forms to be shown.
short = st.one_of(st.integers(-64, 64).map(lambda k: k / 8), st.sampled_from([0.0, -0.0]))
double = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False), st.floats(-1e3, 1e3), short, special
)
#: Triangles of short values, or of any doubles.
triangles = st.sampled_from([short, double]).flatmap(
    lambda values: st.lists(st.lists(values, min_size=3, max_size=3), min_size=3, max_size=3)
)
rational = st.fractions(min_value=-100, max_value=100, max_denominator=1000)
rational_point = st.tuples(rational, rational, rational)


def fits(*values: Fraction) -> bool:
    return all(abs(x.numerator) < 10**MAX_DIGITS and x.denominator < 10**MAX_DIGITS for x in values)


def reference_angle(square: Fraction, dot: Fraction) -> float:
    dot_square = dot * dot
    if square <= dot_square:
        ratio = square / dot_square
        return math.atan2(ratio_sqrt(ratio.numerator, ratio.denominator), 1.0 if dot > 0 else -1.0)
    ratio = dot_square / square
    cosine = ratio_sqrt(ratio.numerator, ratio.denominator)
    return math.atan2(1.0, cosine if dot >= 0 else -cosine)


def reference_fields(
    given: tuple[RationalPoint, RationalPoint, RationalPoint], swap: bool, reason: str | None
) -> dict:  # type: ignore[type-arg]
    """u, v and n rounded, the plane, the angle and the exact forms of the payload, from
    Fractions; ``reason`` is why the exact forms are left out when they are too long."""
    a, b, c = given
    p, q, r = (a, c, b) if swap else (a, b, c)
    u = [q[i] - p[i] for i in range(3)]
    v = [r[i] - p[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    square = sum(x * x for x in n)
    dot = sum(x * y for x, y in zip(u, v, strict=True))
    d = sum(x * y for x, y in zip(n, p, strict=True))
    out: dict = {  # type: ignore[type-arg]
        **{
            key: [round_or_none(x) for x in values]
            for key, values in zip("uv", (u, v), strict=True)
        },
        "normal": [round_or_none(x) for x in n],
        "plane": None,
        "plane_reason": NO_PLANE,
        "exact": None,
        "exact_reason": reason,
    }
    forms = None
    coefficient, radicand = square_root(square)
    units = [x / (coefficient * radicand) for x in n] if square else []
    if fits(*a, *b, *c, *u, *v, *n, d, square, coefficient, Fraction(radicand), *units):
        out["exact_reason"] = None
        forms = {
            **{
                key: [rational_json(x) for x in point]
                for key, point in zip("abc", given, strict=True)
            },
            "u": [rational_json(x) for x in u],
            "v": [rational_json(x) for x in v],
            "normal": [rational_json(x) for x in n],
            "magnitude_squared": rational_json(square),
            "magnitude": surd_json(Surd(coefficient, radicand)),
            "unit_normal": [surd_json(Surd(x, radicand)) for x in units] if square else None,
            "area": surd_json(Surd(coefficient / 2, radicand)),
        }
        out["exact"] = forms
    if square:
        rounded = [round_or_none(x) for x in (*n, d)]
        texts = [js_number(x) for x in rounded if x is not None]
        integers = [str(x) for x in integer_plane((n[0], n[1], n[2], d))]
        out["plane"] = {
            **dict(zip("abcd", rounded, strict=True)),
            "equation": equation_text(texts[:3], texts[3]) if len(texts) == 4 else None,
            "exact": None
            if forms is None
            else {
                **{key: rational_json(x) for key, x in zip("abcd", (*n, d), strict=True)},
                "equation": equation_text(integers[:3], integers[3]),
            },
        }
        out["plane_reason"] = None
    out["angle"] = out["angle_reason"] = None
    if not any(u) or not any(v):
        name, end = ("u", "C" if swap else "B") if not any(u) else ("v", "B" if swap else "C")
        out["angle_reason"] = (
            f"{name} has zero length (points A and {end} coincide), so the angle between u and v "
            "is undefined."
        )
    else:
        radians = reference_angle(square, dot)
        out["angle"] = {"degrees": math.degrees(radians), "radians": radians}
    return out


def same_fields(payload: dict, reference: dict) -> None:  # type: ignore[type-arg]
    """The payload's fields of ``reference``, as JSON (so -0.0 is not 0.0)."""
    assert json_bytes({key: payload[key] for key in reference}) == json_bytes(reference)


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(triangle=triangles, swap=st.booleans())
def test_json_numbers_exact_path_is_the_fractions(triangle: list[list[float]], swap: bool) -> None:
    a, b, c = triangle
    calc = from_doubles(a, b, c, swap_winding=swap)
    assert_matches_reference(calc.result, a, b, c, swap=swap)  # |n|, n̂ and the area too
    given_points = tuple(tuple(Fraction(x) for x in point) for point in (a, b, c))
    reference = reference_fields(given_points, swap, TOO_LONG + DOUBLES_HINT)  # type: ignore[arg-type]
    same_fields(calculation_payload(calc), reference)


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(a=rational_point, b=rational_point, c=rational_point, swap=st.booleans())
def test_typed_fractions_exact_path_is_the_fractions(a, b, c, swap: bool) -> None:  # type: ignore[no-untyped-def]
    names = iter(COORDINATE_FIELDS)
    query = {next(names): f"{x.numerator}/{x.denominator}" for point in (a, b, c) for x in point}
    payload = payload_for({**query, **({"swap": "on"} if swap else {})})
    same_fields(payload, reference_fields((a, b, c), swap, TOO_LONG))


@given(triangle=triangles, swap=st.booleans())
def test_exact_values_of_doubles_are_their_fractions(
    triangle: list[list[float]], swap: bool
) -> None:
    a, b, c = triangle
    # The doubles' integers over a power of two, and the Fractions' over their common denominator.
    exact = double_values(exact_triangle(a, b, c, swap_winding=swap))
    given_points = tuple(tuple(Fraction(x) for x in point) for point in (a, b, c))
    fractions = exact_values(*given_points, swap_winding=swap)  # type: ignore[arg-type]
    assert exact.given == fractions.given == given_points
    for name in ("points", "u", "v", "n", "square", "dot", "plane_d"):
        assert getattr(exact, name) == getattr(fractions, name), name


# --- JSON, CSV and page -------------------------------------------------------------------------


def test_json_over_http(client) -> None:  # type: ignore[no-untyped-def]
    body = client.get("/api/normal", params=HALVES).json()
    assert body["exact"]["magnitude"]["text"] == "√286 / 2"
    posted = client.post("/api/normal", json={"a": [0, 0, 0], "b": [1, 0, 1.5], "c": [0, 3, 6.5]})
    assert posted.json()["exact"] == body["exact"]  # halves are doubles: the same exact forms


def test_csv_columns(client) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal.csv", params=HALVES)
    assert response.status_code == 200
    header, row = list(csv.reader(io.StringIO(response.text)))
    assert header == CSV_COLUMNS
    values = dict(zip(header, row, strict=True))
    assert [values[f"exact_n{axis}"] for axis in "xyz"] == ["-9/2", "-13/2", "3"]
    assert values["exact_magnitude_squared"] == "143/2"
    assert values["exact_magnitude"] == "√286 / 2" and values["exact_area"] == "√286 / 4"
    assert values["exact_unit_x"] == "-9√286 / 286"
    assert [values[f"plane_{key}"] for key in "abcd"] == ["-4.5", "-6.5", "3.0", "0.0"]
    assert [values[f"exact_plane_{key}"] for key in "abcd"] == ["-9/2", "-13/2", "3", "0"]
    assert values["exact_plane_equation"] == "-9x - 13y + 6z = 0"
    assert float(values["angle_degrees"]) == pytest.approx(40.93373170227046, abs=1e-12)
    assert float(values["angle_radians"]) == pytest.approx(math.radians(40.93373170227046))


def test_csv_leaves_absent_values_empty(client) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/api/normal.csv", params={**RIGHT, "bx": "0"})  # B = A
    header, row = list(csv.reader(io.StringIO(response.text)))
    values = dict(zip(header, row, strict=True))
    assert values["angle_degrees"] == values["plane_a"] == values["exact_unit_x"] == ""
    assert values["exact_magnitude"] == "0" and values["exact_plane_equation"] == ""


def test_page_typesets_the_exact_forms(client) -> None:  # type: ignore[no-untyped-def]
    page = Page(client.get("/", params=HALVES).text)
    cells = page.cells()
    assert page.one("math", alttext="= √(286) / 2")  # √(143/2) = √286 / 2, one piece a line
    assert page.one("div", class_="formula", **{"data-formula": "√(286) / 4"})
    assert "exactly" in cells["unit_normal-exact"]
    assert page.one("div", class_="formula", **{"data-formula": "−9x − 13y + 6z = 0"})
    assert cells["plane"] == "−4.5x−6.5y+3z=0"  # the MathML's text: the steps have it too
    assert "normal-exact" not in cells  # -4.5, -6.5 and 3 are already exact
    assert page.find(
        "div", class_="formula", **{"data-formula": "40.93373170227046° = 0.7144283933326027 rad"}
    )


def test_page_says_why_exact_forms_are_left_out(client) -> None:  # type: ignore[no-untyped-def]
    page = Page(client.get("/", params={**RIGHT, "bx": "1e200", "cy": "1e200"}).text)
    assert "exponent beyond ±30" in page.cells()["exact-reason"]
    degenerate = Page(client.get("/", params={**RIGHT, "bx": "0"}).text).cells()
    assert degenerate["angle"].startswith("undefined: u has zero length")
    assert degenerate["plane"].startswith("none: There is no plane")
