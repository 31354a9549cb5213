"""Expected directions and the checks every array of normals must pass, for the core's tests."""

from __future__ import annotations

import numpy as np


def unit(*xyz: float) -> np.ndarray:
    """The (3,) unit vector along ``xyz``."""
    vector = np.array(xyz, dtype=np.float64)
    return vector / np.linalg.norm(vector)


def assert_clean(*arrays: np.ndarray) -> None:
    for array in arrays:
        assert array.dtype == np.float64
        assert np.isfinite(array).all()


def assert_unit_or_zero(normals: np.ndarray, zero: np.ndarray) -> None:
    lengths = np.linalg.norm(normals, axis=-1)
    assert np.all(lengths[zero] == 0.0)
    assert np.allclose(lengths[~zero], 1.0, atol=4e-16, rtol=0)
