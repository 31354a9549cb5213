from __future__ import annotations

import struct

import numpy as np
import pytest

from mesh_normal.files import MeshFileError, read_mesh
from mesh_normal.points.io.read import read_points
from tests.paths import DATA

CLOUD = """ply
format {encoding} 1.0
element vertex {count}
property double x
property double y
property double z
property float nx
property float ny
property float nz
property uchar red
property uchar green
property uchar blue
property float quality
end_header
"""
ROWS = [(0.1, 2e6, -3.5, 0, 0, 1, 255, 0, 7, 0.5), (4.0, 5.0, 6.0, 0.6, 0.8, 0, 1, 2, 3, 1.0)]


def cloud_ply(encoding: str, count: int = len(ROWS)) -> bytes:
    header = CLOUD.format(encoding=encoding, count=count).encode()
    if encoding == "ascii":
        return header + "".join(" ".join(map(repr, row)) + "\n" for row in ROWS).encode()
    endian = "<" if encoding == "binary_little_endian" else ">"
    return header + b"".join(struct.pack(f"{endian}3d3f3Bf", *row) for row in ROWS)


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_vertices_without_faces(encoding: str) -> None:
    cloud = read_points(cloud_ply(encoding), "cloud.ply")
    np.testing.assert_array_equal(cloud.points, [row[:3] for row in ROWS])
    np.testing.assert_array_equal(cloud.normals, np.float32([row[3:6] for row in ROWS]))
    np.testing.assert_array_equal(cloud.colors, [row[6:9] for row in ROWS])
    assert (cloud.format, cloud.source_kind) == ("ply", "points")
    assert cloud.notes == ("The file's vertex quality values are not used.",)


def test_read_mesh_refuses_it_but_read_points_takes_it() -> None:
    with pytest.raises(MeshFileError, match="no faces"):
        read_mesh(cloud_ply("ascii"), "cloud.ply")


def test_read_mesh_refuses_a_lying_ascii_count_before_allocating() -> None:
    # files/ply.py's read_elements checks the count against the text first (the mesh reader's
    # path too): otherwise 10**12 vertices would ask NumPy for 22 TiB.
    with pytest.raises(MeshFileError, match="1,000,000,000,000 vertex elements, but the file is"):
        read_mesh(cloud_ply("ascii", 10**12), "cloud.ply")


def test_a_mesh_ply_gives_its_vertices() -> None:
    mesh = read_mesh(DATA / "colors_meshlab.ply")
    cloud = read_points(DATA / "colors_meshlab.ply")
    np.testing.assert_array_equal(cloud.points, mesh.vertices)
    assert mesh.vertex_colors is not None
    np.testing.assert_array_equal(cloud.colors, mesh.vertex_colors[:, :3])
    assert cloud.source_kind == "mesh vertices"
    assert "The file's vertex alpha values are not used." in cloud.notes
    assert any("other elements are not used: face (1,610)" in note for note in cloud.notes)


def test_float_and_16_bit_colours_become_8_bit() -> None:
    header = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
    header += "property float z\nproperty {kind} red\nproperty {kind} green\nproperty {kind} blue\n"
    header += "end_header\n"
    floats = read_points((header.format(kind="float") + "0 0 0 1 0.5 0\n1 1 1 0 0 0.2\n").encode())
    np.testing.assert_array_equal(floats.colors, [[255, 128, 0], [0, 0, 51]])
    wide = read_points(
        (header.format(kind="ushort") + "0 0 0 65535 257 0\n1 1 1 0 0 128\n").encode()
    )
    np.testing.assert_array_equal(wide.colors, [[255, 1, 0], [0, 0, 0]])


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            cloud_ply("ascii", 10**12),
            "says 1,000,000,000,000 vertex elements, but the file is too short",
        ),
        (
            cloud_ply("binary_little_endian", 10**9),
            "says 1,000,000,000 vertex elements, but the file holds only 2",
        ),
        (cloud_ply("binary_little_endian")[:-5], "holds only 1: it looks truncated"),
        (
            cloud_ply("ascii").replace(b"-3.5", b"nan"),
            "The coordinates of vertex 0 .counting from 0. include nan",
        ),
        (
            cloud_ply("ascii").replace(b"0.6", b"inf"),
            "The normal of vertex 1 .counting from 0. includes inf",
        ),
        (cloud_ply("ascii").replace(b"4.0", b"four"), "'four' where a number should be"),
        (
            cloud_ply("ascii").replace(b"element vertex 2", b"element point 2"),
            "no vertex element with x, y and z",
        ),
        (cloud_ply("ascii").replace(b"end_header", b"end"), "no 'end_header' line"),
        (cloud_ply("ascii", 0)[: len(CLOUD) + 10], "The file holds no points"),
    ],
)
def test_broken_files_are_refused_with_a_sentence(data: bytes, message: str) -> None:
    with pytest.raises(MeshFileError, match=message) as caught:
        read_points(data, "cloud.ply")
    assert caught.value.status_code == 400
