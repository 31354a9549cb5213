"""Exact welding: merge corners with identical coordinates, in order of first appearance.

Two corners merge only when their coordinates are equal as numbers (``-0.0`` equals ``0.0``);
there is no tolerance. The work is one compiled pass in corner order through a hash table of
the points (:func:`_table_weld`): a corner whose bits are in the table takes that point's
number, another starts a new point. Where a file makes many points share a slot, the sort of
before takes over: a compiled pass hashes each corner's coordinate bits and packs the corner's
own index into the low bits of the key, a plain ``np.sort`` of those keys brings equal corners
together, each group ordered by index, and a second compiled pass walks the groups: each corner
is compared bit for bit with the first corner of each distinct point of its group, so a group's
first corner of a point is that point's first appearance, and one pass in index order numbers
the points. A group of more than ``_MOST_DISTINCT`` different points (only a file made to
collide) is welded by the exact NumPy way of before instead.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mesh_normal.kernels import (
    AHEAD,
    PARALLEL_KERNELS,
    announce_compiling,
    claim,
    kernel,
    prange,
    prefetch,
    workers,
)
from mesh_normal.types import BoolArray, IndexArray


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
    grid = corners if corners.ndim == 3 else corners.reshape(-1, 1, 3)
    count = grid.shape[0] * grid.shape[1]
    if count == 0:
        return np.empty((0, 3)), np.empty(0, dtype=np.intp)
    announce_compiling()
    if count < 2**31:
        # The coordinates' bits, as 4 or 8 byte integers (one kernel for each); the table
        # takes -0.0 as 0.0 itself, without a copy of the corners.
        words: IndexArray = grid.view(np.int32 if grid.itemsize == 4 else np.int64)
        is_leader = np.zeros(count, dtype=bool)
        index = np.empty(count, dtype=np.intp)
        digests = np.empty(count, dtype=np.uint32)
        with PARALLEL_KERNELS:
            _row_hashes(words, digests, *workers())
        # A quarter as many slots as rows (a point is in about 6 corners), made here: NumPy
        # asks for huge pages for a large array, and with 4 KB pages the probes wait on the
        # page tables (the table's pass takes almost twice as long).
        size = 16
        while size < count // 4:
            size *= 2
        table = np.full((size, 4), -1, dtype=words.dtype)
        state = np.zeros(2, dtype=np.int64)  # the next row, the points found
        while True:
            done = _table_weld(
                words, digests, table, _SLOT_MASK, _MOST_PROBES, is_leader, index, state
            )
            if done != 1:
                break
            larger = np.full((2 * len(table), 4), -1, dtype=table.dtype)
            if not _regrown(table, larger, words.itemsize == 8, _SLOT_MASK, _MOST_PROBES):
                done = -1
                break
            table = larger
            del larger
        found = int(state[1]) if done == 0 else -1
        del digests, table
        if found >= 0:
            vertices = np.empty((found, 3))
            _leaders(grid, is_leader, vertices)
            return vertices, index
        del is_leader, index
    return weld_by_sort(np.ascontiguousarray(grid.reshape(count, 3)))


def weld_by_sort(points: NDArray[np.floating]) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`weld` of C-contiguous ``points`` (at least one row) by the sort of hashes, where
    the table gives way (and in ``compile_kernels``, whose meshes never need it)."""
    count = len(points)
    points = points + points.dtype.type(0)  # -0.0 + 0.0 is +0.0: one bit pattern for zero
    bits: IndexArray = points.view(np.int32 if points.itemsize == 4 else np.int64)
    index_bits = max(1, (count - 1).bit_length())
    keys = np.empty(count, dtype=np.int64)
    _hash_keys(bits, index_bits, _HASH_MASK, keys)
    keys.sort()
    is_leader = np.zeros(count, dtype=bool)
    index = np.empty(count, dtype=np.intp)
    if not _group(keys, index_bits, bits, _MOST_DISTINCT, is_leader, index):
        del is_leader, index
        return _weld_sorted(points, keys, index_bits)
    return points[is_leader].astype(np.float64), index


#: The hash bits kept in a key (all of them; a test keeps fewer to make groups collide).
_HASH_MASK = (1 << 62) - 1
#: The most different points in one group of equal hashes that the compiled walk separates.
_MOST_DISTINCT = 8
_M32 = 0xFFFFFFFF
_MURMUR = 0x5BD1E995  # below 2**31: a product with a 32-bit value fits an int64


@kernel(python=True)
def _mix(state: int, piece: int) -> int:
    """MurmurHash2's step of a 32-bit ``piece`` into a 32-bit ``state`` (no overflow)."""
    piece = (piece * _MURMUR) & _M32
    piece ^= piece >> 24
    piece = (piece * _MURMUR) & _M32
    return ((state * _MURMUR) & _M32) ^ piece


@kernel(python=True)
def _final(state: int) -> int:
    state ^= state >> 13
    state = (state * _MURMUR) & _M32
    return state ^ (state >> 15)


