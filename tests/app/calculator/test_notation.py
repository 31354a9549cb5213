"""app/calculator/notation.py: how the worked steps write numbers and chains."""

from __future__ import annotations

import math
from fractions import Fraction

from app.calculator.notation import (
    Shown,
    base,
    chain,
    factor,
    float_text,
    given,
    range_notes,
    rounded,
    seg,
    shown,
    sub,
    term,
)


def test_rounding_is_once_and_out_of_range_is_none() -> None:
    assert rounded(Fraction(1, 3)) == 1 / 3
    assert rounded(Fraction(10**400)) is None  # overflows
    assert rounded(Fraction(1, 10**400)) is None  # nonzero, rounds to 0
    assert shown(Fraction(1, 2)) == Shown(0.5, True)
    assert shown(Fraction(1, 3)) == Shown(1 / 3, False)


def test_negatives_and_exponents_get_parentheses_where_they_read_wrong() -> None:
    assert (term(given(-2.0)), term(given(2.0))) == ("(-2)", "2")
    assert factor(given(3.0)) == "(3)"
    assert (base(given(-6.0)), base(given(1e-7)), base(given(6.0))) == ("(-6)", "(1e-7)", "6")


def test_a_chain_turns_to_approximately_from_the_first_rounded_number() -> None:
    third = shown(Fraction(1, 3))
    line = chain(seg("x"), seg("1 / 3"), seg("0.333…", third), seg("again", given(1.0)))
    assert line == "x = 1 / 3 ≈ 0.333… ≈ again"
    assert chain(seg("y"), sub("left out", Shown(None, False)), seg("2", given(2.0))) == "y = 2"


def test_float_words_and_range_notes() -> None:
    assert [float_text(x) for x in (math.nan, math.inf, -math.inf, 0.5)] == [
        "NaN",
        "Infinity",
        "-Infinity",
        "0.5",
    ]
    assert range_notes([("a", given(1.0))]) == ()
    (note,) = range_notes([("n_x", Shown(None, False)), ("n_y", Shown(None, False))])
    assert "n_x and n_y" in note and "They show" in note
