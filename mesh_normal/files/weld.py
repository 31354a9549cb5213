"""Exact welding: merge corners with identical coordinates, in order of first appearance.

Two corners merge only when their coordinates are equal as numbers (``-0.0`` equals ``0.0``);
there is no tolerance. The work is one sort: each corner's coordinate bits are hashed to 64
bits, the corner's own index is packed into the low bits, and a plain ``np.sort`` of those keys
(several times faster than ``argsort``, ``lexsort`` or ``np.unique`` on rows) brings equal
corners together, each group ordered by index, so a group's first corner is its first
appearance and numbering the groups needs no second sort. The result is then checked bit for
bit; the groups of any two different corners that shared a hash (it happens: the hash keeps
only the bits the packed index leaves, about 1 in 50 meshes of a million points has a pair) are
split again exactly with a ``lexsort`` of just their rows.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

_MULTIPLIERS = (
    np.uint64(0x9E3779B97F4A7C15),
    np.uint64(0xC2B2AE3D27D4EB4F),
    np.uint64(0x165667B19E3779F9),
)


def weld(corners: NDArray[np.floating]) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Merge identical points, numbering them by first appearance.

    Parameters
    ----------
    corners : (k, 3) float32 or float64
        Finite points (NaN would compare unequal to itself).

    Returns
    -------
    vertices : (n, 3) float64
        The distinct points, in order of first appearance.
    index : (k,) intp
        ``vertices[index]`` equals ``corners`` (as float64).
    """
    points = np.ascontiguousarray(corners)
    points = points + points.dtype.type(0)  # -0.0 + 0.0 is +0.0: one bit pattern for zero
    if len(points) == 0:
        return np.empty((0, 3)), np.empty(0, dtype=np.intp)
    words = _words(points)
    is_leader, index = _number(*_hash_groups(words))
    wrong = np.zeros(len(points), dtype=bool)
    for word in words:
        wrong |= word[is_leader][index] != word
    if wrong.any():
        is_leader, index = _split_collisions(words, is_leader, index, wrong)
    return points[is_leader].astype(np.float64), index.astype(np.intp)


def _words(points: NDArray[np.floating]) -> list[NDArray[np.unsignedinteger]]:
    """Each row's bits as one to three unsigned integer columns (x and y of a float32 as one)."""
    if points.itemsize == 4:
        xy = np.ascontiguousarray(points[:, :2]).view(np.uint64).ravel()
        return [xy, points[:, 2].view(np.uint32)]
    return list(points.view(np.uint64).T)


def _hash_groups(
    words: list[NDArray[np.unsignedinteger]],
) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """An order bringing equal rows together, by index within a group, and where each group
    starts. Rows of different groups may be merged when they share a hash (checked later)."""
    count = len(words[0])
    index_bits = max(1, (count - 1).bit_length())
    with np.errstate(over="ignore"):
        key = words[0] * _MULTIPLIERS[0]
        for word, multiplier in zip(words[1:], _MULTIPLIERS[1:], strict=False):
            key ^= key >> np.uint64(29)
            key ^= word * multiplier
        key ^= key >> np.uint64(32)
        key *= _MULTIPLIERS[2]
    low = np.uint64((1 << index_bits) - 1)
    key &= ~low
    key |= np.arange(count, dtype=np.uint64)
    key.sort()
    order = (key & low).astype(_index_type(count))
    key >>= np.uint64(index_bits)
    starts = np.ones(count, dtype=bool)
    np.not_equal(key[1:], key[:-1], out=starts[1:])
    return order, starts


def _number(
    order: NDArray[np.intp], starts: NDArray[np.bool_]
) -> tuple[NDArray[np.bool_], NDArray[np.intp]]:
    """Which rows lead their group, and each row's group numbered by its leader's position."""
    leaders = order[starts]  # the first row of each group (groups are in index order)
    is_leader = np.zeros(len(order), dtype=bool)
    is_leader[leaders] = True
    kind = _index_type(len(order))
    number = np.cumsum(is_leader, dtype=kind) - 1  # a leader's rank = its new vertex id
    index = np.empty(len(order), dtype=kind)
    index[order] = number[leaders][np.cumsum(starts, dtype=kind) - 1]
    return is_leader, index


def _index_type(count: int) -> type[np.signedinteger]:
    """int32 where it is wide enough: half the memory traffic of intp in the scatters."""
    return np.int32 if count < 2**31 else np.intp


def _split_collisions(
    words: list[NDArray[np.unsignedinteger]],
    is_leader: NDArray[np.bool_],
    index: NDArray[np.intp],
    wrong: NDArray[np.bool_],
) -> tuple[NDArray[np.bool_], NDArray[np.intp]]:
    """Regroup exactly the rows of the groups that mixed different points (a shared hash)."""
    rows = np.flatnonzero(np.isin(index, index[wrong]))  # in index order
    ordered = rows[np.lexsort([word[rows] for word in words[::-1]])]  # stable: index order kept
    starts = np.zeros(len(ordered), dtype=bool)
    starts[0] = True
    for word in words:
        in_order = word[ordered]
        starts[1:] |= in_order[1:] != in_order[:-1]
    old_leaders, new_leaders = np.flatnonzero(is_leader), ordered[starts]
    is_leader = is_leader.copy()
    is_leader[new_leaders] = True  # old leaders stay: each is the first row of its points
    number = np.cumsum(is_leader, dtype=np.intp) - 1
    index = number[old_leaders][index]
    index[ordered] = number[new_leaders][np.cumsum(starts, dtype=np.intp) - 1]
    return is_leader, index
