"""The memory estimate of a point-cloud job: by the format the bytes show, else the name's."""

from __future__ import annotations

import pytest

from app.points.estimates import JOB_OVERHEAD, MEMORY_PER_BYTE, UNKNOWN_PER_BYTE, estimate, per_byte

PLY = b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nend_header\n"


@pytest.mark.parametrize(
    ("data", "name", "found"),
    [
        (PLY, None, "ply"),
        (PLY, "scan.xyz", "ply"),  # the bytes win over the name
        (b"# .PCD v0.7\nVERSION 0.7\n", None, "pcd"),
        (b"LASF" + bytes(100), "a.las", "las"),
        (b"LASF" + bytes(100), "a.LAZ", "laz"),  # the same signature: told by the name
        (b"0 0 0\n1 0 0\n", "a.txt", "xyz"),
    ],
)
def test_factor_by_format(data: bytes, name: str | None, found: str) -> None:
    assert per_byte(data, name) == MEMORY_PER_BYTE[found]


def test_unknown_and_mesh_files_take_the_largest_factor() -> None:
    assert per_byte(b"0 0 0\n", None) == UNKNOWN_PER_BYTE
    assert per_byte(b"v 0 0 0\nf 1 1 1\n", "a.obj") == UNKNOWN_PER_BYTE
    assert max(MEMORY_PER_BYTE.values()) == UNKNOWN_PER_BYTE


def test_estimate_is_size_times_factor_plus_overhead() -> None:
    data = PLY + bytes(1000)
    assert estimate(data, "a.ply") == int(len(data) * MEMORY_PER_BYTE["ply"]) + JOB_OVERHEAD
