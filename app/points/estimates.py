"""How much memory a point-cloud job may take, estimated from the upload before it starts.

Not measured per format yet: derived from the point-cloud benchmark's peak (README, "Point-
cloud benchmark": 10M points with ``orient="mst"`` took 3.24 GiB, 1.04 GiB of it before the
call, so about 240 bytes a point) and the fewest bytes a point takes in each format (binary
PLY and PCD: 12, three floats; LAS: 20, point format 0; text: about 20; LAZ: about 4), rounded
up. Lower them here, in this one table, when they are measured.
"""

from __future__ import annotations

from mesh_normal.points.read import POINT_SUFFIXES, sniff_points

#: Bytes of memory per byte of the file, by the format read from the bytes (else the name).
MEMORY_PER_BYTE: dict[str, float] = {
    "ply": 20,
    "pcd": 20,
    "las": 12,
    "laz": 60,
    "xyz": 12,
}
#: For a mesh file read as its vertices, or a format not known before reading: the largest.
UNKNOWN_PER_BYTE = max(MEMORY_PER_BYTE.values())

#: Bytes every job takes whatever its size: the k-d tree queries' neighbour lists (a chunk of
#: 2**17 points, 62 MB at k = 30), the report, the pickles.
JOB_OVERHEAD = 128 * 2**20


def estimate(data: bytes, filename: str | None) -> int:
    """The bytes of memory this upload's job may take at its peak."""
    return int(len(data) * per_byte(data, filename)) + JOB_OVERHEAD


def per_byte(data: bytes, filename: str | None) -> float:
    """The factor of the format the bytes show, else the name's (LAZ is told by its name)."""
    suffix = "." + filename.rsplit(".", 1)[-1].lower() if filename and "." in filename else ""
    found = "laz" if suffix == ".laz" else sniff_points(data) or POINT_SUFFIXES.get(suffix)
    return MEMORY_PER_BYTE.get(found or "", UNKNOWN_PER_BYTE)
