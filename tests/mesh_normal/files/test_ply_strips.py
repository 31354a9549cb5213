"""PLY ``tristrips`` (classic scanned models, trimesh2's writer): strips become triangles."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from mesh_normal.files import MeshFileError, read_mesh
from mesh_normal.files.ply import strip_triangles

# A row of a flat grid: 0 2 4 6 along y = 0, 1 3 5 7 along y = 1; a strip zigzags over it.
ROW = [(x, y, 0.0) for x in range(4) for y in (0, 1)]


def strip_ply(strips: list[list[int]], file_format: str = "ascii", faces: str = "") -> bytes:
    """A PLY of ``ROW`` with a ``tristrips`` element (int counts and indices, as trimesh2
    writes), after one ASCII face with a normal when ``faces`` is given."""
    assert not faces or file_format == "ascii"
    face_header = (
        "element face 1\nproperty list uchar int vertex_indices\nproperty float nx\n"
        "property float ny\nproperty float nz\n"
        if faces
        else ""
    )
    header = (
        f"ply\nformat {file_format} 1.0\nelement vertex {len(ROW)}\nproperty float x\n"
        f"property float y\nproperty float z\n{face_header}element tristrips {len(strips)}\n"
        "property list int int vertex_indices\nend_header\n"
    ).encode()
    if file_format == "ascii":
        body = "".join(f"{x} {y} {z}\n" for x, y, z in ROW) + faces
        body += "".join(f"{len(s)} {' '.join(map(str, s))}\n" for s in strips)
        return header + body.encode()
    data = b"".join(struct.pack("<3f", *point) for point in ROW)
    data += b"".join(struct.pack(f"<i{len(s)}i", len(s), *s) for s in strips)
    return header + data


def z_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    corners = vertices[faces]
    return np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2]


@pytest.mark.parametrize("file_format", ["ascii", "binary_little_endian"])
def test_strip_of_a_grid_row_winds_every_triangle_the_same_way(file_format: str) -> None:
    strip = [0, 1, 2, 3, 4, 5, 6, 7]  # down, up, down, up: 6 triangles over the row
    mesh = read_mesh(strip_ply([strip], file_format), "row.ply")
    np.testing.assert_array_equal(
        mesh.faces, [[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5], [4, 5, 6], [6, 5, 7]]
    )
    normals = z_normals(mesh.vertices, mesh.faces)
    assert np.all(normals == normals[0]) and normals[0] != 0  # consistent: one side up
    assert mesh.source_faces == 1
    assert mesh.notes == ("Read 1 triangle strip as 6 triangles.",)


@pytest.mark.parametrize("file_format", ["ascii", "binary_little_endian"])
def test_minus_one_restarts_a_strip_and_records_are_strips(file_format: str) -> None:
    # The second strip after -1 starts even again: (2, 3, 4), not the odd (3, 2, 4).
    strips = [[0, 1, 2, -1, 2, 3, 4, 5], [5, 6, 7], [6, 7]]
    mesh = read_mesh(strip_ply(strips, file_format), "restart.ply")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [2, 3, 4], [4, 3, 5], [5, 6, 7]])
    assert mesh.source_faces == 3  # strips as the file writes them: one per record
    assert mesh.notes == ("Read 3 triangle strips (with 1 restart) as 4 triangles.",)


def test_degenerate_joining_triangles_are_dropped_and_counted() -> None:
    # Repeating 3 and 4 joins two strips in one (the classic stitch): four triangles with a
    # repeated corner, none of them real.
    strip = [0, 1, 2, 3, 3, 4, 4, 5, 6]
    mesh = read_mesh(strip_ply([strip]), "stitch.ply")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [2, 1, 3], [4, 5, 6]])
    assert mesh.notes == (
        "Read 1 triangle strip as 3 triangles, dropping 4 degenerate triangles that repeat "
        "a corner.",
    )


def test_strips_follow_faces_and_drop_face_normals() -> None:
    mesh = read_mesh(strip_ply([[2, 3, 4]], "ascii", faces="3 0 1 2 0 0 1\n"), "both.ply")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [2, 3, 4]])
    assert mesh.source_faces == 2 and mesh.file_face_normals is None
    faces_only = read_mesh(strip_ply([[2, 3]], "ascii", faces="3 0 1 2 0 0 1\n"), "short.ply")
    np.testing.assert_array_equal(faces_only.faces, [[0, 1, 2]])
    np.testing.assert_array_equal(faces_only.file_face_normals, [[0, 0, 1]])
    assert faces_only.notes == ("Read 1 triangle strip as 0 triangles.",)


@pytest.mark.parametrize(
    ("strips", "message"),
    [
        (
            [[0, 1, 2], [1, 2, 9]],
            "Triangle strip 1 (counting from 0) refers to vertex 9 (counting from 0), but the "
            "file has only 8.",
        ),
        (
            [[0, 1, -2]],
            "Triangle strip 0 (counting from 0) refers to vertex -2; vertex indices cannot be "
            "negative.",
        ),
        ([[0, 1]], "The file holds no faces."),
    ],
)
def test_broken_strips_say_which(strips: list[list[int]], message: str) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(strip_ply(strips), "bad.ply")
    assert str(error.value) == message


def test_strip_triangles_of_nothing() -> None:
    triangles, source, dropped = strip_triangles(
        np.zeros(2, dtype=np.intp), np.zeros(0, dtype=np.int64)
    )
    assert triangles.shape == (0, 3) and source.shape == (0,) and dropped == 0


@pytest.mark.parametrize(("kind", "code"), [("uint", "I"), ("ushort", "H")])
def test_an_unsigned_restart_is_all_ones(kind: str, code: str) -> None:
    strip = [0, 1, 2, -1, 2, 3, 4]
    data = strip_ply([strip], "binary_little_endian")
    header, _, body = data.partition(b"end_header\n")
    header = header.replace(b"list int int", f"list int {kind}".encode())
    points = body[: 12 * len(ROW)]
    stored = [index % 2 ** (8 * struct.calcsize(code)) for index in strip]
    records = struct.pack(f"<i{len(strip)}{code}", len(strip), *stored)
    mesh = read_mesh(header + b"end_header\n" + points + records, "unsigned.ply")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [2, 3, 4]])


def test_face_colours_beside_strips_are_named_not_kept() -> None:
    """Strips carry no colour: colours for only some triangles would be no colours at all."""
    data = strip_ply([[0, 1, 2, 3]], faces="3 0 2 4 0 0 1 255 0 0\n").replace(
        b"property float nz\n",
        b"property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n",
    )
    mesh = read_mesh(data, "row.ply")
    assert len(mesh.faces) == 3 and mesh.face_colors is None
    assert "Face colours were not kept: the triangle strips carry none." in mesh.notes


@pytest.mark.parametrize("faces", ["3 0 1 2 0 0 1\n", "4 0 1 2 3 0 0 1\n"])
def test_a_bad_strip_after_faces_is_named_as_a_strip(faces: str) -> None:
    # Faces' triangles come first, the strips' after them: an index out of range in a strip
    # names the strip, whichever way the faces were read (their own triangles or fans).
    data = strip_ply([[0, 1, 2], [1, 2, 9]], "ascii", faces=faces)
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, "bad.ply")
    assert str(error.value).startswith("Triangle strip 1 (counting from 0) refers to vertex 9")
