"""Tests for mesh_normal.mesh.medians: np.median's value, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mesh_normal.mesh.medians import median


@settings(max_examples=300, deadline=None)
@given(
    arrays(
        np.float64,
        st.integers(1, 60),
        elements=st.floats(-1e300, 1e300) | st.sampled_from([0.0, -0.0, 1.0, 2.0]),
    )
)
def test_the_median_is_numpys_bit_for_bit(values: np.ndarray) -> None:
    # The same double; a zero's sign only where both zeros are in the array (which of two
    # equal values a partition puts in the middle is NumPy's choice).
    ours, numpys = median(values), float(np.median(values))
    assert ours == numpys
    if ours == 0.0 and not (np.any(values == 0.0) and np.signbit(values[values == 0.0]).any()):
        assert not math.copysign(1.0, ours) < 0


@pytest.mark.parametrize("count", [1, 2, 3, 871_414, 871_415])
def test_large_and_tiny_counts_match_numpy(count: int) -> None:
    values = np.abs(np.random.default_rng(count).normal(size=count)) * 180 / math.pi
    values[:: max(1, count // 7)] = 0.0  # repeated values
    assert median(values) == float(np.median(values))
    assert median(values.astype(np.float32)) == float(np.median(values.astype(np.float32)))


@pytest.mark.parametrize("where", [0, 1, 5, 9])
def test_a_nan_anywhere_gives_nan_as_numpy_does(where: int) -> None:
    values = np.arange(10.0)
    values[where] = np.nan
    assert math.isnan(median(values)) and math.isnan(float(np.median(values)))
    values[:7] = np.nan  # more NaN than half
    assert math.isnan(median(values))
