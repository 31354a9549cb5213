"""Normals of many triangles at once, in float64, with an exact fallback.

How this differs from :func:`mesh_normal.triangle.normal.triangle_normal` (exact, rounded once):

- Each triangle is first scaled by a power of two (exact) so that its largest coordinate
  lies in [0.5, 1); nothing overflows, and the scale is put back at the end.
- u, v and n = u x v are then computed in float64. Each component of n is within
  ``DETERMINANT_ERROR * (|u_j v_k| + |u_k v_j|)`` of the exact value (Shewchuk's bound).
- A row keeps that float result only when |n| is larger than ``BATCH_MARGIN`` times its
  error bound and the sign of each component is certain (it exceeds its own bound, or it is
  exactly zero because each of its products has a zero factor). Every other row (degenerate
  and near-degenerate slivers, components lost in rounding, rows whose scaled coordinates
  would be subnormal, and rows with a value outside the double range) is recomputed by the
  exact single-triangle path.

So the ``degenerate`` mask, the sign of every component (zeros included) and every row
marked ``exact`` are identical to the exact path; other rows may differ from it in the last
bits, and their unit normal points within about 3e-8 radians of the exact direction (in
practice within a few ulps).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mesh_normal.tolerances import BATCH_MARGIN, BATCH_TINY, DETERMINANT_ERROR
from mesh_normal.triangle.normal import TriangleNormal, triangle_normal
from mesh_normal.types import BoolArray, FloatArray


@dataclass(frozen=True, slots=True)
class BatchNormals:
    """Full-length results for ``n`` triangles, in input order.

    Attributes
    ----------
    normal : (n, 3) float64
        The raw normal u x v.
    magnitude : (n,) float64
        |u x v|.
    unit_normal : (n, 3) float64
        (u x v) / |u x v|; zero rows where ``degenerate``.
    area : (n,) float64
        |u x v| / 2.
    degenerate : (n,) bool
        The exact u x v is zero (repeated or collinear points).
    out_of_range : (n,) bool
        Some value of ``normal``, ``magnitude`` or ``area`` is beyond the double range or
        nonzero but below the smallest double; such values hold 0.0 here, and
        :func:`triangle_normal` on that row says which ones and how large they are.
        ``unit_normal`` is always valid.
    exact : (n,) bool
        The row was computed by the exact single-triangle path.
    """

    normal: FloatArray
    magnitude: FloatArray
    unit_normal: FloatArray
    area: FloatArray
    degenerate: BoolArray
    out_of_range: BoolArray
    exact: BoolArray

    def __len__(self) -> int:
        return len(self.magnitude)


def _as_triangles(triangles: ArrayLike) -> FloatArray:
    array = np.asarray(triangles, dtype=np.float64)
    if array.ndim != 3 or array.shape[1:] != (3, 3):
        raise ValueError(f"triangles must have shape (n, 3, 3), not {array.shape}.")
    finite = np.isfinite(array).all(axis=(1, 2))
    if not finite.all():
        row = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"triangles[{row}] has a coordinate that is not a finite number.")
    return array


def triangle_normals(triangles: ArrayLike, *, swap_winding: bool = False) -> BatchNormals:
    """Return the normals of many triangles (see the module docstring for the precision).

    Parameters
    ----------
    triangles : (n, 3, 3) float64
        ``triangles[i]`` holds the corners A, B, C of triangle ``i``, one per row.
    swap_winding : bool
        Use the order A, C, B for every triangle, which negates every normal.

    Returns
    -------
    BatchNormals
        Full-length arrays in input order, with ``degenerate``, ``out_of_range`` and
        ``exact`` masks. Never NaN or infinity.
    """
    given = _as_triangles(triangles)
    corners = given[:, [0, 2, 1]] if swap_winding else given
    count = len(corners)

    # Scale each triangle by a power of two so that its largest |coordinate| is in [0.5, 1).
    largest = np.abs(corners).reshape(count, 9).max(axis=1, initial=0.0)
    _, scale_exp = np.frexp(largest)
    scaled = np.ldexp(corners, -scale_exp[:, None, None])
    lossy = ((corners != 0) & (np.abs(scaled) < BATCH_TINY)).any(axis=(1, 2))

    u = scaled[:, 1] - scaled[:, 0]
    v = scaled[:, 2] - scaled[:, 0]
    u1, v2, u2, v1 = u[:, [1, 2, 0]], v[:, [2, 0, 1]], u[:, [2, 0, 1]], v[:, [1, 2, 0]]
    left = u1 * v2
    right = u2 * v1
    n = (left - right) + 0.0  # + 0.0 turns -0.0 into 0.0, as the exact path has it
    component_bound = DETERMINANT_ERROR * (np.abs(left) + np.abs(right)) + BATCH_TINY
    bound = component_bound.max(axis=1)
    # A component's sign is certain when it exceeds its error bound, or when both of its
    # products have an exactly zero factor (so it is exactly zero).
    exactly_zero = ((u1 == 0) | (v2 == 0)) & ((u2 == 0) | (v1 == 0))
    certain = ((np.abs(n) > component_bound) | exactly_zero).all(axis=1)

    # Normalise with a second power-of-two scale, so that squares neither under- nor overflow.
    largest_n = np.abs(n).max(axis=1)
    _, n_exp = np.frexp(largest_n)
    n_scaled = np.ldexp(n, -n_exp[:, None])
    length = np.sqrt((n_scaled * n_scaled).sum(axis=1))
    keep = (largest_n > BATCH_MARGIN * bound) & certain & ~lossy

    with np.errstate(over="ignore", under="ignore", divide="ignore", invalid="ignore"):
        unit = np.where(keep[:, None], n_scaled / np.where(keep, length, 1.0)[:, None], 0.0)
        normal = np.ldexp(n, 2 * scale_exp[:, None])
        magnitude = np.ldexp(length, n_exp + 2 * scale_exp)
        area = np.ldexp(length, n_exp + 2 * scale_exp - 1)
    values = np.column_stack([normal, magnitude, area])
    tiny = np.finfo(np.float64).tiny
    unrepresentable = ~np.isfinite(values) | ((values != 0) & (np.abs(values) < tiny))
    unrepresentable[:, :3] |= (n != 0) & (normal == 0)
    keep &= ~unrepresentable.any(axis=1)

    result = BatchNormals(
        normal=np.where(keep[:, None], normal, 0.0),
        magnitude=np.where(keep, magnitude, 0.0),
        unit_normal=unit,
        area=np.where(keep, area, 0.0),
        degenerate=np.zeros(count, dtype=bool),
        out_of_range=np.zeros(count, dtype=bool),
        exact=~keep,
    )
    for row in np.flatnonzero(~keep):
        a, b, c = given[row].tolist()
        _store(result, int(row), triangle_normal(a, b, c, swap_winding=swap_winding))
    return result


def _store(result: BatchNormals, row: int, exact: TriangleNormal) -> None:
    """Write one exact result into the batch arrays, 0.0 standing in for ``None``."""
    result.normal[row] = [0.0 if x is None else x for x in exact.normal]
    result.magnitude[row] = exact.magnitude or 0.0
    result.area[row] = exact.area or 0.0
    result.unit_normal[row] = exact.unit_normal or (0.0, 0.0, 0.0)
    result.degenerate[row] = exact.degenerate
    values = (*exact.normal, exact.magnitude, exact.area)
    result.out_of_range[row] = any(value is None for value in values)
