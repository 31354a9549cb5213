"""How the worked steps write numbers and chains of equalities.

A number is shown as JavaScript's ``String(x)`` writes it, "out of range" beyond the double
range; a chain ``first = second = third`` turns "=" into "≈" from the first segment that holds
a rounded number. For example::

    chain(seg("n_x"), seg("(2)(3) − (0)(0)"), seg("6", given(6.0)))  # n_x = (2)(3) − (0)(0) = 6
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from math import isfinite, isnan

from app.web.formatting import js_number
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


def num(s: Shown) -> str:
    return "out of range" if s.value is None else js_number(s.value)


def term(s: Shown) -> str:
    """A number in a sum or difference: negatives in parentheses."""
    text = num(s)
    return f"({text})" if text.startswith("-") else text


def factor(s: Shown) -> str:
    return f"({num(s)})"


def base(s: Shown) -> str:
    """A number to be squared: ``(-6)²`` and ``(1e-7)²``, but ``6²``."""
    text = num(s)
    return f"({text})" if text.startswith("-") or "e" in text else text


def vector(values: Iterable[Shown]) -> str:
    return "(" + ", ".join(num(s) for s in values) + ")"


def float_text(x: float) -> str:
    """A plain float result, including JavaScript's words for the non-finite ones."""
    if isnan(x):
        return "NaN"
    if not isfinite(x):
        return "Infinity" if x > 0 else "-Infinity"
    return js_number(x)


def float_term(x: float) -> str:
    text = float_text(x)
    return f"({text})" if text.startswith("-") else text


# --- Chains of equalities ---------------------------------------------------------------------

Segment = tuple[str, tuple[Shown, ...]]


def seg(text: str, *values: Shown) -> Segment:
    return text, values


def sub(text: str, *operands: Shown) -> Segment | None:
    """A substitution, left out when one of its numbers is out of range."""
    return None if any(s.value is None for s in operands) else (text, operands)


def chain(*segments: Segment | None) -> str:
    """``first = second = third``, with "≈" from the first segment holding a rounded number."""
    exact, parts = True, list[str]()
    for segment in segments:
        if segment is None:
            continue
        text, values = segment
        exact = exact and all(s.exact or s.value is None for s in values)
        parts.append(f"{'=' if exact else '≈'} {text}" if parts else text)
    return " ".join(parts)


def listing(names: Sequence[str]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def range_notes(named: Iterable[tuple[str, Shown]]) -> tuple[str, ...]:
    names = [name for name, s in named if s.value is None]
    if not names:
        return ()
    one = len(names) == 1
    return (
        f"Beyond the range of doubles (above {LARGEST_DOUBLE_TEXT}, or nonzero but below "
        f"4.9e-324): {listing(names)}. {'It shows' if one else 'They show'} as “out of "
        f"range”; the calculation keeps the exact {'value' if one else 'values'}.",
    )
