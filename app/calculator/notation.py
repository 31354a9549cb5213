"""How the worked steps write numbers and chains of equalities.

A number is shown as JavaScript's ``String(x)`` writes it, with the real minus sign, and
"out of range" beyond the double range; a chain ``first = second = third`` turns "=" into "≈"
from the first segment that holds a rounded number. Each piece is a
:class:`~app.calculator.mathml.Formula` (MathML and plain text). For example::

    chain(seg(indexed("n", "x")), seg(product(two, three)), seg(num(six), six))  # n_x = 2·3 = 6
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from math import isfinite, isnan

from app.calculator.mathml import (
    APPROX,
    DOT,
    EQUALS,
    Formula,
    chained,
    column,
    fenced,
    joined,
    number,
    plain_number,
    word,
)
from app.web.formatting import for_people, js_number, number_text
from mesh_normal.tolerances import LARGEST_DOUBLE_TEXT


@dataclass(frozen=True, slots=True)
class Shown:
    """A number as displayed: its double (None beyond the double range) and whether exact."""

    value: float | None
    exact: bool


# --- Numbers ----------------------------------------------------------------------------------


def rounded(x: Fraction) -> float | None:
    """``x`` rounded once to the nearest double; None when it overflows or underflows to 0."""
    try:
        value = float(x)  # int / int: correctly rounded
    except OverflowError:
        return None
    return None if value == 0 and x != 0 else value


def shown(x: Fraction) -> Shown:
    return matching(rounded(x), x)


def matching(value: float | None, x: Fraction) -> Shown:
    """A value the core rounded from ``x``."""
    return Shown(value, value is not None and Fraction(value) == x)


def given(value: float) -> Shown:
    return Shown(value, True)


def num(s: Shown) -> Formula:
    return word("out of range") if s.value is None else number(s.value)


def _negative_or_exponent(s: Shown, exponents: bool) -> bool:
    if s.value is None:
        return False
    return s.value < 0 or (exponents and "e" in js_number(s.value))


def term(s: Shown) -> Formula:
    """A number in a sum or difference: negatives in parentheses."""
    return fenced(num(s)) if _negative_or_exponent(s, exponents=False) else num(s)


def base(s: Shown) -> Formula:
    """A number to be squared or multiplied: ``(−6)²`` and ``(1e−7)²``, but ``6²``."""
    return fenced(num(s)) if _negative_or_exponent(s, exponents=True) else num(s)


def product(*factors: Shown) -> Formula:
    """``2·(−1)``: factors joined by a centred dot."""
    return joined((base(s) for s in factors), DOT)


def vector(values: Iterable[Shown]) -> Formula:
    return column([num(s) for s in values])


def float_text(x: float) -> str:
    """A plain float result, including JavaScript's words for the non-finite ones."""
    if isnan(x):
        return "NaN"
    if not isfinite(x):
        return "Infinity" if x > 0 else "−Infinity"
    return number_text(x)


def float_number(x: float) -> Formula:
    return number(x) if isfinite(x) else plain_number(float_text(x))


def float_term(x: float) -> Formula:
    return fenced(float_number(x)) if x < 0 else float_number(x)


# --- Chains of equalities ---------------------------------------------------------------------

Segment = tuple[Formula, tuple[Shown, ...]]


def seg(formula: Formula, *values: Shown) -> Segment:
    return formula, values


def sub(formula: Formula, *operands: Shown) -> Segment | None:
    """A substitution, left out when one of its numbers is out of range."""
    return None if any(s.value is None for s in operands) else (formula, operands)


def chain(*segments: Segment | None) -> Formula:
    """``first = second = third``, with "≈" from the first segment holding a rounded number."""
    exact, parts = True, list[Formula]()
    for segment in segments:
        if segment is None:
            continue
        formula, values = segment
        exact = exact and all(s.exact or s.value is None for s in values)
        if parts:
            parts.append(EQUALS if exact else APPROX)
        parts.append(formula)
    return chained(parts)


def listing(names: Sequence[str]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def range_notes(named: Iterable[tuple[str, Shown]]) -> tuple[str, ...]:
    names = [name for name, s in named if s.value is None]
    if not names:
        return ()
    one, smallest = len(names) == 1, for_people("4.9e-324")
    return (
        f"Beyond the range of doubles (above {LARGEST_DOUBLE_TEXT}, or nonzero but below "
        f"{smallest}): {listing(names)}. {'It shows' if one else 'They show'} as “out of "
        f"range”; the calculation keeps the exact {'value' if one else 'values'}.",
    )
