"""Tests for mesh_normal.triangle.normal: the exact, once-rounded normal of one triangle."""

from __future__ import annotations

import dataclasses
import math
import sys
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal import TriangleNormal, triangle_normal
from mesh_normal.triangle import normal as core
from tests.mesh_normal._reference import (
    exact_triangle,
    is_rounded_sqrt,
    round_or_none,
    sqrt_outcome,
)

AXES = "xyz"
MIN_NORMAL = sys.float_info.min

finite_floats = st.floats(allow_nan=False, allow_infinity=False)
# Wide exponent range plus plenty of ordinary and integer-valued coordinates.
coordinates = st.one_of(
    finite_floats,
    st.floats(-1e3, 1e3),
    st.integers(-50, 50).map(float),
)
points = st.tuples(coordinates, coordinates, coordinates)
small_int_points = st.tuples(*[st.integers(-(2**20), 2**20).map(float)] * 3)


@st.composite
def slivers(draw: st.DrawFn) -> tuple[tuple[float, ...], ...]:
    """Triangles that are collinear up to a tiny (often sub-ulp) perturbation."""
    a = draw(st.tuples(*[st.floats(-1e6, 1e6)] * 3))
    d = draw(st.tuples(*[st.floats(-1e3, 1e3)] * 3))
    s, t = draw(st.floats(-4, 4)), draw(st.floats(-4, 4))
    eps = draw(st.tuples(*[st.floats(-1e-12, 1e-12)] * 3))
    b = tuple(a[i] + s * d[i] for i in range(3))
    c = tuple(a[i] + t * d[i] + eps[i] for i in range(3))
    return a, b, c


def neg(values: tuple[float | None, ...]) -> tuple[float | None, ...]:
    return tuple(None if x is None else -x for x in values)


def all_floats(result: TriangleNormal) -> list[float]:
    """Every float anywhere in a result."""
    values: list[float] = []
    for field in dataclasses.fields(result):
        value = getattr(result, field.name)
        if isinstance(value, tuple):
            values.extend(x for x in value if isinstance(x, float))
        elif isinstance(value, float):
            values.append(value)
    return values


def assert_finite(result: TriangleNormal) -> None:
    assert all(math.isfinite(x) for x in all_floats(result)), result


def assert_matches_reference(result: TriangleNormal, a, b, c, *, swap: bool = False) -> None:
    """Every value is the exact one rounded once; None exactly when out of range."""
    u, v, n, square = exact_triangle(a, b, c, swap=swap)
    missing: list[str] = []
    for name, got, exact in (("u", result.u, u), ("v", result.v, v)):
        assert got == tuple(round_or_none(x) for x in exact), (name, got)
        missing += [f"{name}_{axis}" for axis, x in zip(AXES, got, strict=True) if x is None]
    assert result.degenerate == (square == 0)
    if square == 0:
        assert result.normal == (0.0, 0.0, 0.0)
        assert result.magnitude == 0.0
        assert result.area == 0.0
        assert result.unit_normal is None
        assert result.message
        return
    assert result.normal == tuple(round_or_none(x) for x in n)
    missing += [f"n_{axis}" for axis, x in zip(AXES, result.normal, strict=True) if x is None]
    for name, got, exact_square in (
        ("magnitude", result.magnitude, square),
        ("area", result.area, square / 4),
    ):
        if got is None:
            assert sqrt_outcome(exact_square) != "ok", name
            missing.append(name)
        else:
            assert is_rounded_sqrt(got, exact_square), (name, got)
    assert result.unit_normal is not None
    for got, exact in zip(result.unit_normal, n, strict=True):
        ratio = exact * exact / square
        if exact == 0 or sqrt_outcome(ratio) == "underflow":
            assert got == 0.0
        else:
            assert (got < 0) == (exact < 0)
            assert is_rounded_sqrt(abs(got), ratio), (got, exact)
    if missing:
        assert result.message is not None
        for name in missing:
            assert f"{name} (about " in result.message, (name, result.message)
    else:
        assert result.message is None
    assert_finite(result)