@kernel(python=True)
def _hash_keys(bits: IndexArray, index_bits: int, mask: int, keys: IndexArray) -> None:
    """Each row's key: a 62-bit hash of its integers (two 31-bit halves), its low
    ``index_bits`` bits replaced by the row's number."""
    low = (1 << index_bits) - 1
    columns = bits.shape[1]
    for row in range(len(bits)):
        first, second = 0x9747B28C, 0x3C6EF372
        for column in range(columns):
            word = int(bits[row, column])  # a Python int in the Python source: no overflow
            first = _mix(first, word & _M32)
            second = _mix(second, (word >> 16) & _M32)  # a 4-byte word's high half, shifted in
            if bits.itemsize == 8:
                first = _mix(first, (word >> 32) & _M32)
                second = _mix(second, (word >> 48) & _M32)
        digest = ((_final(first) >> 1) << 31) | (_final(second) >> 1)
        keys[row] = ((digest & mask) & ~low) | row


#: The hash bits that choose a row's slot in :func:`_table_weld` (all 32; a test keeps fewer).
_SLOT_MASK = _M32
#: A row that finds its point (or a free slot) no sooner than this many slots on gives the
#: table up for the sort (a file made so that many points share a slot).
_MOST_PROBES = 64


#: The bits of -0.0 as an int32 and as an int64: the lowest of each.
_LOWEST_32, _LOWEST_64 = -(2**31), -(2**63)


@kernel(python=True)
def _row_words(bits: IndexArray, face: int, corner: int) -> tuple[int, int, int]:
    """A corner's three integers, with -0.0's bits (the lowest integer) as 0.0's."""
    lowest = _LOWEST_32 if bits.itemsize == 4 else _LOWEST_64
    x, y, z = int(bits[face, corner, 0]), int(bits[face, corner, 1]), int(bits[face, corner, 2])
    return (0 if x == lowest else x), (0 if y == lowest else y), (0 if z == lowest else z)


@kernel(python=True)
def _words_hash(x: int, y: int, z: int, wide: bool) -> int:
    """A 32-bit hash of three integers (MurmurHash2's steps, a 32-bit piece at a time; the
    high halves too where ``wide``)."""
    state = 0x9747B28C
    for word in (x, y, z):
        state = _mix(state, word & _M32)
        if wide:
            state = _mix(state, (word >> 32) & _M32)
    return _final(state)


@kernel(parallel=True, python=True)
def _row_hashes(
    bits: IndexArray, digests: NDArray[np.uint32], counter: IndexArray, workers: int
) -> None:
    """Each row's 32-bit hash (:func:`_words_hash` of :func:`_row_words`), in blocks of
    ``HASH_BLOCK`` faces claimed by every core."""
    faces, per = bits.shape[0], bits.shape[1]
    wide = bits.itemsize == 8
    blocks = (faces + HASH_BLOCK - 1) // HASH_BLOCK
    for _ in prange(workers):
        block = claim(counter)
        while block < blocks:
            for face in range(block * HASH_BLOCK, min((block + 1) * HASH_BLOCK, faces)):
                for corner in range(per):
                    x, y, z = _row_words(bits, face, corner)
                    digests[face * per + corner] = _words_hash(x, y, z, wide)
            block = claim(counter)


#: Faces per task of :func:`_row_hashes`.
HASH_BLOCK = 1 << 13


@kernel(python=True)
def _table_weld(
    bits: IndexArray,
    digests: NDArray[np.uint32],
    table: IndexArray,
    mask: int,
    most: int,
    is_leader: BoolArray,
    index: IndexArray,
    state: IndexArray,
) -> int:
    """Number each row's point by first appearance, through a hash table of the points (the
    rows of ``bits`` (f, c, 3) in order, ``f * c`` of them, with their hashes ``digests``):
    mark each point's first row in ``is_leader`` and give every row its point's number in
    ``index``. -0.0 counts as 0.0 (see :func:`_row_words`).

    One pass in row order from row ``state[0]``, ``state[1]`` points found before it: a row
    whose bits are in the table takes that point's number, another starts a new point. Each
    slot of ``table`` (a power of two of them) holds a point's bits and its number (-1 when
    free). Returns 0 when every row is numbered (``state[1]`` the number of points); 1 when
    the table is half full (``state`` says where to go on, once the caller has placed the points
    in a table twice the size: :func:`_regrown`); -1 (and the arrays half written) when a row
    had to look more than ``most`` slots on. The slot of the row ``AHEAD`` rows on is asked for
    in advance: the table is larger than the cache on a large mesh.

    The table is never replaced inside this loop: with the doubling written in it (the table a
    variable the loop assigns), the pass takes 2.5 times as long.
    """
    faces, per = bits.shape[0], bits.shape[1]
    count = faces * per
    size = len(table)
    points = state[1]
    start = state[0]
    face, corner = start // per, start % per - 1  # the row's, counted on: no division a row
    for row in range(start, count):
        corner += 1
        if corner == per:
            face, corner = face + 1, 0
        if row + AHEAD < count:
            prefetch(table, int(digests[row + AHEAD]) & mask & (size - 1))
        x, y, z = _row_words(bits, face, corner)
        slot = int(digests[row]) & mask & (size - 1)
        probes = 0
        while True:
            number = table[slot, 3]
            if number < 0:
                table[slot, 0], table[slot, 1], table[slot, 2] = x, y, z
                table[slot, 3] = points
                is_leader[row] = True
                index[row] = points
                points += 1
                break
            if table[slot, 0] == x and table[slot, 1] == y and table[slot, 2] == z:
                index[row] = number
                break
            probes += 1
            if probes > most:
                return -1
            slot = (slot + 1) & (size - 1)
        if 2 * points > size:  # half full: the caller doubles the table, then on from here
            state[0], state[1] = row + 1, points
            return 1
    state[0], state[1] = count, points
    return 0


