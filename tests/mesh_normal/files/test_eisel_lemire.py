"""The compiled decimal conversion against Python's ``float()``: the same bits, or declined."""

from __future__ import annotations

import random

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.files.eisel_lemire import (
    FIVES,
    LARGEST_POWER,
    SMALLEST_POWER,
    bit_length,
    eisel_lemire,
    multiply,
)
from mesh_normal.files.text_kernels import decimal


def bits(value: float) -> bytes:
    return np.float64(value).tobytes()


def agrees(w: int, q: int) -> bool:
    """Whether the conversion of ``w * 10**q`` is Python's, or declined where it may be."""
    found, value = eisel_lemire(w, q)
    exact = float(f"{w}e{q}")
    if not found:
        # Declined only for results that are subnormal or infinite (or off the table).
        tiny = exact == 0.0 or abs(exact) < 2.2250738585072014e-308
        return tiny or exact == float("inf") or not SMALLEST_POWER <= q <= LARGEST_POWER
    return bits(value) == bits(exact)


def test_the_table_is_fast_floats() -> None:
    # fast_float's power_of_five_128 (and Go's detailedPowersOfTen): its first row (5**-342),
    # 5**-189 (truncated), 5**-1 (rounded up) and 5**0.
    rows = FIVES.reshape(-1, 2)
    assert len(rows) == LARGEST_POWER - SMALLEST_POWER + 1
    assert rows[0].tolist() == [0xEEF453D6923BD65A, 0x113FAA2906A13B3F]
    assert rows[-1 - SMALLEST_POWER].tolist() == [0xCCCCCCCCCCCCCCCC, 0xCCCCCCCCCCCCCCCD]
    assert rows[-SMALLEST_POWER].tolist() == [1 << 63, 0]
    assert rows[-189 - SMALLEST_POWER].tolist() == [0x8E938662882AF53E, 0x547EB47B7282EE9C]
    for q in (1, 27, 55, 308):  # truncated powers: the top 128 bits of 5**q
        power = 5**q
        value = int(rows[q - SMALLEST_POWER][0]) << 64 | int(rows[q - SMALLEST_POWER][1])
        assert value == power >> max(power.bit_length() - 128, 0) << max(
            128 - power.bit_length(), 0
        )


@pytest.mark.parametrize("seed", range(4))
def test_128_bit_products(seed: int) -> None:
    rng = random.Random(seed)
    for _ in range(2000):
        a, b = rng.getrandbits(64), rng.getrandbits(64)
        high, low = multiply(np.uint64(a), np.uint64(b))
        assert int(high) << 64 | int(low) == a * b


def test_bit_length() -> None:
    for w in [1, 2, 3, 255, 256, 10**17, 2**53, 2**62, 2**63 - 1]:
        assert bit_length(w) == w.bit_length()


@pytest.mark.parametrize("seed", range(4))
def test_random_decimals_read_as_python_float(seed: int) -> None:
    rng = random.Random(seed)
    for _ in range(20000):
        w = rng.randrange(1, 10 ** rng.randint(1, 18))
        q = rng.randint(-30, 30) if rng.random() < 0.5 else rng.randint(-350, 315)
        assert agrees(w, q), (w, q)


def test_ties_round_to_even() -> None:
    rng = random.Random(5)
    for _ in range(5000):
        odd = rng.randrange(2**53, 2**54) | 1  # halfway between two doubles, as an integer
        assert agrees(odd, 0)
        k = rng.randrange(2**51, 2**52)  # k + 0.5: halfway at the scale of 2**52
        assert agrees(10 * k + 5, -1)
        smaller = rng.randrange(2**53, 2**53 + 2**52) | 1  # times 5**4 still below 2**63
        assert agrees(smaller * 5**4, -4)  # a tie written with four more decimals
        assert agrees(odd, rng.randint(1, 4))  # ties times a power of ten
    for w, q in [(9007199254740993, 0), (9007199254740995, 0), (1, 23), (123456789012345678, -22)]:
        assert agrees(w, q)


@settings(max_examples=3000, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False, min_value=0.0, exclude_min=True))
def test_every_double_written_with_17_digits_reads_back(value: float) -> None:
    digits, _, power = f"{value:.16e}".partition("e")
    w, q = int(digits.replace(".", "")), int(power) - 16
    found, _ = eisel_lemire(w, q)
    assert agrees(w, q)
    assert found or value < 2.2250738585072014e-308


@pytest.mark.parametrize(
    "token",
    [
        "0.12345678901234567",
        "-3.1415926535897931",
        "1.0000000000000002e-300",
        "6.0221407599999999e23",
    ],
)
def test_17_digit_tokens_are_read_in_the_kernel(token: str) -> None:
    # Not marked hard (handed to Python): the kernel's own value, with float()'s bits.
    data = np.frombuffer(token.encode(), np.uint8)
    stop, value = decimal(data, 0, len(data))
    assert stop == len(data)
    assert bits(value) == bits(float(token))


@pytest.mark.parametrize(
    "token", ["2.2250738585072011e-308", "1e-320", "1.8e308", "1234567890123456789"]
)
def test_what_it_declines_is_still_marked_hard(token: str) -> None:
    data = np.frombuffer(token.encode(), np.uint8)
    stop, _ = decimal(data, 0, len(data))
    assert stop == -2 - len(data)
