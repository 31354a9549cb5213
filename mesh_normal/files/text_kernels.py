"""Compiled byte loops for the text formats: numbers read straight from a file's bytes.

A kernel here reads what it can certify and declines the rest: its callers then read that part
with their exact Python path. A decimal token (``[+-]digits[.digits][e[+-]digits]``) whose
significant digits make an integer of at most 2**53 and whose power of ten is at most 22 is
read as that integer times or over the power of ten, both exact doubles: one rounding, so the
correctly rounded double, the bits of Python's ``float()`` (Clinger's fast path). Any other
with at most 18 significant digits (17 digits, a large exponent) goes through
:func:`~mesh_normal.files.eisel_lemire.eisel_lemire`, also correctly rounded. What that
declines (a subnormal or infinite result) and a token of more than 18 significant digits that
are not all zeros after the 18th are marked *hard*: their bytes are copied out for
:func:`hard_values`, which reads them with Python's own conversion.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.eisel_lemire import eisel_lemire
from mesh_normal.kernels import claim, kernel, load_word, prange

#: 10**0 to 10**22: every one an exact double.
POWERS = np.array([10.0**k for k in range(23)])
#: The largest integer below which every integer is an exact double.
EXACT = 2**53

#: What :func:`scan_obj` says of a line (the reader's kinds; ``UNKNOWN`` is left to Python).
UNKNOWN, IGNORE, VERTEX, NORMAL, TEXTURE, FACE = -1, 0, 1, 2, 3, 4

#: Why :func:`scan_obj` declined a chunk (0: it did not).
READ, BAD_BYTE, BAD_NUMBER, BAD_CORNER, SHORT_LINE = range(5)


@kernel()
def decimal(data: NDArray[np.uint8], start: int, end: int) -> tuple[int, float]:
    """The decimal token at ``data[start:]`` up to a space, tab or ``end``: ``(stop, value)``,
    ``stop`` the byte after it, or ``(-1, 0.0)`` when it is no decimal, ``(-2 - stop, 0.0)``
    when it is one that needs :func:`hard_values`."""
    i, negative = start, False
    if i < end and (data[i] == 43 or data[i] == 45):  # + -
        negative = data[i] == 45
        i += 1
    mantissa, digits, exponent, seen, exact = 0, 0, 0, False, True
    while i < end and 48 <= data[i] <= 57:
        seen = True
        if mantissa or data[i] != 48:
            if digits < 18:
                mantissa = mantissa * 10 + (int(data[i]) - 48)
                digits += 1
            else:
                exponent += 1
                exact = exact and data[i] == 48
        i += 1
    if i < end and data[i] == 46:  # .
        i += 1
        while i < end and 48 <= data[i] <= 57:
            seen = True
            if mantissa or data[i] != 48:
                if digits < 18:
                    mantissa = mantissa * 10 + (int(data[i]) - 48)
                    digits += 1
                    exponent -= 1
                else:
                    exact = exact and data[i] == 48
            else:
                exponent -= 1
            i += 1
    if not seen:
        return -1, 0.0
    if i < end and (data[i] == 101 or data[i] == 69):  # e E
        i += 1
        minus = False
        if i < end and (data[i] == 43 or data[i] == 45):
            minus = data[i] == 45
            i += 1
        if i >= end or not 48 <= data[i] <= 57:
            return -1, 0.0
        power = 0
        while i < end and 48 <= data[i] <= 57:
            if power < 100000:
                power = power * 10 + (int(data[i]) - 48)
            i += 1
        exponent += -power if minus else power
    if i < end and data[i] != 32 and data[i] != 9:
        return -1, 0.0
    if not mantissa:
        return i, -0.0 if negative else 0.0
    if not exact:
        return -2 - i, 0.0
    if mantissa <= EXACT and -22 <= exponent <= 22:
        value = float(mantissa)
        value = value * POWERS[exponent] if exponent >= 0 else value / POWERS[-exponent]
    else:
        found, value = eisel_lemire(mantissa, exponent)
        if not found:
            return -2 - i, 0.0
    return i, -value if negative else value


@kernel()
def integer(data: NDArray[np.uint8], start: int, end: int) -> tuple[int, int]:
    """The integer at ``data[start:]`` (``[+-]digits``, at most 18 of them): ``(stop, value)``,
    or ``(-1, 0)`` when there is none."""
    i, negative = start, False
    if i < end and (data[i] == 43 or data[i] == 45):
        negative = data[i] == 45
        i += 1
    value, digits = 0, 0
    while i < end and 48 <= data[i] <= 57:
        value = value * 10 + (int(data[i]) - 48)
        digits += 1
        i += 1
    if not digits or digits > 18:
        return -1, 0
    return i, -value if negative else value


@kernel(nogil=True)
def scan_obj(
    data: NDArray[np.uint8],
    kinds: NDArray[np.int8],
    starts: NDArray[np.int64],
    ends: NDArray[np.int64],
    widths: NDArray[np.int64],
    values: NDArray[np.float64],
    hard_at: NDArray[np.int64],
    hard_text: NDArray[np.uint8],
    vertex_ids: NDArray[np.int64],
    normal_ids: NDArray[np.int64],
    counts: NDArray[np.int64],
) -> tuple[int, int, int, int, int, int, bool]:
    """Each line of an OBJ chunk: its kind, where it starts and ends (before ``\\r\\n``); the
    numbers of ``v`` and ``vn`` lines (``widths`` of each line, then every number in
    ``values``, hard ones marked in ``hard_at`` with their text in ``hard_text``); the vertex
    and normal index of every face corner and the corners of each face.

    Returns ``(reason, lines, _, hard, hard bytes, corners, every corner has a
    normal)``; a ``reason`` other than ``READ`` declines the chunk: a byte that Python's
    ``str.splitlines`` or ``str.split`` would treat otherwise, a line that is not certain.
    """
    size = len(data)
    line, position, numbers, hard, hard_bytes, corners, faces = 0, 0, 0, 0, 0, 0, 0
    all_normals = True
    while position < size:
        end = position
        while end < size and data[end] != 10:
            byte = data[end]
            # Line breaks to str.splitlines: \v \f \x1c-\x1e, NEL (0x85), a lone \r.
            if byte == 11 or byte == 12 or 28 <= byte <= 30 or byte == 133:
                return BAD_BYTE, line, 0, 0, 0, 0, False
            if byte == 13 and end + 1 < size and data[end + 1] != 10:
                return BAD_BYTE, line, 0, 0, 0, 0, False
            end += 1
        stop = end + 1
        if end > position and data[end - 1] == 13:
            end -= 1
        starts[line], ends[line] = position, end
        first = data[position] if end > position else 0
        second = data[position + 1] if end > position + 1 else 0
        kind = UNKNOWN
        if end == position or first == 35:  # empty, or a comment
            kind = IGNORE
        elif first == 118 and second == 116:  # vt: only counted
            kind = TEXTURE
        elif first == 118 and (
            second == 32
            or (second == 110 and end > position + 2 and (data[position + 2] in (32, 9)))
        ):
            kind = VERTEX if second == 32 else NORMAL
            i, width = position + 2 if second == 32 else position + 3, 0
            while True:
                while i < end and (data[i] == 32 or data[i] == 9):
                    i += 1
                if i >= end:
                    break
                after, value = decimal(data, i, end)
                if after == -1:
                    return BAD_NUMBER, line, 0, 0, 0, 0, False
                if after < -1:
                    after = -2 - after
                    hard_at[hard] = numbers
                    hard += 1
                    hard_text[hard_bytes : hard_bytes + after - i] = data[i:after]
                    hard_bytes += after - i
                    hard_text[hard_bytes] = 32
                    hard_bytes += 1
                values[numbers] = value
                numbers += 1
                width += 1
                i = after
            if width < 3:
                return SHORT_LINE, line, 0, 0, 0, 0, False
            widths[line] = width
        elif first == 102 and second == 32:  # f
            kind, i, count = FACE, position + 2, 0
            while True:
                while i < end and (data[i] == 32 or data[i] == 9):
                    i += 1
                if i >= end or data[i] == 35:  # a comment may follow the corners
                    break
                i, vertex = integer(data, i, end)
                if i < 0:
                    return BAD_CORNER, line, 0, 0, 0, 0, False
                normal = 0
                has_normal = False
                if i < end and data[i] == 47:  # v/...
                    i += 1
                    if i < end and data[i] != 47 and data[i] != 32 and data[i] != 9:
                        i, _ = integer(data, i, end)  # the texture index, not kept
                        if i < 0:
                            return BAD_CORNER, line, 0, 0, 0, 0, False
                    if i < end and data[i] == 47:  # v/vt/vn, v//vn, v//
                        i += 1
                        if i < end and data[i] != 32 and data[i] != 9 and data[i] != 35:
                            i, normal = integer(data, i, end)
                            if i < 0:
                                return BAD_CORNER, line, 0, 0, 0, 0, False
                            has_normal = True
                if i < end and data[i] != 32 and data[i] != 9 and data[i] != 35:
                    return BAD_CORNER, line, 0, 0, 0, 0, False
                all_normals = all_normals and has_normal
                vertex_ids[corners] = vertex
                normal_ids[corners] = normal
                corners += 1
                count += 1
            counts[faces] = count
            faces += 1
        kinds[line] = kind
        line += 1
        position = stop
    return READ, line, numbers, hard, hard_bytes, corners, all_normals


def hard_values(text: bytes, count: int) -> NDArray[np.float64] | None:
    """The ``count`` space-separated decimal tokens of ``text`` as Python's ``float()`` reads
    them (NumPy's text reader calls the same conversion, ``PyOS_string_to_double``), or
    ``None`` if it does not read exactly ``count``."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            values = np.fromstring(text, dtype=np.float64, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    return values if len(values) == count else None


#: What :meth:`ObjScanner.scan` gives: each line's kind (``UNKNOWN`` left to the caller), the
#: ``v`` coordinates, their colours (when every ``v`` has six numbers), the ``vn`` vectors,
#: each corner's vertex index and normal index (when every corner has one), the corners of
#: each face, and the text of each ``UNKNOWN`` line by its row.
ObjChunk = tuple[
    NDArray[np.int8],
    NDArray[np.float64],
    NDArray[np.float64] | None,
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.int64] | None,
    NDArray[np.intp],
    dict[int, str],
]


