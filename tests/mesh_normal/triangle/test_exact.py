"""mesh_normal.triangle.exact: fixed-point conversion and once-rounded values and roots."""

from __future__ import annotations

import math
import random
import sys
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.triangle.exact import (
    OutOfRange,
    bracketed,
    ratio_sqrt,
    root_bracket,
    root_over,
    round_scaled,
    split_square,
    sqrt_scaled,
    square_root,
    to_fixed,
    unit_vector,
)
from tests.mesh_normal._reference import (
    MAX,
    RefOutOfRange,
    is_rounded_sqrt,
    round_ref,
    sqrt_outcome,
)

TINY = 5e-324  # the smallest subnormal, 2**-1074
finite_floats = st.floats(allow_nan=False, allow_infinity=False)


def rounded_or_kind(value: int, exponent: int) -> float | str:
    try:
        return round_scaled(value, exponent)
    except OutOfRange as error:
        return error.kind


def reference_or_kind(value: Fraction) -> float | str:
    try:
        return round_ref(value)
    except RefOutOfRange as error:
        return error.kind


def same_float(x: float | str, y: float | str) -> bool:
    """Equal, including the sign of zero."""
    if isinstance(x, str) or isinstance(y, str):
        return x == y
    return x == y and math.copysign(1.0, x) == math.copysign(1.0, y)


# --- the reference itself ---------------------------------------------------------------


@given(st.integers(-(2**2200), 2**2200), st.integers(0, 4400))
@settings(max_examples=200)
def test_reference_rounding_agrees_with_fraction_float(value: int, exponent: int) -> None:
    exact = Fraction(value, 2**exponent)
    try:
        expected: float | str = float(exact)
    except OverflowError:
        expected = "overflow"
    if expected == 0.0 and value != 0:
        expected = "underflow"
    assert reference_or_kind(exact) == expected


# --- to_fixed ---------------------------------------------------------------------------


@given(st.lists(finite_floats, min_size=1, max_size=9))
@settings(max_examples=200)
def test_to_fixed_is_exact_and_uses_the_smallest_scale(values: list[float]) -> None:
    integers, scale = to_fixed(values)
    assert scale >= 0
    assert all(isinstance(x, int) for x in integers)
    for value, integer in zip(values, integers, strict=True):
        assert Fraction(integer, 2**scale) == Fraction(value)
    if scale > 0:  # a smaller scale would not do: some integer is odd
        assert any(x % 2 == 1 for x in integers)


def test_to_fixed_examples() -> None:
    assert to_fixed([1.0, 2.0, -3.0]) == ([1, 2, -3], 0)
    assert to_fixed([0.5, 0.25, 0.0]) == ([2, 1, 0], 2)
    assert to_fixed([TINY]) == ([1], 1074)
    assert to_fixed([-0.0]) == ([0], 0)


# --- round_scaled -----------------------------------------------------------------------


@given(st.integers(-(2**2300), 2**2300), st.integers(0, 4500))
@settings(max_examples=200)
def test_round_scaled_matches_the_integer_reference(value: int, exponent: int) -> None:
    got = rounded_or_kind(value, exponent)
    assert same_float(got, reference_or_kind(Fraction(value, 2**exponent)))


@given(st.integers(1, 2**60), st.integers(-1200, 1000))
@settings(max_examples=200)
def test_round_scaled_near_the_range_limits(mantissa: int, power: int) -> None:
    # mantissa * 2**power, from below half the smallest subnormal to beyond the largest double.
    value, exponent = mantissa << (power + 1200), 1200
    for signed in (value, -value):
        got = rounded_or_kind(signed, exponent)
        assert same_float(got, reference_or_kind(Fraction(signed, 2**exponent)))


def test_round_scaled_exact_values() -> None:
    assert round_scaled(3, 1) == 1.5
    assert round_scaled(-3, 1) == -1.5
    assert round_scaled(1, 1074) == TINY
    assert round_scaled(2**53 - 1, 0) == 2.0**53 - 1


def test_round_scaled_zero_is_zero_at_any_scale() -> None:
    assert same_float(round_scaled(0, 0), 0.0)
    assert same_float(round_scaled(0, 10_000), 0.0)


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (2**53 + 1, 2.0**53),  # halfway between 2**53 and 2**53 + 2: to the even one (down)
        (2**53 + 3, 2.0**53 + 4),  # halfway between 2**53 + 2 and 2**53 + 4: up
        (-(2**53 + 1), -(2.0**53)),
        (-(2**53 + 3), -(2.0**53 + 4)),
        (2**54 + 2, 2.0**54),  # halfway, down to even
        (2**54 + 3, 2.0**54 + 4),  # above halfway
    ],
)
def test_round_scaled_ties_to_even(value: int, expected: float) -> None:
    assert round_scaled(value, 0) == expected
    # The same tie far down, at a scale of 2**-1000, and in the subnormal range.
    assert round_scaled(value, 1000) == math.ldexp(expected, -1000)
    assert round_scaled(value << 1, 1) == expected


