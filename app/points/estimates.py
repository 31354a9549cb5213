"""How much memory a point-cloud job may take, estimated from the upload before it starts.

For a sphere in float32 binary PLY (k = 30, ``orient="mst"``, the whole report), the peak
above the file's bytes is about 210 MB whatever the size (the k-d tree queries' neighbour
lists, a chunk of 2**17 points at a time, and the kernels' first call) plus 213 bytes a point.
The factors below are that per point over the fewest bytes a point takes in each format
(binary PLY and PCD: 12, three floats; LAS: 20, point format 0; text: about 20; LAZ: about 4),
plus the file itself, rounded up: wider records take less a byte (binary PLY of doubles, 24
bytes a point, about 9 besides the fixed part; XYZ text of 59 bytes a point about 4).
Lower them here, in this one table, when they are measured per format. The readers charge
points they unpack from compressed data (a PCD's LZF, LAZ) at the same 213 bytes a point
(``mesh_normal.points.io.cloud.POINT_JOB_BYTES``) to the upload's expansion budget, so a file
that packs more points than its size allows is refused before this estimate could be wrong.
"""

from __future__ import annotations

from mesh_normal.points.io.formats import POINT_SUFFIXES

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

#: Bytes every job takes whatever its size (about 210 MB, see above), rounded up.
JOB_OVERHEAD = 224 * 2**20


def estimate(data: bytes, filename: str | None) -> int:
    """The bytes of memory this upload's job may take at its peak."""
    return int(len(data) * per_byte(data, filename)) + JOB_OVERHEAD


def per_byte(data: bytes, filename: str | None) -> float:
    """The factor of the format the bytes show, else the name's (LAZ is told by its name)."""
    from mesh_normal.points.io.read import sniff_points  # here: the readers load after start-up

    suffix = "." + filename.rsplit(".", 1)[-1].lower() if filename and "." in filename else ""
    found = "laz" if suffix == ".laz" else sniff_points(data) or POINT_SUFFIXES.get(suffix)
    return MEMORY_PER_BYTE.get(found or "", UNKNOWN_PER_BYTE)