class ObjScanner:
    """:func:`scan_obj` over the chunks of one file, with its scratch space (about fifteen
    times a chunk) kept from chunk to chunk: fresh pages cost more than the scan of them."""

    def __init__(self) -> None:
        self.size = -1
        self.lines = -1

    def _scratch(self, size: int, lines: int) -> None:
        if size > self.size:
            self.size, bound = size, size // 2 + 1
            self.values, self.hard_at = np.empty(bound), np.empty(bound, np.int64)
            self.hard_text = np.empty(size + 1, np.uint8)
            self.vertex_ids, self.normal_ids = np.empty(bound, np.int64), np.empty(bound, np.int64)
        if lines > self.lines:
            self.lines = lines
            self.kinds = np.empty(lines, np.int8)
            self.starts, self.ends = np.empty(lines, np.int64), np.empty(lines, np.int64)
            self.widths, self.counts = np.empty(lines, np.int64), np.empty(lines, np.int64)

    def scan(self, data: bytes, start: int, end: int) -> ObjChunk | None:
        """The lines of ``data[start:end]`` (whole lines) as :func:`scan_obj` reads them, or
        ``None`` where it declines. The arrays are the chunk's own."""
        size = end - start
        view = np.frombuffer(data, np.uint8, size, start)
        lines = data.count(b"\n", start, end) + 1
        self._scratch(size, lines)
        widths, values = self.widths, self.values
        widths[:lines] = 0
        reason, lines, _, hard, hard_bytes, corners, all_normals = scan_obj(
            view, self.kinds, self.starts, self.ends, widths, values, self.hard_at,
            self.hard_text, self.vertex_ids, self.normal_ids, self.counts,
        )  # fmt: skip
        if reason != READ:
            return None
        if hard:
            exact = hard_values(self.hard_text[:hard_bytes].tobytes(), hard)
            if exact is None:
                return None
            values[self.hard_at[:hard]] = exact
        kinds = self.kinds[:lines].copy()
        numeric = (kinds == VERTEX) | (kinds == NORMAL)
        firsts = np.cumsum(widths[:lines][numeric]) - widths[:lines][numeric]
        is_vertex = kinds[numeric] == VERTEX
        vertex_firsts, vertex_widths = firsts[is_vertex], widths[:lines][kinds == VERTEX]
        columns = np.arange(3)
        vertices = values[vertex_firsts[:, None] + columns]
        colors = None
        if len(vertex_widths) and (vertex_widths == 6).all():
            colors = values[vertex_firsts[:, None] + 3 + columns]
        normals = values[firsts[~is_vertex][:, None] + columns]
        faces = int(np.count_nonzero(kinds == FACE))
        unknown = np.flatnonzero(kinds == UNKNOWN)
        spans = zip(
            unknown.tolist(),
            self.starts[unknown].tolist(),
            self.ends[unknown].tolist(),
            strict=True,
        )
        texts = {row: data[start + a : start + b].decode("latin-1") for row, a, b in spans}
        return (
            kinds,
            vertices,
            colors,
            normals,
            self.vertex_ids[:corners].copy(),
            self.normal_ids[:corners].copy() if all_normals and corners else None,
            self.counts[:faces].astype(np.intp),
            texts,
        )