# --- hand-computed cases ------------------------------------------------------------------


def test_unit_right_triangle() -> None:
    r = triangle_normal((0, 0, 0), (1, 0, 0), (0, 1, 0))
    assert r.a == (0.0, 0.0, 0.0) and r.b == (1.0, 0.0, 0.0) and r.c == (0.0, 1.0, 0.0)
    assert r.order == "ABC"
    assert r.u == (1.0, 0.0, 0.0)
    assert r.v == (0.0, 1.0, 0.0)
    assert r.normal == (0.0, 0.0, 1.0)
    assert r.magnitude == 1.0
    assert r.area == 0.5
    assert r.unit_normal == (0.0, 0.0, 1.0)
    assert r.degenerate is False
    assert r.message is None
    assert all(isinstance(x, float) for x in all_floats(r))


def test_hand_computed_non_axis_triangle() -> None:
    # u = (3, 4, 0), v = (0, 0, 5), n = (4*5 - 0*0, 0*0 - 3*5, 3*0 - 4*0) = (20, -15, 0),
    # |n| = 25, area 12.5, unit normal (0.8, -0.6, 0).
    r = triangle_normal((1, 2, 3), (4, 6, 3), (1, 2, 8))
    assert r.u == (3.0, 4.0, 0.0)
    assert r.v == (0.0, 0.0, 5.0)
    assert r.normal == (20.0, -15.0, 0.0)
    assert r.magnitude == 25.0
    assert r.area == 12.5
    assert r.unit_normal == (0.8, -0.6, 0.0)
    assert r.order == "ABC"
    assert not r.degenerate and r.message is None

    s = triangle_normal((1, 2, 3), (4, 6, 3), (1, 2, 8), swap_winding=True)
    assert s.order == "ACB"
    assert s.u == (0.0, 0.0, 5.0) and s.v == (3.0, 4.0, 0.0)
    assert s.normal == (-20.0, 15.0, 0.0)
    assert s.unit_normal == (-0.8, 0.6, 0.0)
    assert s.magnitude == 25.0 and s.area == 12.5
    assert (s.a, s.b, s.c) == (r.a, r.b, r.c)  # the points are reported as given


def test_hand_computed_irrational_length() -> None:
    # u = (1, 2, 3), v = (4, 5, 6): n = (2*6 - 3*5, 3*4 - 1*6, 1*5 - 2*4) = (-3, 6, -3),
    # |n| = sqrt(54) = 3 sqrt(6), unit normal (-1, 2, -1) / sqrt(6).
    r = triangle_normal((0, 0, 0), (1, 2, 3), (4, 5, 6))
    assert r.normal == (-3.0, 6.0, -3.0)
    assert is_rounded_sqrt(r.magnitude, 54)
    assert is_rounded_sqrt(r.area, Fraction(54, 4))
    assert r.magnitude == math.sqrt(54)  # math.sqrt is correctly rounded too
    assert r.unit_normal is not None
    ex, ey, ez = r.unit_normal
    assert ex == ez < 0 < ey
    assert is_rounded_sqrt(-ex, Fraction(1, 6)) and is_rounded_sqrt(ey, Fraction(4, 6))
    assert_matches_reference(r, (0, 0, 0), (1, 2, 3), (4, 5, 6))


def test_integer_and_float_inputs_agree() -> None:
    assert triangle_normal([1, 2, 3], [4, 6, 3], [1, 2, 8]) == triangle_normal(
        (1.0, 2.0, 3.0), (4.0, 6.0, 3.0), (1.0, 2.0, 8.0)
    )


def test_docstring_example() -> None:
    assert triangle_normal((0, 0, 0), (1, 0, 0), (0, 1, 0)).unit_normal == (0.0, 0.0, 1.0)


# --- exactness --------------------------------------------------------------------------

SLIVER = ((0.0, 0.0, 0.0), (1 + 2**-52, 1.0, 0.0), (1.0, 1 - 2**-53, 0.0))


