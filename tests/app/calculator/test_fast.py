"""The fast path of POST /api/normal against the exact path: the same bytes, or no answer."""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from app.calculator.calculation import calculation_payload, from_doubles
from app.calculator.exact_forms import _fits, equation_text
from app.calculator.fast import (
    _certified_root,
    _dyadic_fits,
    _equation,
    _number_text,
    fast_payload,
)
from app.web.formatting import js_number
from app.web.jsonio import json_bytes
from mesh_normal.triangle.exact import ratio_sqrt

Point = list[float]


def exact_bytes(a: Point, b: Point, c: Point, swap: bool) -> bytes:
    return json_bytes(calculation_payload(from_doubles(a, b, c, swap_winding=swap)))


def agrees(a: Point, b: Point, c: Point, swap: bool) -> bool:
    """Whether the fast path answered (the same bytes as the exact path: asserted)."""
    fast = fast_payload(a, b, c, swap)
    if fast is not None:
        assert json_bytes(fast) == exact_bytes(a, b, c, swap)
    return fast is not None


BENCH = ([1.5, -2.25, 0.1], [4.0, 0.5, -3.0], [0.3, 7.0, 2.5])


@pytest.mark.parametrize("swap", [False, True])
def test_decimals_take_the_fast_path(swap: bool) -> None:
    assert agrees(*BENCH, swap)
    fast = fast_payload(*BENCH, swap)
    assert fast is not None
    assert fast["exact"] is None and fast["exact_reason"].startswith("The exact forms are left")
    assert fast["u"] == [2.5, 2.75, -3.1] if not swap else [-1.2, 9.25, 2.4]


@pytest.mark.parametrize(
    "points",
    [
        ([0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]),  # integers: the exact forms fit
        ([0.0, 0, 0], [0.5, 0, 0], [0.0, 0.25, 0]),  # halves and quarters: likewise
        ([0.1, 0.2, 0.3], [0.1, 0.2, 0.3], [1.0, 2, 3]),  # repeated points: degenerate
        ([0.1, 0.2, 0.3], [0.2, 0.4, 0.6], [0.4, 0.8, 1.2]),  # on one line (exactly)
        ([1e300, 0.1, 0], [0.1, 1e300, 0], [0.0, 0.1, 1e300]),  # n beyond the doubles
        ([1e-300, 0.1, 0], [0.1, 1e-300, 0], [0.3, 0.7, 1e-300]),  # d far below, n fine
        ([1e-170, 0, 0.1], [0.1, 1e-170, 0], [0, 0.1, 3e-170]),
        ([5e-324, 0, 0], [0, 5e-324, 0], [0, 0, 5e-324]),  # subnormals: n underflows
        ([1.0, 2, 3], [4.0, 5, 6], [7.0, 8, 10]),  # integers with area
        ([-0.0, 0.1, 0], [0.0, 0.3, 1], [0.7, -0.0, 0.2]),  # signed zeros
    ],
)
@pytest.mark.parametrize("swap", [False, True])
def test_awkward_triangles(points: tuple[Point, Point, Point], swap: bool) -> None:
    agrees(*points, swap)


def test_what_falls_back() -> None:
    """Exact forms that fit, degenerate triangles and values beyond the doubles: no answer."""
    assert fast_payload([0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0], False) is None
    assert fast_payload([0.1, 0.2, 0.3], [0.2, 0.4, 0.6], [0.4, 0.8, 1.2], False) is None
    assert fast_payload([1e300, 0.1, 0], [0.1, 1e300, 0], [0.0, 0.1, 1e300], False) is None
    assert fast_payload([1, 2, 3], [4.0, 5, 6], [7.0, 8, 10], False) is None  # type: ignore[list-item]


# --- Random and adversarial triangles -----------------------------------------------------------

#: Any finite double: huge and tiny exponents, subnormals, signed zeros.
ANY = st.floats(allow_nan=False, allow_infinity=False)
#: Short decimals, the usual JSON input (their doubles have long exact values).
DECIMAL = st.integers(-(10**7), 10**7).map(lambda i: i / 1000)
#: Small integers and halves: exact forms that fit, ties in the roundings.
DYADIC = st.integers(-64, 64).map(lambda i: i / 2)
#: A mantissa at any exponent: sums of these round to ties and lose bits.
SCALED = st.builds(math.ldexp, st.integers(-(2**53), 2**53), st.integers(-1100, 970))
COORDINATE = st.one_of(ANY, DECIMAL, DYADIC, SCALED)
POINT = st.lists(COORDINATE, min_size=3, max_size=3)