#: Records per task of :func:`binary_items`.
ITEMS_BLOCK = 1 << 14


@kernel(parallel=True)
def binary_items(
    data: NDArray[np.uint8],
    offset: int,
    stride: int,
    size: int,
    signed: bool,
    little: bool,
    native: bool,
    items: NDArray[np.int64],
    counter: NDArray[np.int64],
    workers: int,
) -> None:
    """The integers of ``size`` bytes (1, 2 or 4) at ``data[offset + i * stride + j * size]``
    into ``items[i, j]``: a binary PLY's lists of one length, read in one pass from its records
    (NumPy's cast of the records' unaligned, strided view takes three times as long), in blocks
    of ``ITEMS_BLOCK`` records claimed by every core. 4-byte integers in this machine's byte
    order (``native``: a little-endian file here), the usual kind, are each one unaligned load
    (:func:`~mesh_normal.kernels.load_word`)."""
    rows, columns = items.shape
    top = 1 << (8 * size)
    half = top >> 1
    blocks = (rows + ITEMS_BLOCK - 1) // ITEMS_BLOCK
    for _ in prange(workers):
        block = claim(counter)
        while block < blocks:
            last = min(rows, (block + 1) * ITEMS_BLOCK)
            if size == 4 and native:
                for i in range(block * ITEMS_BLOCK, last):
                    at = offset + i * stride
                    for j in range(columns):
                        items[i, j] = load_word(data, at + 4 * j, signed)
            else:
                for i in range(block * ITEMS_BLOCK, last):
                    start = offset + i * stride
                    for j in range(columns):
                        at = start + j * size
                        if size == 4:
                            a, b = int(data[at]), int(data[at + 1])
                            c, d = int(data[at + 2]), int(data[at + 3])
                            value = (
                                a | b << 8 | c << 16 | d << 24
                                if little
                                else d | c << 8 | b << 16 | a << 24
                            )
                        elif size == 2:
                            a, b = int(data[at]), int(data[at + 1])
                            value = a | b << 8 if little else b | a << 8
                        else:
                            value = int(data[at])
                        if signed and value >= half:
                            value -= top
                        items[i, j] = value
            block = claim(counter)