def test_sliver_that_naive_floats_call_flat() -> None:
    a, b, c = SLIVER
    # Why this case matters: the plain float cross product says the triangle is flat.
    naive_z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    assert naive_z == 0.0

    r = triangle_normal(a, b, c)
    exact_z = Fraction(b[0]) * Fraction(c[1]) - Fraction(b[1]) * Fraction(c[0])
    assert exact_z == Fraction(1, 2**53) - Fraction(1, 2**105) != 0
    assert not r.degenerate
    assert r.normal == (0.0, 0.0, float(exact_z))
    assert r.normal[2] == 2**-53 - 2**-105  # representable, so exactly this
    assert r.magnitude == float(exact_z)
    assert r.area == float(exact_z) / 2
    assert r.unit_normal == (0.0, 0.0, 1.0)
    assert r.message is None
    assert_matches_reference(r, a, b, c)

    s = triangle_normal(a, b, c, swap_winding=True)
    assert s.unit_normal == (0.0, 0.0, -1.0)
    assert s.normal[2] == -float(exact_z)


def test_tiny_coordinates_whose_normal_underflows() -> None:
    a, b, c = (0.0, 0.0, 0.0), (1e-200, 0.0, 0.0), (0.0, 1e-200, 0.0)
    r = triangle_normal(a, b, c)
    assert not r.degenerate
    assert r.unit_normal == (0.0, 0.0, 1.0)
    assert r.u == (1e-200, 0.0, 0.0) and r.v == (0.0, 1e-200, 0.0)
    assert r.normal == (0.0, 0.0, None)
    assert r.magnitude is None and r.area is None
    assert r.message is not None
    assert "magnitude" in r.message and "n_z" in r.message and "area" in r.message
    assert "smallest double" in r.message
    assert "1e-400" in r.message  # the size of the lost value
    assert_finite(r)
    assert_matches_reference(r, a, b, c)


def test_one_normal_component_underflows_but_the_rest_is_fine() -> None:
    # u = (1, 0, 1e-200), v = (0, 1e-200, 0): n = (-1e-400, 0, 1e-200).
    a, b, c = (0.0, 0.0, 0.0), (1.0, 0.0, 1e-200), (0.0, 1e-200, 0.0)
    r = triangle_normal(a, b, c)
    assert r.normal == (None, 0.0, 1e-200)
    assert r.magnitude == 1e-200 and r.area == 5e-201
    assert r.unit_normal is not None
    assert r.unit_normal[0] == -1e-200 and r.unit_normal[2] == 1.0
    assert r.message is not None and "n_x" in r.message and "magnitude" not in r.message
    assert_matches_reference(r, a, b, c)


@pytest.mark.parametrize("size", [1e200, 1e250, 1e300, 1e308, sys.float_info.max])
def test_huge_coordinates(size: float) -> None:
    a, b, c = (0.0, 0.0, 0.0), (size, 0.0, 0.0), (0.0, size, 0.0)
    r = triangle_normal(a, b, c)
    assert not r.degenerate
    assert r.unit_normal == (0.0, 0.0, 1.0)
    assert r.normal == (0.0, 0.0, None)
    assert r.magnitude is None and r.area is None
    assert r.message is not None and "beyond the largest double" in r.message
    assert "1.8e308" in r.message
    assert_finite(r)
    assert_matches_reference(r, a, b, c)


def test_huge_coordinates_with_overflowing_edges() -> None:
    # u = (-2e308, 2e308, 0), v = (0, 2e308, 1e308): n = (2e616, 2e616, -4e616).
    a, b, c = (1e308, -1e308, 0.0), (-1e308, 1e308, 0.0), (1e308, 1e308, 1e308)
    r = triangle_normal(a, b, c)
    assert r.u == (None, None, 0.0)
    assert r.v == (0.0, None, 1e308)
    assert r.normal == (None, None, None)
    assert r.magnitude is None and r.area is None
    assert r.unit_normal is not None
    ex, ey, ez = r.unit_normal
    assert ex == ey > 0 > ez
    assert is_rounded_sqrt(ex, Fraction(1, 6)) and is_rounded_sqrt(-ez, Fraction(4, 6))
    assert r.message is not None
    for name in ("u_x", "u_y", "v_y", "n_x", "n_y", "n_z", "magnitude", "area"):
        assert name in r.message
    assert "beyond the largest double" in r.message
    assert r.message.endswith("The unit normal is exact all the same.")
    assert_finite(r)
    assert_matches_reference(r, a, b, c)


