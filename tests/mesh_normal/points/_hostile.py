"""Hostile point-cloud files, built small: what ``tests/data/hostile/points_*`` hold.

``python -m tests.mesh_normal.points._hostile`` writes them there (the LAS and LAZ headers name
laspy's version, so a rewrite may differ in those bytes); the tests read the stored files and
make larger ones the same ways.
"""

from __future__ import annotations

import datetime
import io
import struct
from pathlib import Path

import laspy
import numpy as np

from tests.mesh_normal.points._pcd import literal_lzf, pcd_header

#: An LZF back reference of 264 bytes (the longest) to the byte just before it.
_REPEAT_264 = bytes([7 << 5, 255, 0])


def zeros_lzf(size: int) -> bytes:
    """LZF data unpacking to ``size`` zero bytes: one literal zero, then back references that
    repeat it (3 bytes for each 264), and a literal tail."""
    repeats, tail = divmod(size - 1, 264)
    return bytes([0, 0]) + _REPEAT_264 * repeats + (literal_lzf(bytes(tail)) if tail else b"")


def lzf_bomb_pcd(points: int, size: int = 1, kind: str = "U") -> bytes:
    """A ``binary_compressed`` PCD of ``points`` points at the origin, x y z of ``size`` bytes
    each: its LZF data are 1/88 of what they unpack to."""
    header = pcd_header(
        "x y z", f"{size} {size} {size}", f"{kind} {kind} {kind}", points, "binary_compressed"
    )
    raw = 3 * size * points
    packed = zeros_lzf(raw)
    return header + struct.pack("<II", len(packed), raw) + packed


def lzf_past_end_pcd() -> bytes:
    """One point (12 bytes), whose LZF data go on to write 264 bytes more."""
    header = pcd_header("x y z", "4 4 4", "F F F", 1, "binary_compressed")
    packed = literal_lzf(bytes(12)) + _REPEAT_264
    return header + struct.pack("<II", len(packed), 12) + packed


def coincident_xyz(points: int) -> bytes:
    """``points`` lines of ``0 0 0``."""
    return b"0 0 0\n" * points


def las_points(
    points: int = 4, compress: bool = False, scale: float = 0.01, offset: float = 0.0
) -> bytes:
    """A LAS 1.2 (or LAZ) file of point format 0: ``points`` points along a diagonal."""
    header = _las_header()
    header.scales = np.array([0.01, 0.01, 0.01])
    header.offsets = np.zeros(3)
    data = laspy.LasData(header)
    steps = np.arange(points, dtype=np.float64) % 100
    data.x, data.y, data.z = steps, 2 * steps, np.zeros(points)
    out = io.BytesIO()
    data.write(out, do_compress=compress)
    written = bytearray(out.getvalue())
    struct.pack_into("<d", written, 131, scale)  # the x scale, written after laspy's checks
    struct.pack_into("<d", written, 155, offset)  # the x offset
    return bytes(written)


def _las_header() -> laspy.LasHeader:
    header = laspy.LasHeader(point_format=0, version="1.2")
    header.creation_date = datetime.date(2024, 1, 1)
    return header


def las_count(data: bytes, count: int) -> bytes:
    """``data`` with its header's (legacy) point count set to ``count``."""
    changed = bytearray(data)
    struct.pack_into("<I", changed, 107, count)
    return bytes(changed)


def laz_bomb(points: int) -> bytes:
    """A LAZ file of ``points`` points all at the origin: about 7 bytes a thousand points."""
    data = laspy.LasData(_las_header())
    data.x = data.y = data.z = np.zeros(points)
    out = io.BytesIO()
    data.write(out, do_compress=True)
    return out.getvalue()


#: The stored files: name -> bytes, and the answer each must get (status and words of the
#: sentence, or of a note for a 200).
HOSTILE_POINTS = {
    "points_lzf_bomb.pcd": (lambda: lzf_bomb_pcd(1_500_000), 413, "1,500,000 points"),
    "points_lzf_past_end.pcd": (lzf_past_end_pcd, 400, "more than the 12 bytes"),
    "points_coincident.xyz": (lambda: coincident_xyz(16_000), 200, "sit exactly where"),
    "points_count_short.las": (lambda: las_count(las_points(), 1000), 400, "only 4"),
    "points_count_long.las": (lambda: las_count(las_points(1000), 10), 200, "room for 1,000"),
    "points_scale_zero.las": (lambda: las_points(scale=0.0), 400, "x scale is 0"),
    "points_offset_nan.las": (lambda: las_points(offset=float("nan")), 400, "x offset is nan"),
    "points_laz_bomb.laz": (lambda: laz_bomb(1_500_000), 413, "1,500,000"),
}


def main() -> None:
    folder = Path(__file__).resolve().parents[2] / "data" / "hostile"
    folder.mkdir(exist_ok=True)
    for name, (make, _, _) in HOSTILE_POINTS.items():
        (folder / name).write_bytes(make())


if __name__ == "__main__":
    main()
