"""PCD files built in the tests, and an LZF compressor to make ``binary_compressed`` ones."""

from __future__ import annotations

import struct

import numpy as np
from numpy.typing import NDArray


def pcd_header(
    fields: str,
    sizes: str,
    types: str,
    points: int,
    data: str = "ascii",
    counts: str | None = None,
    height: int = 1,
    viewpoint: str = "0 0 0 1 0 0 0",
) -> bytes:
    count_line = f"COUNT {counts}\n" if counts else ""
    return (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
        f"FIELDS {fields}\nSIZE {sizes}\nTYPE {types}\n{count_line}"
        f"WIDTH {points // height}\nHEIGHT {height}\nVIEWPOINT {viewpoint}\n"
        f"POINTS {points}\nDATA {data}\n"
    ).encode()


def literal_lzf(raw: bytes) -> bytes:
    """LZF data that are only literal runs (valid LZF, no compression)."""
    out = bytearray()
    for start in range(0, len(raw), 32):
        run = raw[start : start + 32]
        out.append(len(run) - 1)
        out += run
    return bytes(out)


def lzf_compress(raw: bytes) -> bytes:
    """A small greedy LZF compressor (matches of 3 bytes and more, found by their first 3)."""
    out, literal = bytearray(), bytearray()
    last: dict[bytes, int] = {}
    i = 0

    def flush() -> None:
        for start in range(0, len(literal), 32):
            run = literal[start : start + 32]
            out.append(len(run) - 1)
            out.extend(run)
        literal.clear()

    while i < len(raw):
        key = raw[i : i + 3]
        candidate = last.get(key)
        last[key] = i
        if candidate is not None and len(key) == 3 and i - candidate <= 8192:
            length = 3
            while (
                length < 264
                and i + length < len(raw)
                and raw[candidate + length] == raw[i + length]
            ):
                length += 1
            flush()
            distance = i - candidate - 1
            code = length - 2
            if code < 7:
                out += bytes([(code << 5) | (distance >> 8), distance & 255])
            else:
                out += bytes([(7 << 5) | (distance >> 8), code - 7, distance & 255])
            i += length
        else:
            literal.append(raw[i])
            i += 1
    flush()
    return bytes(out)


def compressed_body(record: NDArray[np.void]) -> bytes:
    """A ``binary_compressed`` body: the fields one after another, as LZF."""
    raw = b"".join(
        np.ascontiguousarray(record[name]).tobytes() for name in record.dtype.names or ()
    )
    packed = lzf_compress(raw)
    return struct.pack("<II", len(packed), len(raw)) + packed