def test_magnitude_overflows_but_area_does_not() -> None:
    # n = (0, 0, 2e308): beyond the largest double, while the area 1e308 is not.
    a, b, c = (-1e308, 0.0, 0.0), (1e308, 0.0, 0.0), (0.0, 1.0, 0.0)
    r = triangle_normal(a, b, c)
    assert r.u == (None, 0.0, 0.0)
    assert r.normal == (0.0, 0.0, None)
    assert r.magnitude is None
    assert r.area == 1e308
    assert r.unit_normal == (0.0, 0.0, 1.0)
    assert r.message is not None and "u_x" in r.message and "magnitude" in r.message
    assert "area" not in r.message
    assert_matches_reference(r, a, b, c)


def test_mixed_scales_in_one_triangle() -> None:
    a, b, c = (1e300, 0.0, 0.0), (0.0, 1e-300, 0.0), (0.0, 0.0, 1e-300)
    r = triangle_normal(a, b, c)
    assert not r.degenerate
    assert_matches_reference(r, a, b, c)
    assert_matches_reference(triangle_normal(a, b, c, swap_winding=True), a, b, c, swap=True)


def test_subnormal_coordinates() -> None:
    tiny = 5e-324
    a, b, c = (0.0, 0.0, 0.0), (tiny, 0.0, 0.0), (0.0, tiny, 3 * tiny)
    r = triangle_normal(a, b, c)
    assert not r.degenerate
    assert r.unit_normal is not None
    # n = (0, -3 tiny**2, tiny**2): direction (0, -3, 1) / sqrt(10).
    assert r.unit_normal[0] == 0.0
    assert is_rounded_sqrt(-r.unit_normal[1], Fraction(9, 10))
    assert is_rounded_sqrt(r.unit_normal[2], Fraction(1, 10))
    assert_matches_reference(r, a, b, c)


# --- degenerate triangles ---------------------------------------------------------------


def assert_degenerate(r: TriangleNormal, sentences: int = 1) -> str:
    assert r.degenerate is True
    assert r.normal == (0.0, 0.0, 0.0)
    assert r.magnitude == 0.0
    assert r.area == 0.0
    assert r.unit_normal is None
    assert r.message is not None
    # One sentence explains; a second one only where a value is out of range.
    assert r.message.endswith(".") and r.message.count(".") == sentences
    assert r.message[0].isupper()
    return r.message


@pytest.mark.parametrize("swap", [False, True])
def test_collinear(swap: bool) -> None:
    r = triangle_normal((0, 0, 0), (1, 1, 1), (3, 3, 3), swap_winding=swap)
    message = assert_degenerate(r)
    assert "one line" in message
    assert r.u == ((3.0,) * 3 if swap else (1.0,) * 3)


def test_exactly_collinear_points_that_naive_floats_call_a_triangle() -> None:
    # Three points on the line y = 3x (3x is exact for these x), but the float cross
    # product of their rounded differences is not zero.
    xs = [
        float.fromhex(h)
        for h in ("0x1.8a7dd82c07cd0p-45", "0x1.09210a5d2f350p-57", "0x1.9ea77c65c1e50p-30")
    ]
    a, b, c = ((x, 3 * x, 0.0) for x in xs)
    assert all(Fraction(p[1]) == 3 * Fraction(p[0]) for p in (a, b, c))
    naive_z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    assert naive_z != 0.0
    r = triangle_normal(a, b, c)
    assert "one line" in assert_degenerate(r)
    assert_matches_reference(r, a, b, c)


