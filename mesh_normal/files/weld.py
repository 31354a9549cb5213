"""Exact welding: merge corners with identical coordinates, in order of first appearance.

Two corners merge only when their coordinates are equal as numbers (``-0.0`` equals ``0.0``);
there is no tolerance. The work is one compiled pass in corner order through a hash table of
the points (``_core.weld_table``): a corner whose bits are in the table takes that point's
number, another starts a new point. Where a file makes many points share a slot (a corner has
to look more than ``_MOST_PROBES`` slots on), a compiled sort of the corners by their bits
(``_core.weld_sort``) gives the same numbering instead, whatever the hashes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

import mesh_normal._core as _core


def weld(corners: NDArray[np.floating]) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Merge identical points, numbering them by first appearance.

    Parameters
    ----------
    corners : (k, 3) or (f, c, 3) float32 or float64
        Finite points (NaN would compare unequal to itself), in any layout: a binary STL's
        (f, 3, 3) corners are read where they lie in its 50-byte records, without a copy.

    Returns
    -------
    vertices : (n, 3) float64
        The distinct points, in order of first appearance.
    index : (k,) or (f * c,) intp
        ``vertices[index]`` equals the corners' rows in order (as float64).
    """
    grid = _corner_bytes(corners)
    if grid.shape[0] * grid.shape[1] < 2**31:
        welded = _core.weld_table(grid, _SLOT_MASK, _MOST_PROBES)
        if welded is not None:
            return welded
    return _weld_by_sort(grid)


def _weld_by_sort(grid: NDArray[np.uint8]) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`weld` of the corners' bytes by the sort, where the table gives way."""
    return _core.weld_sort(grid)


def _corner_bytes(corners: NDArray[np.floating]) -> NDArray[np.uint8]:
    """The corners as (f, c, 12 or 24) bytes where they lie: each corner's three coordinates
    must be adjacent, in native float32 or float64 (else a copy makes them so)."""
    grid = corners if corners.ndim == 3 else corners.reshape(-1, 1, 3)
    if grid.dtype not in (np.float32, np.float64) or not grid.dtype.isnative:
        grid = grid.astype(np.float64)
    if grid.strides[2] != grid.itemsize:
        grid = np.ascontiguousarray(grid)
    return grid.view(np.uint8)


#: The hash bits that choose a corner's slot in the table (all 32; a test keeps fewer).
_SLOT_MASK = 0xFFFFFFFF
#: A corner that finds its point (or a free slot) no sooner than this many slots on gives the
#: table up for the sort (a file made so that many points share a slot).
_MOST_PROBES = 64
