"""Exact arithmetic on doubles, rounded once.

Every finite double is an integer times a power of two, so a group of doubles can be held
as Python integers over one common scale 2**-k (k is at most 1074, the exponent of the
smallest subnormal). Differences of such integers are exact, their products are exact
multiples of 2**-2k, and a sum of squares of those is an exact multiple of 2**-4k.
Rounding to a double happens once, at the end, through Python's correctly rounded
``int / int`` division.
"""

from __future__ import annotations

from fractions import Fraction
from math import isqrt

from mesh_normal.tolerances import SURD_TRIAL_LIMIT

#: Extra bits kept below a double's 53 when rounding a square root (plus a sticky bit).
_GUARD_BITS = 64


class OutOfRange(Exception):
    """An exact value is nonzero but rounds to zero, or is beyond the largest double."""

    def __init__(self, kind: str) -> None:
        super().__init__(kind)
        self.kind = kind  # "overflow" or "underflow"


def to_fixed(values: list[float]) -> tuple[list[int], int]:
    """Return integers ``X`` and the smallest ``k >= 0`` with ``X[i] * 2**-k == values[i]``.

    The values must be finite.
    """
    ratios = [x.as_integer_ratio() for x in values]
    # Each denominator is a power of two, 2**(bit_length - 1).
    scale = max([den for _, den in ratios]).bit_length() - 1
    return [num << (scale + 1 - den.bit_length()) for num, den in ratios], scale


def round_scaled(value: int, exponent: int) -> float:
    """Round ``value * 2**-exponent`` to the nearest double, ties to even.

    Raises
    ------
    OutOfRange
        ``"overflow"`` when the result is beyond the double range, ``"underflow"`` when
        ``value`` is nonzero but the result rounds to zero.
    """
    if value == 0:
        return 0.0
    try:
        result = value / (1 << exponent)
    except OverflowError:
        raise OutOfRange("overflow") from None
    if result == 0.0:
        raise OutOfRange("underflow")
    return result


def _sqrt_with_sticky(numerator: int, denominator: int, shift: int) -> int:
    """Return ``floor(sqrt(numerator / denominator) * 2**shift)`` with a sticky low bit.

    The result carries one extra low bit that is set when the true value lies strictly
    between two representable integers, so that rounding it once more to fewer bits
    rounds the exact value correctly.
    """
    quotient, remainder = divmod(numerator << (2 * shift), denominator)
    root = isqrt(quotient)
    inexact = remainder != 0 or root * root != quotient
    return (root << 1) | int(inexact)


