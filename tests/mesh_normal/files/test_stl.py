from __future__ import annotations

import numpy as np
import pytest

from mesh_normal.files import MeshFileError, read_mesh
from tests.meshes import TETRA_FACES, TETRA_VERTICES, ascii_stl, binary_stl

CORNERS = TETRA_VERTICES[TETRA_FACES]
NORMALS = np.array([[0.0, 0, -1], [0, -1, 0], [-1, 0, 0], [1, 1, 1]])


@pytest.mark.parametrize(
    "data", [binary_stl(CORNERS, NORMALS), ascii_stl(CORNERS, NORMALS)], ids=["binary", "ascii"]
)
def test_tetrahedron_is_welded_in_first_appearance_order(data: bytes) -> None:
    mesh = read_mesh(data, "tetra.stl")
    assert mesh.format == "stl"
    # Corners in file order: 0 2 1 | 0 1 3 | ...: first appearances are 0, 2, 1, 3.
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES[[0, 2, 1, 3]])
    np.testing.assert_array_equal(mesh.vertices[mesh.faces], CORNERS)
    np.testing.assert_array_equal(mesh.file_face_normals, NORMALS)
    assert mesh.source_faces == 4
    assert mesh.notes == (
        "Welded 12 STL corners into 4 vertices (identical coordinates merged, "
        "in order of first appearance).",
    )


def test_binary_header_starting_with_solid_is_still_binary() -> None:
    mesh = read_mesh(binary_stl(CORNERS, NORMALS, header=b"solid facet endsolid"))
    assert mesh.format == "stl" and len(mesh.faces) == 4


def test_minus_zero_welds_with_zero() -> None:
    corners = CORNERS.copy()
    corners[1, 0] = [-0.0, -0.0, -0.0]
    assert len(read_mesh(binary_stl(corners), "t.stl").vertices) == 4


def test_all_zero_facet_normals_mean_none() -> None:
    mesh = read_mesh(binary_stl(CORNERS), "t.stl")
    assert mesh.file_face_normals is None
    assert any("zero" in note for note in mesh.notes)


def test_header_count_zero_reads_what_the_file_holds() -> None:
    mesh = read_mesh(binary_stl(CORNERS, NORMALS, count=0), "t.stl")
    assert len(mesh.faces) == 4 and "says 0 triangles" in mesh.notes[0]


def test_trailing_bytes_are_ignored_with_a_note() -> None:
    mesh = read_mesh(binary_stl(CORNERS, NORMALS) + b"\0\0\0", "t.stl")
    assert len(mesh.faces) == 4 and "Ignored 3 bytes" in mesh.notes[0]


def test_header_claiming_more_triangles_than_the_bytes_hold() -> None:
    with pytest.raises(MeshFileError, match="says 1,000 triangles, but the file holds only 4"):
        read_mesh(binary_stl(CORNERS, NORMALS, count=1000), "t.stl")


def test_truncated_binary_stl() -> None:
    data = binary_stl(CORNERS, NORMALS)[:-20]
    with pytest.raises(MeshFileError, match="says 4 triangles, but the file holds only 3") as error:
        read_mesh(data, "t.stl")
    assert error.value.status_code == 400


def test_shorter_than_a_header() -> None:
    with pytest.raises(MeshFileError, match="too short for a binary STL"):
        read_mesh(b"abc", "t.stl")


def test_nan_corner_names_the_triangle() -> None:
    corners = CORNERS.copy()
    corners[2, 1, 0] = np.nan
    with pytest.raises(MeshFileError, match=r"Triangle 3 .* not a finite number"):
        read_mesh(binary_stl(corners), "t.stl")


def test_ascii_stl_cut_short() -> None:
    data = ascii_stl(CORNERS, NORMALS)
    with pytest.raises(MeshFileError, match="4 facets, 4 facet normals and 11 vertices"):
        read_mesh(data[: data.rindex(b"vertex")], "t.stl")


def test_ascii_stl_bad_number() -> None:
    data = ascii_stl(CORNERS, NORMALS).replace(b"vertex 1.0", b"vertex 1.0q", 1)
    with pytest.raises(MeshFileError, match=r"'1\.0q' after 'vertex'"):
        read_mesh(data, "t.stl")


def test_empty_binary_stl() -> None:
    with pytest.raises(MeshFileError, match="no vertices and no faces"):
        read_mesh(binary_stl(np.zeros((0, 3, 3))), "t.stl")
