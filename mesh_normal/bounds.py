"""The bounds of a mesh's points: one compiled pass over the rows.

A module of its own, imported by the analysis and the visibility test: the kernels of a module
that every first call imports (``mesh_normal.kernels``) are looked up, and announced as
compiling, by calls that never run them (see :func:`mesh_normal.kernels.announce_compiling`).
"""

from __future__ import annotations

import numpy as np

from mesh_normal.kernels import kernel
from mesh_normal.types import BoolArray, FloatArray, IndexArray


def column_bounds(
    points: FloatArray, faces: IndexArray | None = None
) -> tuple[FloatArray, FloatArray]:
    """The smallest and largest of each column of ``points`` (finite, at least one row), or
    of the rows that ``faces`` use: one pass, where NumPy's ``min(axis=0)`` and
    ``max(axis=0)`` take two slow ones (and a used-rows copy); a zero's sign is the first's."""
    low, high = np.empty(3), np.empty(3)
    if faces is None:
        _bounds_kernel(points, low, high)
    else:
        used = np.zeros(len(points), dtype=bool)
        used[faces.ravel()] = True
        _used_bounds_kernel(points, used, low, high)
    return low, high


@kernel(python=True)
def _widen(points: FloatArray, row: int, low: FloatArray, high: FloatArray) -> None:
    """Widen the bounds ``low``, ``high`` to hold row ``row`` of ``points``."""
    for axis in range(3):
        value = points[row, axis]
        if value < low[axis]:
            low[axis] = value
        elif value > high[axis]:
            high[axis] = value


@kernel(python=True)
def _bounds_kernel(points: FloatArray, low: FloatArray, high: FloatArray) -> None:
    for axis in range(3):
        low[axis] = high[axis] = points[0, axis]
    for row in range(1, len(points)):
        _widen(points, row, low, high)


@kernel(python=True)
def _used_bounds_kernel(
    points: FloatArray, used: BoolArray, low: FloatArray, high: FloatArray
) -> None:
    first = 0
    while not used[first]:
        first += 1
    for axis in range(3):
        low[axis] = high[axis] = points[first, axis]
    for row in range(first + 1, len(points)):
        if used[row]:
            _widen(points, row, low, high)
