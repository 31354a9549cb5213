"""Independent exact references for the core tests.

Nothing here uses ``int / int`` or ``float(Fraction)`` (which is the same CPython routine
that ``mesh_normal.triangle.exact.round_scaled`` relies on), so the tests of the rounding code
compare against a second, separately written implementation.
"""

from __future__ import annotations

import math
import sys
from fractions import Fraction

MAX = sys.float_info.max
#: Values at or beyond this round to infinity (half an ulp above the largest double).
OVERFLOW_THRESHOLD = Fraction(2**1024 - 2**970)
#: Half the smallest subnormal: values at or below it round to zero (ties to even).
UNDERFLOW_THRESHOLD = Fraction(1, 2**1075)


class RefOutOfRange(Exception):
    def __init__(self, kind: str) -> None:
        super().__init__(kind)
        self.kind = kind


def round_ref(value: Fraction | int) -> float:
    """Round an exact rational to the nearest double, ties to even, with integer arithmetic.

    Raises RefOutOfRange("overflow" / "underflow") like ``mesh_normal.triangle.exact.round_scaled``.
    """
    value = Fraction(value)
    if value == 0:
        return 0.0
    sign = -1.0 if value < 0 else 1.0
    num, den = abs(value.numerator), value.denominator
    # e0 = floor(log2(num / den)).
    e0 = num.bit_length() - den.bit_length()
    if (num << max(0, -e0)) < (den << max(0, e0)):
        e0 -= 1
    quantum = max(e0 - 52, -1074)  # the spacing of doubles around the value
    if quantum >= 0:
        mantissa, remainder = divmod(num, den << quantum)
        divisor = den << quantum
    else:
        mantissa, remainder = divmod(num << -quantum, den)
        divisor = den
    if 2 * remainder > divisor or (2 * remainder == divisor and mantissa % 2 == 1):
        mantissa += 1
    if mantissa == 0:
        raise RefOutOfRange("underflow")
    if mantissa.bit_length() + quantum > 1024:
        raise RefOutOfRange("overflow")
    return sign * math.ldexp(mantissa, quantum)


def round_or_none(value: Fraction | int) -> float | None:
    try:
        return round_ref(value)
    except RefOutOfRange:
        return None


def _even(x: float) -> bool:
    """Whether the last significand bit of the positive double ``x`` is zero."""
    quotient = Fraction(x) / Fraction(math.ulp(x))
    assert quotient.denominator == 1
    return quotient.numerator % 2 == 0


def sqrt_outcome(square: Fraction | int) -> str:
    """For ``square > 0``: "overflow", "underflow" or "ok" for the rounded ``sqrt(square)``."""
    square = Fraction(square)
    if square >= OVERFLOW_THRESHOLD**2:
        return "overflow"
    if square <= UNDERFLOW_THRESHOLD**2:
        return "underflow"
    return "ok"


def is_rounded_sqrt(x: float, square: Fraction | int) -> bool:
    """Whether the double ``x >= 0`` is ``sqrt(square)`` correctly rounded (ties to even).

    Compares the exact square with the exact squares of the midpoints between ``x`` and its
    neighbours, so no square root is ever taken.
    """
    square = Fraction(square)
    if square == 0:
        return x == 0.0
    if not (math.isfinite(x) and x > 0):
        return False
    below = Fraction(math.nextafter(x, 0.0))
    above = Fraction(2**1024) if x == MAX else Fraction(math.nextafter(x, math.inf))
    low_mid = (Fraction(x) + below) / 2
    high_mid = (Fraction(x) + above) / 2
    if not low_mid**2 <= square <= high_mid**2:
        return False
    if square in (low_mid**2, high_mid**2):
        return _even(x)
    return True


def cross(u: list[Fraction], v: list[Fraction]) -> list[Fraction]:
    return [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]


def exact_triangle(
    a: tuple[float, ...], b: tuple[float, ...], c: tuple[float, ...], *, swap: bool = False
) -> tuple[list[Fraction], list[Fraction], list[Fraction], Fraction]:
    """Exact u, v, n and n . n of a triangle, in Fractions."""
    if swap:
        b, c = c, b
    pa, pb, pc = ([Fraction(x) for x in p] for p in (a, b, c))
    u = [pb[i] - pa[i] for i in range(3)]
    v = [pc[i] - pa[i] for i in range(3)]
    n = cross(u, v)
    return u, v, n, sum(x * x for x in n)
