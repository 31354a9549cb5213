"""The bounds of a mesh's points: one compiled pass over the rows."""

from __future__ import annotations

import numpy as np

import mesh_normal._core as _core
from mesh_normal.types import FloatArray, IndexArray


def column_bounds(
    points: FloatArray, faces: IndexArray | None = None
) -> tuple[FloatArray, FloatArray]:
    """The smallest and largest of each column of ``points`` (finite, at least one row), or
    of the rows that ``faces`` use: one pass, where NumPy's ``min(axis=0)`` and
    ``max(axis=0)`` take two slow ones (and a used-rows copy); a zero's sign is the first's."""
    low, high = np.empty(3), np.empty(3)
    rows = np.ascontiguousarray(points, dtype=np.float64)
    if faces is None:
        _core.column_bounds(rows, low, high)
    else:
        used = np.zeros(len(points), dtype=bool)
        used[faces.ravel()] = True
        _core.used_column_bounds(rows, used, low, high)
    return low, high
