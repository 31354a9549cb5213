"""The median of an array, as ``np.median`` computes it, in a fraction of its time."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


def median(values: NDArray[np.floating]) -> float:
    """``float(np.median(values))`` of a non-empty 1-D float array, bit for bit (a zero's sign
    aside, where ``0.0`` and ``-0.0`` are both in the array: which of equal values lands in
    the middle is the partition's choice).

    ``np.median`` of an even count partitions at the two middle places at once, which NumPy
    does slowly (about seven times as long as one place). One place is enough:
    after a partition at ``k = n // 2``, the value below the middle is the largest of the
    first ``k``. The two are averaged as ``np.median`` does (``np.mean`` of the pair), and a
    NaN anywhere gives NaN, as there (a partition puts every NaN at ``k`` or after it).
    """
    count = len(values)
    middle = count // 2
    part = np.partition(values, middle)
    if np.isnan(part[middle:]).any():
        return math.nan
    if count % 2:
        return float(part[middle])
    return float(np.mean(np.array([part[:middle].max(), part[middle]])))