def sqrt_scaled(square: int, exponent: int) -> float:
    """Correctly rounded ``sqrt(square) * 2**-exponent`` for an integer ``square >= 0``.

    Raises
    ------
    OutOfRange
        As :func:`round_scaled`.
    """
    if square == 0:
        return 0.0
    # Keep at least 53 + _GUARD_BITS significant bits in the integer root.
    shift = max(0, 53 + _GUARD_BITS - square.bit_length() // 2)
    root = _sqrt_with_sticky(square, 1, shift)
    return round_scaled(root, exponent + shift + 1)


def ratio_sqrt(part: int, whole: int) -> float:
    """Correctly rounded ``sqrt(part / whole)`` for integers ``0 <= part <= whole``, ``whole > 0``.

    Used for a unit-vector component ``|n_i| / |n|`` = ``sqrt(n_i**2 / sum(n_j**2))``.
    """
    if part == 0:
        return 0.0
    # The ratio is in (0, 1]; its square root is at least sqrt(part / whole). Enough bits
    # so that the root has 53 + guard significant bits even for a tiny ratio.
    deficit = max(0, whole.bit_length() - part.bit_length())
    shift = 53 + _GUARD_BITS + deficit // 2 + 1
    root = _sqrt_with_sticky(part, whole, shift)
    # At most 1, so never beyond the doubles; below the smallest one, zero is the nearest
    # double (an absolute error under 2**-1074 on a length-1 vector is no loss).
    return root / (1 << (shift + 1))


def root_bracket(square: int) -> tuple[int, int]:
    """``(root, shift)`` with ``sqrt(square) * 2**shift`` in ``[root, root + 1)`` and ``root`` of
    at least ``53 + _GUARD_BITS`` bits (``square > 0``): one integer square root from which
    :func:`bracketed` rounds ``|n|`` and :func:`unit_vector` each ``n_i / |n|``."""
    shift = max(0, 53 + _GUARD_BITS - square.bit_length() // 2)
    return isqrt(square << (2 * shift)), shift


def bracketed(low: int, denominator: int) -> float | None:
    """The double nearest every value in ``[low, low + 1) / denominator``, when one double is
    (nonzero and finite); else ``None``: the interval holds a rounding boundary (an exact tie,
    or about once in ``2**_GUARD_BITS`` for a ``low`` from :func:`root_bracket`) or is out of
    range, and the caller rounds exactly."""
    try:
        value = low / denominator
        if value and (low + 1) / denominator == value:  # rounding is monotonic
            return value
    except OverflowError:
        pass
    return None


def unit_vector(
    n: tuple[int, int, int], square: int, root: int, shift: int
) -> tuple[float, float, float]:
    """Correctly rounded ``n / |n|`` for integers ``n`` with ``square = n . n > 0``, from
    :func:`root_bracket`'s ``root`` and ``shift``.

    ``|n_i| / |n|`` lies between ``|n_i| * 2**shift`` over ``root + 1`` and over ``root``, two
    quotients that differ beyond a double's precision by ``_GUARD_BITS`` bits. Where both round
    to the same double, that is the correctly rounded value; where they do not (an exact tie,
    or about once in ``2**_GUARD_BITS``), :func:`ratio_sqrt` decides. A component below the
    smallest double is 0, as there.
    """
    x, y, z = n
    return (
        _unit_part(x, square, root, shift),
        _unit_part(y, square, root, shift),
        _unit_part(z, square, root, shift),
    )


def _unit_part(value: int, square: int, root: int, shift: int) -> float:
    """One component of :func:`unit_vector`."""
    if value == 0:
        return 0.0
    top = abs(value) << shift
    high = top / root
    if top / (root + 1) != high:
        high = ratio_sqrt(value * value, square)
    return -high if value < 0 else high


def root_over(square: int, denominator: int) -> float:
    """Correctly rounded ``sqrt(square) / denominator`` (``square >= 0``, ``denominator > 0``).

    The general form of :func:`sqrt_scaled`, for exact rationals whose common denominator is
    not a power of two (a typed ``1/3`` or ``0.1``).

    Raises
    ------
    OutOfRange
        As :func:`round_scaled`.
    """
    if square == 0:
        return 0.0
    if denominator & (denominator - 1) == 0:
        return sqrt_scaled(square, denominator.bit_length() - 1)
    whole = denominator * denominator
    # Enough bits that the root of square / whole keeps 53 + guard significant bits.
    deficit = whole.bit_length() - square.bit_length()
    shift = max(0, 53 + _GUARD_BITS + deficit // 2 + 1)
    root = _sqrt_with_sticky(square, whole, shift)
    return round_scaled(root, shift + 1)


def split_square(value: int, limit: int = SURD_TRIAL_LIMIT) -> tuple[int, int]:
    """Return ``(s, r)`` with ``value == s * s * r`` for an integer ``value >= 1``.

    ``r`` is square-free as far as trial division by 2 and the odd numbers up to ``limit``
    can tell: a square ``p**2`` of a prime ``p > limit`` stays inside ``r`` unless what is left
    after the trial divisions is itself a perfect square (checked once, with ``isqrt``). The
    work is bounded by ``limit / 2`` divisions whatever the size of ``value``. For example,
    ``split_square(72) == (6, 2)`` and ``split_square(286) == (1, 286)``.
    """
    if value < 1:
        raise ValueError("split_square needs an integer of at least 1.")
    outside, inside = 1, 1
    divisor = 2
    while divisor <= limit and divisor * divisor <= value:
        if value % divisor == 0:
            count = 0
            while value % divisor == 0:
                value //= divisor
                count += 1
            outside *= divisor ** (count // 2)
            inside *= divisor ** (count % 2)
        divisor += 1 if divisor == 2 else 2
    root = isqrt(value)
    if root * root == value:
        return outside * root, inside
    return outside, inside * value


def square_root(square: Fraction, limit: int = SURD_TRIAL_LIMIT) -> tuple[Fraction, int]:
    """Return ``(c, r)`` with ``sqrt(square) == c * sqrt(r)``: ``r`` an integer, ``c`` rational.

    ``sqrt(p / q) = sqrt(p * q) / q``, then squares come out of ``p * q`` as
    :func:`split_square` finds them (bounded trial division; a radicand may keep a square of
    a large prime). Zero is ``(0, 1)``. For example ``sqrt(143 / 2) = sqrt(286) / 2``::

        >>> square_root(Fraction(143, 2))
        (Fraction(1, 2), 286)
    """
    if square < 0:
        raise ValueError("square_root needs a number of at least 0.")
    if square == 0:
        return Fraction(0), 1
    outside, inside = split_square(square.numerator * square.denominator, limit)
    return Fraction(outside, square.denominator), inside