def test_round_scaled_ties_to_even_in_the_subnormal_range() -> None:
    # 1.5 and 2.5 times the smallest subnormal round to 2 times it (even).
    assert round_scaled(3, 1075) == 2 * TINY
    assert round_scaled(5, 1075) == 2 * TINY
    assert round_scaled(7, 1075) == 4 * TINY


def test_round_scaled_overflow() -> None:
    threshold = 2**1024 - 2**970  # halfway between the largest double and 2**1024
    assert round_scaled(threshold - 1, 0) == MAX
    assert round_scaled(-(threshold - 1), 0) == -MAX
    assert round_scaled((threshold - 1) << 3, 3) == MAX
    cases = [(threshold, 0), (-threshold, 0), (2**1024, 0), (2**5000, 3000), (threshold << 50, 50)]
    for value, exponent in cases:
        with pytest.raises(OutOfRange) as info:
            round_scaled(value, exponent)
        assert info.value.kind == "overflow"


def test_round_scaled_underflow() -> None:
    for value, exponent in [(1, 1075), (-1, 1075), (1, 5000), (2**100, 1175 + 100)]:
        with pytest.raises(OutOfRange) as info:
            round_scaled(value, exponent)
        assert info.value.kind == "underflow"
    # Just above half the smallest subnormal rounds up to it, not to zero.
    assert round_scaled(2**1074 + 1, 2149) == TINY
    assert round_scaled(-(2**1074 + 1), 2149) == -TINY
    assert round_scaled(3, 1076) == TINY


def test_out_of_range_is_an_exception_with_a_kind() -> None:
    error = OutOfRange("overflow")
    assert isinstance(error, Exception)
    assert error.kind == "overflow"
    assert str(error) == "overflow"


# --- sqrt_scaled ------------------------------------------------------------------------


def check_sqrt_scaled(square: int, exponent: int) -> None:
    exact_square = Fraction(square, 2 ** (2 * exponent))
    outcome = sqrt_outcome(exact_square) if square else "ok"
    try:
        got = sqrt_scaled(square, exponent)
    except OutOfRange as error:
        assert error.kind == outcome, (square, exponent)  # noqa: PT017 (either outcome)
        return
    assert outcome == "ok", (square, exponent, got)
    assert is_rounded_sqrt(got, exact_square), (square, exponent, got)


@given(st.integers(0, 2**4400), st.integers(0, 4400))
@settings(max_examples=200)
def test_sqrt_scaled_is_correctly_rounded(square: int, exponent: int) -> None:
    check_sqrt_scaled(square, exponent)


@given(st.integers(0, 2**200), st.integers(-2, 2), st.integers(0, 1200))
@settings(max_examples=200)
def test_sqrt_scaled_near_perfect_squares(root: int, offset: int, exponent: int) -> None:
    check_sqrt_scaled(max(root * root + offset, 0), exponent)