@settings(max_examples=600, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(POINT, POINT, POINT, st.booleans())
@example([2.0**-54, 0.1, 0.0], [1.0, 0.2, 0.0], [0.3, 1.0, 0.5], False)  # u.x is a tie
@example([0.1, 0.2, 0.3], [0.1, 0.2, 0.3 + 2**-40], [0.7, 0.1, 0.3], True)
def test_same_bytes_as_the_exact_path(a: Point, b: Point, c: Point, swap: bool) -> None:
    agrees(a, b, c, swap)


def _near_line(a: Point, b: Point, t: float, nudge: float, axis: int) -> Point:
    """A point on line AB at ``t`` (rounded), one coordinate moved by ``nudge`` ulps."""
    point = [a[i] + t * (b[i] - a[i]) for i in range(3)]
    point[axis] = point[axis] + nudge * math.ulp(point[axis])
    return point


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(DECIMAL, min_size=3, max_size=3),
    st.lists(DECIMAL, min_size=3, max_size=3),
    st.floats(-3, 3),
    st.integers(-4, 4),
    st.integers(0, 2),
    st.booleans(),
)
def test_near_collinear(a: Point, b: Point, t: float, nudge: int, axis: int, swap: bool) -> None:
    c = _near_line(a, b, t, nudge, axis)
    if all(math.isfinite(x) for x in c):
        agrees(a, b, c, swap)


@settings(max_examples=300, deadline=None)
@given(st.lists(DECIMAL, min_size=9, max_size=9), st.integers(-330, 330), st.booleans())
def test_decimals_at_any_scale(values: list[float], exponent: int, swap: bool) -> None:
    """The same shape scaled by 2**exponent: n, |n| and d reach the doubles' ends."""
    x = [math.ldexp(value, exponent) for value in values]
    agrees(x[0:3], x[3:6], x[6:9], swap)


@settings(max_examples=300, deadline=None)
@given(st.lists(DECIMAL, min_size=9, max_size=9), st.booleans())
def test_decimals_mostly_take_the_fast_path(values: list[float], swap: bool) -> None:
    """Decimals with area (forms too long, values in range) never fall back."""
    a, b, c = values[0:3], values[3:6], values[6:9]
    if (
        calculation_payload(from_doubles(a, b, c))["exact"] is None
        and not from_doubles(a, b, c).result.degenerate
    ):
        assert agrees(a, b, c, swap)


@given(ANY)
@example(1e16)
@example(9999999999999998.0)
@example(1e-4)
@example(0.0001)
@example(-0.0)
@example(123.0)
def test_number_text_is_js_number(x: float) -> None:
    assert _number_text(x) == js_number(x)


@given(st.integers(-(10**45), 10**45), st.integers(0, 500))
@example(10**40, 0)
@example(10**40 - 1, 0)
@example(1, 132)
@example(1, 133)
@example(2, 133)
def test_dyadic_fits_as_a_fraction(value: int, bits: int) -> None:
    assert _dyadic_fits(value, bits) == _fits(Fraction(value, 2**bits))


def test_the_api_answers_as_the_exact_path(client: TestClient) -> None:
    for a, b, c in (BENCH, ([0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0])):
        for swap in (False, True):
            body = {"a": a, "b": b, "c": c, "swap_winding": swap}
            response = client.post("/api/normal", json=body)
            assert response.status_code == 200
            assert response.content == exact_bytes(a, b, c, swap)


@settings(max_examples=500)
@given(st.integers(1, 2**400), st.integers(0, 2**400), st.integers(-3, 3))
@example(1, 4, 0)  # 1/2: a power of two, left to the exact root
@example(2, 2, 0)  # 1
@example(9, 16, 0)  # 3/4 exactly
@example((2**53 + 1) ** 2, 2**108, 0)  # a tie between two doubles
def test_a_certified_root_is_the_exact_root(part: int, extra: int, ulps: int) -> None:
    """Whatever the guess (a few ulps off), a certified root is ratio_sqrt's double."""
    whole = part + extra
    guess = math.sqrt(part / whole)
    for _ in range(abs(ulps)):
        guess = math.nextafter(guess, math.inf if ulps > 0 else 0.0)
    value = _certified_root(part, whole, guess)
    exact = ratio_sqrt(part, whole)
    assert value is None or value == exact
    mantissa, exponent = math.frexp(exact)
    top, scaled = int(mantissa * 2**53), part << (108 - 2 * exponent)
    tie = scaled in ((2 * top - 1) ** 2 * whole, (2 * top + 1) ** 2 * whole)
    awkward = mantissa == 0.5 or tie  # a power of two, or the root exactly between two doubles
    if abs(ulps) <= 1 and 2.0**-1000 < guess < 0.5 and not awkward:
        assert value is not None  # near its answer, away from the awkward cases: certified


@given(
    st.lists(
        st.one_of(ANY, DYADIC, st.sampled_from([1.0, -1.0, 0.0, -0.0])), min_size=4, max_size=4
    )
)
def test_equation_is_equation_text(values: list[float]) -> None:
    texts = [js_number(value) for value in values]
    assert _equation(values[:3], values[3]) == equation_text(texts[:3], texts[3])