@pytest.mark.parametrize(
    ("a", "b", "c", "swap", "named"),
    [
        ((1, 2, 3), (1, 2, 3), (4, 5, 7), False, {"A", "B"}),
        ((1, 2, 3), (4, 5, 7), (1, 2, 3), False, {"A", "C"}),
        ((4, 5, 7), (1, 2, 3), (1, 2, 3), False, {"B", "C"}),
        ((1, 2, 3), (1, 2, 3), (4, 5, 7), True, {"A", "B"}),
        ((1, 2, 3), (4, 5, 7), (1, 2, 3), True, {"A", "C"}),
        ((4, 5, 7), (1, 2, 3), (1, 2, 3), True, {"B", "C"}),
        ((0.0, 0.0, 0.0), (-0.0, 0.0, -0.0), (1, 1, 1), False, {"A", "B"}),
    ],
)
def test_two_equal_points(a, b, c, swap: bool, named: set[str]) -> None:
    r = triangle_normal(a, b, c, swap_winding=swap)
    message = assert_degenerate(r)
    assert "coincide" in message
    assert message.startswith("Points ")
    mentioned = {name for name in "ABC" if f" {name} " in f" {message} "}
    assert mentioned == named, message


@pytest.mark.parametrize("swap", [False, True])
def test_all_points_equal(swap: bool) -> None:
    r = triangle_normal((2.5, -1, 7), (2.5, -1, 7), (2.5, -1, 7), swap_winding=swap)
    message = assert_degenerate(r)
    assert "All three points are the same" in message
    assert r.u == (0.0, 0.0, 0.0) and r.v == (0.0, 0.0, 0.0)


def test_degenerate_with_huge_coordinates_has_no_infinity() -> None:
    r = triangle_normal((-1e308, 0, 0), (1e308, 0, 0), (0, 0, 0))
    assert_degenerate(r, sentences=3)  # "about 2e+308" and "1.8e308" hold two more dots
    assert r.u == (None, 0.0, 0.0)  # 2e308 does not fit a double
    assert_finite(r)


def test_degenerate_message_explains_a_missing_edge_value() -> None:
    r = triangle_normal((-1e308, 0, 0), (1e308, 0, 0), (0, 0, 0))
    assert r.u[0] is None
    assert r.message is not None and "u_x" in r.message


# --- reference check on random doubles --------------------------------------------------


@given(points, points, points, st.booleans())
@settings(max_examples=200, deadline=None)
def test_every_value_is_the_exact_value_rounded_once(a, b, c, swap: bool) -> None:
    assert_matches_reference(triangle_normal(a, b, c, swap_winding=swap), a, b, c, swap=swap)


@given(slivers(), st.booleans())
@settings(max_examples=200, deadline=None)
def test_slivers_match_the_reference(triangle, swap: bool) -> None:
    a, b, c = triangle
    assert_matches_reference(triangle_normal(a, b, c, swap_winding=swap), a, b, c, swap=swap)


# --- properties -------------------------------------------------------------------------


@given(points, points, points)
@settings(max_examples=200, deadline=None)
def test_swapping_the_winding_negates_the_normal(a, b, c) -> None:
    r = triangle_normal(a, b, c)
    s = triangle_normal(a, b, c, swap_winding=True)
    assert (r.order, s.order) == ("ABC", "ACB")
    assert (s.a, s.b, s.c) == (r.a, r.b, r.c)
    assert (s.u, s.v) == (r.v, r.u)
    assert s.degenerate == r.degenerate
    assert s.magnitude == r.magnitude
    assert s.area == r.area
    if r.degenerate:
        assert s.normal == r.normal == (0.0, 0.0, 0.0)
        assert s.unit_normal is None
    else:
        assert s.normal == neg(r.normal)
        assert r.unit_normal is not None
        assert s.unit_normal == neg(r.unit_normal)


@pytest.mark.parametrize("exponent", range(-515, -509))
def test_the_area_by_the_subnormals_is_rounded_once(exponent: int) -> None:
    # |n| = 2**(2 * exponent) * sqrt(491): the area is |n| halved above the subnormals and
    # rounded from the exact value below them, where halving would round twice.
    s = 2.0**exponent
    a, b, c = (0.0, 0.0, 0.0), (s, 0.0, 3 * s), (0.0, 7 * s, s)
    assert_matches_reference(triangle_normal(a, b, c), a, b, c)