def test_sqrt_scaled_many_random_integers() -> None:
    rng = random.Random(20240601)
    for _ in range(1500):
        bits = rng.randint(1, 4300)
        square = rng.getrandbits(bits) | 1
        exponent = rng.randint(0, 2 * 1074 + bits // 2 + 10)
        check_sqrt_scaled(square, exponent)


def test_sqrt_scaled_examples() -> None:
    assert sqrt_scaled(0, 123) == 0.0
    assert sqrt_scaled(4, 0) == 2.0
    assert sqrt_scaled(4, 1) == 1.0
    assert sqrt_scaled(2, 0) == math.sqrt(2)
    assert sqrt_scaled(10**40, 0) == 1e20
    for square in range(1, 2000):
        assert sqrt_scaled(square, 0) == math.sqrt(square)  # math.sqrt is correctly rounded


def test_sqrt_scaled_exact_ties_go_to_even() -> None:
    # sqrt((2**53 + 1)**2) = 2**53 + 1 is halfway between two doubles: the sticky bit must
    # stay clear so that it rounds to the even one.
    assert sqrt_scaled((2**53 + 1) ** 2, 0) == 2.0**53
    assert sqrt_scaled((2**53 + 3) ** 2, 0) == 2.0**53 + 4
    # One more or less than the tie's square is not a tie.
    assert sqrt_scaled((2**53 + 1) ** 2 + 1, 0) == 2.0**53 + 2
    assert sqrt_scaled((2**53 + 3) ** 2 - 1, 0) == 2.0**53 + 2


def test_sqrt_scaled_sticky_bit_breaks_false_ties() -> None:
    # The root truncated to 53 + 64 bits is exactly a midpoint, but the true root is a hair
    # above it: only the sticky bit tells the rounding to go up rather than to even.
    midpoint = (2**53 + 1) << 64
    assert sqrt_scaled(midpoint**2 + 1, 64) == 2.0**53 + 2
    assert sqrt_scaled(midpoint**2, 64) == 2.0**53  # the real tie goes to even
    assert sqrt_scaled(midpoint**2 - 1, 64) == 2.0**53


def test_ratio_sqrt_sticky_bit_breaks_false_ties() -> None:
    # sqrt(part / whole) is just above / at / below 0.5 + 2**-54, the midpoint of 0.5 and
    # the next double, with the truncated root landing exactly on that midpoint.
    middle, whole = ((2**53 + 1) << 20) ** 2, 2**148
    assert ratio_sqrt(middle + 1, whole) == 0.5 + 2**-53
    assert ratio_sqrt(middle, whole) == 0.5
    assert ratio_sqrt(middle - 1, whole) == 0.5


def test_sqrt_scaled_out_of_range() -> None:
    threshold = 2**1024 - 2**970
    assert sqrt_scaled(threshold**2 - 1, 0) == MAX
    with pytest.raises(OutOfRange) as info:
        sqrt_scaled(threshold**2, 0)  # exactly halfway: ties to "even" 2**1024
    assert info.value.kind == "overflow"
    with pytest.raises(OutOfRange) as info:
        sqrt_scaled(1, 1075)  # 2**-1075, halfway between 0 and the smallest subnormal
    assert info.value.kind == "underflow"
    assert sqrt_scaled(2, 1075) == TINY
    assert sqrt_scaled(1, 1074) == TINY
    assert sqrt_scaled(4**1022, 2044) == sys.float_info.min  # 2**-1022, normal


# --- ratio_sqrt -------------------------------------------------------------------------


def check_ratio_sqrt(part: int, whole: int) -> None:
    got = ratio_sqrt(part, whole)
    ratio = Fraction(part, whole)
    assert 0.0 <= got <= 1.0
    if part and sqrt_outcome(ratio) == "underflow":
        assert got == 0.0
    else:
        assert is_rounded_sqrt(got, ratio), (part, whole, got)


@given(st.data())
@settings(max_examples=200)
def test_ratio_sqrt_is_correctly_rounded(data: st.DataObject) -> None:
    whole = data.draw(st.integers(1, 2**4400))
    part = data.draw(st.integers(0, whole))
    check_ratio_sqrt(part, whole)


@given(st.integers(1, 2**300), st.integers(0, 4400))
@settings(max_examples=200)
def test_ratio_sqrt_small_ratios(part: int, extra_bits: int) -> None:
    whole = (part << extra_bits) + 1
    check_ratio_sqrt(part, whole)


def test_ratio_sqrt_examples() -> None:
    assert ratio_sqrt(0, 7) == 0.0
    assert ratio_sqrt(7, 7) == 1.0
    assert ratio_sqrt(1, 4) == 0.5
    assert ratio_sqrt(9, 25) == 0.6
    assert ratio_sqrt(16, 25) == 0.8
    assert ratio_sqrt(1, 2) == math.sqrt(0.5)
    assert ratio_sqrt(1, 2**2148) == TINY  # exactly the smallest subnormal
    assert ratio_sqrt(10**600, 10**600 + 1) == 1.0  # a hair below 1 rounds to 1


def test_ratio_sqrt_below_the_smallest_double_is_zero_not_an_error() -> None:
    assert ratio_sqrt(1, 2**2150) == 0.0  # 2**-1075: a tie, to the even zero
    assert ratio_sqrt(1, 2**5000) == 0.0
    assert ratio_sqrt(1, 2**2150 - 1) == TINY  # just above the tie


def test_ratio_sqrt_unit_vector_components_have_length_one() -> None:
    rng = random.Random(7)
    for _ in range(300):
        n = [rng.getrandbits(rng.randint(1, 2000)) * rng.choice((-1, 1)) for _ in range(3)]
        square = sum(x * x for x in n)
        if square == 0:
            continue
        unit = [ratio_sqrt(x * x, square) for x in n]
        length_squared = sum(Fraction(x) ** 2 for x in unit)
        assert abs(length_squared - 1) <= Fraction(8, 2**53)


# --- One root for |n| and n / |n| ----------------------------------------------------------


def unit_by_ratios(n: tuple[int, int, int], square: int) -> tuple[float, ...]:
    return tuple(math.copysign(ratio_sqrt(x * x, square), x) if x else 0.0 for x in n)


@given(st.tuples(*[st.integers(-(2**700), 2**700)] * 3), st.integers(0, 3))
@settings(max_examples=300)
def test_one_root_rounds_as_a_root_each(n: tuple[int, int, int], scale: int) -> None:
    """unit_vector and bracketed from root_bracket agree with the exact roots taken one by one."""
    square = n[0] ** 2 + n[1] ** 2 + n[2] ** 2
    if square == 0:
        return
    root, shift = root_bracket(square)
    assert root**2 <= square << (2 * shift) < (root + 1) ** 2
    assert unit_vector(n, square, root, shift) == unit_by_ratios(n, square)
    denominator = 1 << (60 * scale)
    magnitude = bracketed(root, denominator << shift)
    if magnitude is not None:
        assert magnitude == root_over(square, denominator)


def test_one_root_at_exact_ties_and_whole_numbers() -> None:
    for n in [(3, 4, 0), (0, 0, -5), (1, 1, 0), (2, -3, 6), (1, 2**600, 0), (2**53 + 1, 0, 0)]:
        square = sum(x * x for x in n)
        root, shift = root_bracket(square)
        assert unit_vector(n, square, root, shift) == unit_by_ratios(n, square)
    # |n| exactly a whole number: the bracket [root, root + 1) starts on it.
    root, shift = root_bracket(49)
    assert bracketed(root, 1 << shift) == 7.0
    # sqrt(2**2150) = 2**1075 over 2**2150: the tie below the smallest double is left to the
    # exact rounding (None), as is a value beyond the largest double.
    root, shift = root_bracket(1)
    assert bracketed(root, 1 << (shift + 1075)) is None
    root, shift = root_bracket(4**1100)
    assert bracketed(root, 1 << shift) is None


# --- Squares out of a radicand ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("value", "split"),
    [(1, (1, 1)), (2, (1, 2)), (4, (2, 1)), (72, (6, 2)), (286, (1, 286)), (1000, (10, 10))],
)
def test_split_square_by_hand(value: int, split: tuple[int, int]) -> None:
    assert split_square(value) == split


