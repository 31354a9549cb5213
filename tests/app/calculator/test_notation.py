"""app/calculator/notation.py: how the worked steps write numbers and chains."""

from __future__ import annotations

import math
from fractions import Fraction

import pytest

from app.calculator.mathml import ident
from app.calculator.notation import (
    Shown,
    base,
    chain,
    float_text,
    given,
    num,
    product,
    range_notes,
    rounded,
    seg,
    shown,
    sub,
    term,
    vector,
)
from app.web.formatting import decimals_text, number_text


def test_rounding_is_once_and_out_of_range_is_none() -> None:
    assert rounded(Fraction(1, 3)) == 1 / 3
    assert rounded(Fraction(10**400)) is None  # overflows
    assert rounded(Fraction(1, 10**400)) is None  # nonzero, rounds to 0
    assert shown(Fraction(1, 2)) == Shown(0.5, True)
    assert shown(Fraction(1, 3)) == Shown(1 / 3, False)


def test_negatives_use_the_real_minus_sign_and_get_parentheses_where_they_read_wrong() -> None:
    assert (term(given(-2.0)).text, term(given(2.0)).text) == ("(−2)", "2")
    assert product(given(3.0), given(-1.0)).text == "3·(−1)"
    assert [base(given(x)).text for x in (-6.0, 1e-7, 6.0)] == ["(−6)", "(1e−7)", "6"]
    assert vector([given(-1.5), Shown(None, False), given(0.0)]).text == "(−1.5, out of range, 0)"


def test_a_number_keeps_its_machine_text_for_the_precision_setting() -> None:
    markup = num(given(-1.5)).markup
    assert markup == '<mn class="num" data-num="-1.5">−1.5</mn>'


@pytest.mark.parametrize(
    ("x", "decimals", "text"),
    [
        (0.0, 4, "0.0000"),
        (-0.0, 2, "0.00"),
        (-1.5, 4, "−1.5000"),
        (0.125, 2, "0.13"),  # half away from zero, as JavaScript's toFixed
        (123.456, 2, "123.46"),
        (2.5e-7, 2, "2.50e−7"),
        (-1e20, 4, "−1.0000e+20"),
        (9.9999e20, 2, "1.00e+21"),
    ],
)
def test_fixed_decimals_read_as_javascript_with_the_real_minus(
    x: float, decimals: int, text: str
) -> None:
    assert decimals_text(x, decimals) == text
    assert number_text(x, decimals) == text


def test_full_numbers_use_the_real_minus_sign_in_the_mantissa_and_exponent() -> None:
    assert number_text(-2.5e-7) == "−2.5e−7"
    assert number_text(0.0) == "0" and number_text(-0.0) == "0"


def test_a_chain_turns_to_approximately_from_the_first_rounded_number() -> None:
    third = shown(Fraction(1, 3))
    x, again = ident("x"), ident("again")
    line = chain(seg(x), seg(num(third), third), seg(again, given(1.0)))
    assert line.text == f"x ≈ {1 / 3} ≈ again"
    assert "<mo>≈</mo>" in line.markup and "<mo>=</mo>" not in line.markup
    two = given(2.0)
    assert (
        chain(seg(ident("y")), sub(ident("left out"), Shown(None, False)), seg(num(two), two)).text
        == "y = 2"
    )


def test_float_words_and_range_notes() -> None:
    assert [float_text(x) for x in (math.nan, math.inf, -math.inf, 0.5, -0.5)] == [
        "NaN",
        "Infinity",
        "−Infinity",
        "0.5",
        "−0.5",
    ]
    assert range_notes([("a", given(1.0))]) == ()
    (note,) = range_notes([("n_x", Shown(None, False)), ("n_y", Shown(None, False))])
    assert "n_x and n_y" in note and "They show" in note and "4.9e−324" in note
