"""The correctly rounded double of a decimal, compiled: the Eisel-Lemire algorithm.

A decimal ``w * 10**q`` (``w`` an integer below 2**63, not zero) is the double nearest to it,
ties to even, the bits of Python's ``float()`` of its text, when :func:`eisel_lemire` says
it found one. It multiplies ``w`` (shifted so that its top bit is set) by a 128-bit
approximation of ``5**q`` from :data:`FIVES` and reads the 53 bits of the double from the top
of the 192-bit product: the approximation's error cannot reach those bits, and where the
product lies on a tie it is exact (Lemire, "Number Parsing at a Gigabyte per Second",
Software: Practice and Experience 51(8), 2021; Mushtak and Lemire, "Fast Number Parsing
Without Fallback", 2023; the fast_float library). Subnormal and infinite results, a power of
ten beyond the table and the rare products that the paper's first version left undecided
are declined: the caller reads those with Python's own conversion, as before.

Integer arithmetic here is on ``np.uint64`` only, each constant typed: numba reads a mixed
signed and unsigned operation as a float one.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mesh_normal.kernels import kernel

#: The powers of ten in :data:`FIVES`: beyond them a double is zero or infinite.
SMALLEST_POWER, LARGEST_POWER = -342, 308


def _fives() -> NDArray[np.uint64]:
    """``5**q`` for ``q`` from -342 to 308, as 128-bit numbers with the top bit set, each as
    two words (high, low), flat: truncated for ``q >= 0``; for ``q < 0``, ``2**b // 5**-q + 1``
    truncated, ``b`` as fast_float's table takes it (exact, then rounded up, below 5**28)."""
    rows = []
    for q in range(SMALLEST_POWER, 0):
        power = 5**-q
        z = power.bit_length()  # the least z with 2**z >= power (no power of 5 is one of 2)
        c = 2 ** (z + 127 if q >= -27 else 2 * z + 128) // power + 1
        rows.append(c >> max(c.bit_length() - 128, 0))
    for q in range(LARGEST_POWER + 1):
        power = 5**q
        shift = power.bit_length() - 128
        rows.append(power >> shift if shift > 0 else power << -shift)
    words = [(row >> 64, row & (2**64 - 1)) for row in rows]
    return np.array(words, dtype=np.uint64).reshape(-1)


#: The table of :func:`_fives`, 651 rows of two words.
FIVES = _fives()


@kernel()
def multiply(a: np.uint64, b: np.uint64) -> tuple[np.uint64, np.uint64]:
    """The 128-bit product of two 64-bit words, ``(high, low)``, from 32-bit halves."""
    half, mask = np.uint64(32), np.uint64(0xFFFFFFFF)
    a_low, a_high, b_low, b_high = a & mask, a >> half, b & mask, b >> half
    low_low, low_high = a_low * b_low, a_low * b_high
    high_low, high_high = a_high * b_low, a_high * b_high
    middle = (low_low >> half) + (high_low & mask) + low_high  # at most 2**64 - 1
    high = high_high + (high_low >> half) + (middle >> half)
    return high, (middle << half) | (low_low & mask)


@kernel()
def bit_length(w: int) -> int:
    """The bits of a positive int64, as ``int.bit_length``."""
    length = 0
    for step in (32, 16, 8, 4, 2, 1):
        if w >= 1 << step:
            w >>= step
            length += step
    return length + w


@kernel()
def eisel_lemire(w: int, q: int) -> tuple[bool, float]:
    """``(True, x)``, ``x`` the double nearest to ``w * 10**q`` (ties to even), for
    ``0 < w < 2**63``; ``(False, 0.0)`` where the result would be subnormal or infinite or
    the product cannot decide (see the module docstring)."""
    if q < SMALLEST_POWER or q > LARGEST_POWER:
        return False, 0.0
    zeros = 64 - bit_length(w)
    word = np.uint64(w) << np.uint64(zeros)
    index = 2 * (q - SMALLEST_POWER)
    high, low = multiply(word, FIVES[index])
    precision = np.uint64(0x1FF)  # the bits below the 55 that are kept
    if high & precision == precision:
        # The truncated power may have cost a carry into the kept bits: add the next word.
        more, _ = multiply(word, FIVES[index + 1])
        low += more
        if more > low:
            high += np.uint64(1)
    full = np.uint64(0xFFFFFFFFFFFFFFFF)
    if low == full and (q < -27 or q > 55) and high & precision == precision:
        return False, 0.0  # undecided in the paper's first version: left to Python
    upper = 1 if high >> np.uint64(63) else 0
    shift = np.uint64(upper + 9)
    mantissa = high >> shift
    power = (((152170 + 65536) * q) >> 16) + 63 + upper - zeros + 1023
    if power <= 0:
        return False, 0.0  # subnormal
    one = np.uint64(1)
    tie = low <= one and -4 <= q <= 23 and mantissa & np.uint64(3) == one
    if tie and mantissa << shift == high:
        # Exactly between two doubles (5**q is exact here): round to even, not up.
        mantissa &= ~one
    mantissa += mantissa & one
    mantissa >>= one
    if mantissa >= np.uint64(1 << 53):
        mantissa = np.uint64(1 << 52)
        power += 1
    if power >= 0x7FF:
        return False, 0.0  # infinite
    return True, math.ldexp(float(mantissa), power - 1075)