def test_split_square_stops_at_its_limit() -> None:
    # 10007 is prime: past a limit of 100 its square stays inside, next to another factor.
    assert split_square(3 * 10007**2 * 10009, limit=100) == (1, 3 * 10007**2 * 10009)
    assert split_square(3 * 10007**2 * 10009, limit=20_000) == (10007, 3 * 10009)
    # What the trial divisions leave is checked once for a perfect square.
    assert split_square(10007**2, limit=100) == (10007, 1)


def test_split_square_is_quick_on_huge_numbers() -> None:
    big = 2**4000 + 1  # no small factor to speak of; the loop ends at the limit
    outside, inside = split_square(big * 4)
    assert outside * outside * inside == big * 4 and outside % 2 == 0


def test_square_root_by_hand() -> None:
    assert square_root(Fraction(143, 2)) == (Fraction(1, 2), 286)  # √71.5 = √286 / 2
    assert square_root(Fraction(49)) == (Fraction(7), 1)
    assert square_root(Fraction(0)) == (Fraction(0), 1)
    assert square_root(Fraction(8, 9)) == (Fraction(2, 3), 2)
    with pytest.raises(ValueError, match="at least 0"):
        square_root(Fraction(-1))


def _square_free(value: int) -> bool:
    return all(value % (d * d) for d in range(2, math.isqrt(value) + 1))


@given(st.integers(min_value=1, max_value=10**7))
def test_split_square_is_a_factorisation(value: int) -> None:
    outside, inside = split_square(value)
    assert outside * outside * inside == value
    assert _square_free(inside)  # below limit**2 the splitting is complete


@given(st.fractions(min_value=0, max_denominator=10**6).filter(lambda q: q < 10**6))
def test_square_root_squares_back(square: Fraction) -> None:
    coefficient, radicand = square_root(square)
    assert coefficient >= 0 and radicand >= 1
    assert coefficient * coefficient * radicand == square
