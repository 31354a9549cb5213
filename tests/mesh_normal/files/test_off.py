from __future__ import annotations

import numpy as np
import pytest

from mesh_normal.files import MeshFileError, read_mesh

SQUARE = b"""# a square and a pyramid tip
OFF
5 3 0
0 0 0
1 0 0
1 1 0
0 1 0 # a comment
0.5 0.5 1
4 0 1 2 3 255 0 0
3 0 4 1
3 1 4 2
"""


def test_polygons_comments_and_colours() -> None:
    mesh = read_mesh(SQUARE)
    assert mesh.format == "off" and mesh.source_faces == 3
    np.testing.assert_array_equal(mesh.vertices[4], [0.5, 0.5, 1])
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3], [0, 4, 1], [1, 4, 2]])


def test_noff_normals_and_counts_on_the_keyword_line() -> None:
    data = b"NOFF 3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n"
    mesh = read_mesh(data, "n.off")
    np.testing.assert_array_equal(mesh.file_vertex_normals, [[0, 0, 1]] * 3)


@pytest.mark.parametrize(
    ("data", "message", "status"),
    [
        (SQUARE.replace(b"5 3 0", b"5 30 0"), "says 5 vertices and 30 faces", 400),
        (SQUARE.replace(b"3 1 4 2", b"3 1 4 7"), "the face on line 11 refers to vertex 7", 400),
        (
            SQUARE.replace(b"1 1 0", b"1 inf 0"),
            "vertex 2 (counting from 0, line 6) include inf",
            400,
        ),
        (SQUARE.replace(b"3 0 4 1", b"3 0 4"), "Line 10: the face says it has 3 corners", 400),
        (b"OFF BINARY\n1 2 3", "Binary OFF files are not supported", 415),
    ],
)
def test_errors(data: bytes, message: str, status: int) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, "s.off")
    assert message in str(error.value).replace("The face", "the face")
    assert error.value.status_code == status
