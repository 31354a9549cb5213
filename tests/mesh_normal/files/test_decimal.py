"""The OBJ scan's decimal conversion (``std::from_chars``) against Python's ``float()``: the
same bits for every decimal of the form it reads, however many digits, whatever exponent."""

from __future__ import annotations

import random
from decimal import Decimal, localcontext

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal._core import read_decimal


def bits(value: float) -> bytes:
    return np.float64(value).tobytes()


def read(token: str) -> float:
    value = read_decimal(token)
    assert value is not None, token
    return value


def agrees(token: str) -> bool:
    """Whether the scan reads ``token`` as ``float()`` does, to the bit."""
    value = read_decimal(token)
    return value is not None and bits(value) == bits(float(token))


@pytest.mark.parametrize("seed", range(4))
def test_random_decimals_read_as_python_float(seed: int) -> None:
    rng = random.Random(seed)
    for _ in range(20000):
        w = rng.randrange(1, 10 ** rng.randint(1, 40))  # up to 40 digits
        q = rng.randint(-30, 30) if rng.random() < 0.5 else rng.randint(-360, 330)
        token = f"{w}e{q}" if rng.random() < 0.5 else f"-{w}E+{q}".replace("+-", "-")
        assert agrees(token), token


def test_ties_round_to_even() -> None:
    rng = random.Random(5)
    for _ in range(5000):
        odd = rng.randrange(2**53, 2**54) | 1  # halfway between two doubles, as an integer
        assert agrees(str(odd))
        k = rng.randrange(2**51, 2**52)  # k + 0.5: halfway at the scale of 2**52
        assert agrees(f"{k}.5")
        assert agrees(f"{odd}e{rng.randint(1, 4)}")  # ties times a power of ten
    for token in ["9007199254740993", "9007199254740995", "1e23", "123456789012345678e-22"]:
        assert agrees(token)


def test_exact_midpoints_and_their_neighbours_in_full() -> None:
    # The exact decimal halfway between two doubles (hundreds of digits), and a hair either
    # side: only a conversion that reads every digit rounds each of these right.
    rng = random.Random(6)
    with localcontext() as context:
        context.prec = 1200
        for _ in range(500):
            low = abs(float(np.frombuffer(rng.getrandbits(64).to_bytes(8, "little"))[0]))
            high = float(np.nextafter(low, np.inf))
            if not np.isfinite(high):
                continue
            middle = (Decimal(low) + Decimal(high)) / 2
            hair = Decimal(f"1e{middle.adjusted() - 1100}")
            for value in (middle, middle + hair, middle - hair):
                assert agrees(format(value, "e")), value


@settings(max_examples=3000, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False), st.integers(1, 25))
def test_every_double_written_with_any_number_of_digits_reads_back(
    value: float, digits: int
) -> None:
    for token in (repr(value), f"{value:.{digits}e}", f"{value:.{digits}f}"):
        assert agrees(token), token
    assert bits(read(repr(value))) == bits(value)


@pytest.mark.parametrize(
    ("token", "value"),
    [
        ("2.2250738585072011e-308", 2.225073858507201e-308),  # subnormal
        ("1e-320", 1e-320),
        ("4.9406564584124654e-324", 5e-324),
        ("2.4703282292062328e-324", 5e-324),  # just above half the smallest: rounds up
        ("2.4703282292062327e-324", 0.0),  # just below: zero
        ("1.8e308", float("inf")),
        ("-1e99999", float("-inf")),
        ("-1e-99999", -0.0),
        ("1234567890123456789", 1234567890123456768.0),
    ],
)
def test_subnormal_infinite_and_long_results_are_read_as_float_reads_them(
    token: str, value: float
) -> None:
    assert agrees(token)
    assert bits(read(token)) == bits(value)