@given(points, points, points)
@settings(max_examples=200, deadline=None)
def test_magnitude_is_twice_the_area(a, b, c) -> None:
    r = triangle_normal(a, b, c)
    if r.magnitude is not None and r.area is not None and r.area >= MIN_NORMAL:
        assert r.magnitude == 2 * r.area
    if r.degenerate:
        assert r.magnitude == r.area == 0.0


@given(points, points, points)
@settings(max_examples=200, deadline=None)
def test_unit_normal_has_length_one(a, b, c) -> None:
    r = triangle_normal(a, b, c)
    if r.degenerate:
        assert r.unit_normal is None
        return
    assert r.unit_normal is not None
    assert abs(math.hypot(*r.unit_normal) - 1.0) <= 4 * math.ulp(1.0)
    length_squared = sum(Fraction(x) ** 2 for x in r.unit_normal)
    assert abs(length_squared - 1) <= 8 * Fraction(math.ulp(1.0))


@given(
    small_int_points,
    small_int_points,
    small_int_points,
    st.tuples(*[st.integers(-(2**30), 2**30)] * 3),
    st.booleans(),
)
@settings(max_examples=200)
def test_integer_translation_leaves_the_normal_unchanged(a, b, c, shift, swap: bool) -> None:
    def moved(p: tuple[float, ...]) -> tuple[float, ...]:
        return tuple(x + s for x, s in zip(p, shift, strict=True))  # exact: all below 2**53

    r = triangle_normal(a, b, c, swap_winding=swap)
    t = triangle_normal(moved(a), moved(b), moved(c), swap_winding=swap)
    assert (t.u, t.v, t.normal) == (r.u, r.v, r.normal)
    assert (t.magnitude, t.area, t.unit_normal) == (r.magnitude, r.area, r.unit_normal)
    assert (t.degenerate, t.message) == (r.degenerate, r.message)


@given(small_int_points, small_int_points, small_int_points, st.integers(-600, 600))
@settings(max_examples=200)
def test_power_of_two_scaling_scales_the_normal_exactly(a, b, c, k: int) -> None:
    def scaled(p: tuple[float, ...]) -> tuple[float, ...]:
        return tuple(math.ldexp(x, k) for x in p)  # exact: at most 21 bits, in range

    r = triangle_normal(a, b, c)
    s = triangle_normal(scaled(a), scaled(b), scaled(c))
    assert s.degenerate == r.degenerate
    assert s.u == tuple(math.ldexp(x, k) for x in r.u)  # type: ignore[arg-type]
    # Integer corners: n is an exact integer below 2**53, so n * 4**k is the exact value.
    assert all(x is not None and x == int(x) for x in r.normal)
    for got, base in zip(s.normal, r.normal, strict=True):
        assert got == round_or_none(Fraction(base) * Fraction(4) ** k)
        if got is not None and abs(got) >= MIN_NORMAL:
            assert got == math.ldexp(base, 2 * k)
    assert s.unit_normal == r.unit_normal  # the direction does not change at all
    if r.degenerate:
        return
    assert r.magnitude is not None and r.area is not None
    for got, base in ((s.magnitude, r.magnitude), (s.area, r.area)):
        expected = Fraction(base) * Fraction(4) ** k
        if MIN_NORMAL <= expected <= sys.float_info.max:
            assert got == math.ldexp(base, 2 * k)  # scaling commutes with rounding here
        elif expected >= 2 * sys.float_info.max:
            assert got is None
    assert_finite(s)


@given(points, points, points, st.booleans())
@settings(max_examples=200, deadline=None)
def test_never_nan_or_infinity(a, b, c, swap: bool) -> None:
    r = triangle_normal(a, b, c, swap_winding=swap)
    assert_finite(r)
    assert r.unit_normal is not None or r.degenerate
    assert (r.message is None) == (
        not r.degenerate and None not in (*r.u, *r.v, *r.normal, r.magnitude, r.area)
    )