@kernel(python=True)
def _regrown(table: IndexArray, larger: IndexArray, wide: bool, mask: int, most: int) -> bool:
    """Place every point of ``table`` in ``larger`` (all -1, twice the slots), in slot order;
    False if one had to look more than ``most`` slots on."""
    size = len(larger)
    for old in range(len(table)):
        if table[old, 3] < 0:
            continue
        a, b, c = int(table[old, 0]), int(table[old, 1]), int(table[old, 2])
        slot = _words_hash(a, b, c, wide) & mask & (size - 1)
        probes = 0
        while larger[slot, 3] >= 0:
            probes += 1
            if probes > most:
                return False
            slot = (slot + 1) & (size - 1)
        for column in range(4):
            larger[slot, column] = table[old, column]
    return True


@kernel(python=True)
def _leaders(
    points: NDArray[np.floating], is_leader: BoolArray, vertices: NDArray[np.float64]
) -> None:
    """The leading rows of ``points`` (f, c, 3) in turn, as float64 and with -0.0 as 0.0 (plus
    0.0), into ``vertices`` (one pass: NumPy's mask and conversion take about 1.4 s at the
    Lucy size)."""
    point = 0
    row = 0
    for face in range(points.shape[0]):
        for corner in range(points.shape[1]):
            if is_leader[row]:
                for axis in range(3):
                    vertices[point, axis] = float(points[face, corner, axis]) + 0.0
                point += 1
            row += 1


@kernel(python=True)
def _group(
    keys: IndexArray,
    index_bits: int,
    bits: IndexArray,
    most: int,
    is_leader: BoolArray,
    index: IndexArray,
) -> bool:
    """Walk the sorted keys' groups of equal hashes of the rows (three integers each): mark
    each point's first row and number every row's point by first appearance in ``index``;
    False (and nothing numbered) if a group holds more than ``most`` different points.

    The rows' bits are gathered in key order first (a copy of ``bits``): compared where they
    lie, the walk is three times slower, waiting on memory at every row."""
    low = (1 << index_bits) - 1
    count = len(bits)
    ordered = np.empty_like(bits)
    for position in range(count):
        row = keys[position] & low
        ordered[position, 0], ordered[position, 1] = bits[row, 0], bits[row, 1]
        ordered[position, 2] = bits[row, 2]
    heads = np.empty(most, dtype=np.int64)  # the first position of each point of the group
    start = 0
    while start < count:
        end = start + 1
        while end < count and keys[end] >> index_bits == keys[start] >> index_bits:
            end += 1
        found = 0
        for position in range(start, end):  # in row order: a point's first row comes first
            x, y, z = ordered[position, 0], ordered[position, 1], ordered[position, 2]
            head = -1
            for h in range(found):
                first = heads[h]
                if x == ordered[first, 0] and y == ordered[first, 1] and z == ordered[first, 2]:
                    head = first
                    break
            row = keys[position] & low
            if head < 0:
                if found == most:
                    return False
                heads[found] = position
                found += 1
                is_leader[row] = True
                head = position
            index[row] = keys[head] & low
        start = end
    # Number the points in row order: a row's first row is earlier, so numbered already.
    number = 0
    for row in range(count):
        if is_leader[row]:
            index[row] = number
            number += 1
        else:
            index[row] = index[index[row]]
    return True


def _weld_sorted(
    points: NDArray[np.floating], keys: NDArray[np.int64], index_bits: int
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`weld` of ``points`` (no -0.0) the NumPy way, from the sorted keys: the groups of
    equal hashes numbered, checked after, and those that mixed points split exactly with a
    ``lexsort``."""
    words = _words(points)
    is_leader, index = _number(*_hash_groups(keys, index_bits))
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
    keys: NDArray[np.int64], index_bits: int
) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """The order that the sorted keys (:func:`_hash_keys`) bring the rows in, and where each
    group of equal hashes starts; rows of different points may share one (checked later)."""
    count = len(keys)
    order = (keys & ((1 << index_bits) - 1)).astype(_index_type(count))
    hashes = keys >> index_bits
    starts = np.ones(count, dtype=bool)
    np.not_equal(hashes[1:], hashes[:-1], out=starts[1:])
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