# --- invalid input ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("a", "b", "c", "match"),
    [
        ((0, 0), (1, 0, 0), (0, 1, 0), "Point A must have 3 coordinates, not 2"),
        ((0, 0, 0), (1, 0, 0, 0), (0, 1, 0), "Point B must have 3 coordinates, not 4"),
        ((0, 0, 0), (1, 0, 0), (), "Point C must have 3 coordinates, not 0"),
        ((math.nan, 0, 0), (1, 0, 0), (0, 1, 0), r"A\.x must be a finite number"),
        ((0, 0, 0), (1, math.inf, 0), (0, 1, 0), r"B\.y must be a finite number"),
        ((0, 0, 0), (1, 0, 0), (0, 1, -math.inf), r"C\.z must be a finite number"),
        ((True, 0, 0), (1, 0, 0), (0, 1, 0), r"A\.x must be a number"),
        ((0, 0, 0), (1, 0, False), (0, 1, 0), r"B\.z must be a number"),
        ((0, 0, 0), (1, 0, 0), ("0", 1, 0), r"C\.x must be a number"),
        ((0, 0, 0), (1, 0, 0), "xyz", r"C\.x must be a number"),
        ((0, 0, None), (1, 0, 0), (0, 1, 0), r"A\.z must be a number"),
        ((0, 0, 0), (1, 0, 0), (0, 1, 1j), r"C\.z must be a number"),
    ],
)
@pytest.mark.parametrize("swap", [False, True])
def test_invalid_input_raises_value_error(a, b, c, match: str, swap: bool) -> None:
    with pytest.raises(ValueError, match=match):
        triangle_normal(a, b, c, swap_winding=swap)


def test_integer_too_large_for_a_double_raises_value_error() -> None:
    with pytest.raises(ValueError, match=r"A\.x must be a finite number"):
        triangle_normal((10**400, 0, 0), (1, 0, 0), (0, 1, 0))


def test_result_is_frozen() -> None:
    r = triangle_normal((0, 0, 0), (1, 0, 0), (0, 1, 0))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.area = 1.0  # type: ignore[misc]


# --- The exact values behind the rounding (what the worked steps show) ------------------------


def _fractions(values: tuple[int, int, int], exponent: int) -> list[Fraction]:
    return [Fraction(value, 2**exponent) for value in values]


@given(points, points, points, st.booleans())
@settings(max_examples=300, deadline=None)
def test_exact_values_are_the_exact_edges_and_cross_product(a, b, c, swap: bool) -> None:  # type: ignore[no-untyped-def]
    exact = core.exact_triangle(a, b, c, swap_winding=swap)
    u, v, n, square = exact_triangle(a, b, c, swap=swap)  # the reference, in Fractions
    assert _fractions(exact.u, exact.scale) == u
    assert _fractions(exact.v, exact.scale) == v
    assert _fractions(exact.n, 2 * exact.scale) == n
    assert Fraction(exact.square, 2 ** (4 * exact.scale)) == square
    assert Fraction(exact.dot, 2 ** (2 * exact.scale)) == sum(
        x * y for x, y in zip(u, v, strict=True)
    )
    assert exact.order == ("ACB" if swap else "ABC")


@given(points, points, points, st.booleans())
@settings(max_examples=200, deadline=None)
def test_the_normal_is_the_exact_values_rounded_once(a, b, c, swap: bool) -> None:  # type: ignore[no-untyped-def]
    exact = core.exact_triangle(a, b, c, swap_winding=swap)
    result = triangle_normal(a, b, c, swap_winding=swap)
    assert result.u == tuple(round_or_none(x) for x in _fractions(exact.u, exact.scale))
    assert result.degenerate is (exact.square == 0)
    if not result.degenerate:
        assert result.normal == tuple(
            round_or_none(x) for x in _fractions(exact.n, 2 * exact.scale)
        )


def test_exact_values_check_their_input_like_the_normal() -> None:
    with pytest.raises(ValueError, match="finite"):
        core.exact_triangle((0, 0, math.inf), (1, 0, 0), (0, 1, 0))
