from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.files import MeshFileError, read_mesh
from mesh_normal.mesh.topology import by_position, same_points
from tests.meshes import (
    CUBE_FACES,
    CUBE_VERTICES,
    TETRA_FACES,
    TETRA_VERTICES,
    ascii_solids,
    ascii_stl,
    binary_stl,
)
from tests.paths import DATA

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


# --- ASCII solids: one object each ---------------------------------------------------------

#: A unit cube's twelve triangles as (12, 3, 3) corners, wound outward.
CUBE_CORNERS = CUBE_VERTICES[CUBE_FACES]


def test_each_solid_is_an_object_and_the_welding_is_across_the_file() -> None:
    # The tetrahedron's four corners are corners of the cube: welded with them.
    mesh = read_mesh(ascii_solids(("bodyA", CUBE_CORNERS), ("bodyB", CORNERS)), "two.stl")
    assert mesh.group_names == ("bodyA", "bodyB")
    assert mesh.face_groups is not None
    np.testing.assert_array_equal(mesh.face_groups, [0] * 12 + [1] * 4)
    np.testing.assert_array_equal(
        mesh.vertices[mesh.faces], np.concatenate([CUBE_CORNERS, CORNERS])
    )
    assert len(mesh.vertices) == 8
    assert mesh.notes[0] == "Joined 2 ASCII STL solids into one mesh, each an object."


def test_one_solid_is_one_object_as_one_obj_object_is() -> None:
    mesh = read_mesh(ascii_stl(CORNERS, NORMALS, "tetra"), "t.stl")
    assert mesh.group_names == ("tetra",)
    assert mesh.face_groups is not None and not mesh.face_groups.any()
    assert not any("Joined" in note for note in mesh.notes)


def test_binary_stl_has_no_objects() -> None:
    mesh = read_mesh(binary_stl(CORNERS, NORMALS, header=b"solid bodyA"), "t.stl")
    assert mesh.face_groups is None and mesh.group_names is None


def test_solids_without_a_name_are_numbered_and_taken_names_are_kept_apart() -> None:
    data = ascii_solids(
        ("", CORNERS), ("part", CORNERS), ("part", CORNERS), ("solid 1", CORNERS), ("part", CORNERS)
    )
    names = read_mesh(data, "t.stl").group_names
    assert names == ("solid 1", "part", "part (2)", "solid 1 (2)", "part (3)")


def test_a_solid_without_facets_is_no_object_and_a_note_says_so() -> None:
    data = ascii_solids(("lid", CORNERS), ("empty", CORNERS[:0]), ("", CORNERS[:0]), ("", CORNERS))
    mesh = read_mesh(data, "t.stl")
    # The fourth solid is named by its place in the file, though the two before it are gone.
    assert mesh.group_names == ("lid", "solid 4")
    np.testing.assert_array_equal(mesh.face_groups, [0] * 4 + [1] * 4)
    assert "Solids 2 ('empty') and 3 of 4 hold no facets, so they are no objects." in mesh.notes


def test_one_empty_solid_is_named_in_the_note() -> None:
    mesh = read_mesh(ascii_solids(("a", CORNERS), ("b", CORNERS[:0])), "t.stl")
    assert mesh.group_names == ("a",)
    assert "Solid 2 ('b') of 2 holds no facets, so it is no object." in mesh.notes


def test_only_empty_solids_are_no_mesh() -> None:
    with pytest.raises(MeshFileError, match="no vertices and no faces"):
        read_mesh(ascii_solids(("a", CORNERS[:0]), ("b", CORNERS[:0])), "t.stl")


def test_concatenated_files_are_the_solids_of_one_mesh() -> None:
    data = ascii_stl(CORNERS, NORMALS, "a") + b"\n" + ascii_stl(CORNERS + 5, NORMALS, "b")
    mesh = read_mesh(data, "t.stl")
    assert mesh.group_names == ("a", "b") and len(mesh.vertices) == 8


def test_crlf_blank_lines_and_text_after_endsolid() -> None:
    data = ascii_solids(("Part 1", CUBE_CORNERS), ("Part 2", CORNERS + 3))
    data = data.replace(b"endsolid Part 1", b"endsolid Part 1 exported 2024-01-01\n\n\n")
    data = (data + b"\n\n% trailing words without keywords\n").replace(b"\n", b"\r\n")
    mesh = read_mesh(data, "t.stl")
    assert mesh.group_names == ("Part 1", "Part 2")  # no "\r" left in the names
    assert len(mesh.faces) == 16 and len(mesh.vertices) == 12


def test_old_mac_line_ends() -> None:
    data = ascii_solids(("a", CUBE_CORNERS), ("b", CORNERS + 3)).replace(b"\n", b"\r")
    mesh = read_mesh(data, "t.stl")
    assert mesh.group_names == ("a", "b") and len(mesh.faces) == 16


def test_keywords_in_any_case() -> None:
    data = ascii_solids(("Body", CUBE_CORNERS), ("Other", CORNERS + 3))
    for word in (b"solid", b"facet normal", b"outer loop", b"vertex", b"endloop", b"endfacet"):
        data = data.replace(word, word.upper())
    data = data.replace(b"SOLID Other", b"Solid Other")
    mesh = read_mesh(data, "t.stl")
    assert mesh.group_names == ("Body", "Other")  # the names keep their case
    np.testing.assert_array_equal(
        mesh.vertices[mesh.faces], np.concatenate([CUBE_CORNERS, CORNERS + 3])
    )


def test_names_with_spaces_and_unicode() -> None:
    data = ascii_solids(("Würfel (Körper 1)", CUBE_CORNERS), ("  padded  ", CORNERS + 3))
    latin = ascii_solids(("a", CORNERS)).replace(b"solid a", "solid café".encode("latin-1"), 1)
    assert read_mesh(data, "t.stl").group_names == ("Würfel (Körper 1)", "padded")
    assert read_mesh(latin, "t.stl").group_names == ("café",)


def test_a_byte_order_mark_before_the_text() -> None:
    mesh = read_mesh(b"\xef\xbb\xbf" + ascii_solids(("a", CORNERS), ("b", CORNERS + 3)), "t.stl")
    assert mesh.group_names == ("a", "b") and len(mesh.faces) == 8


def test_solid_inside_a_name_or_a_longer_word_starts_no_solid() -> None:
    data = ascii_solids(("solid", CORNERS), ("b", CORNERS + 3))
    data = data.replace(b"solid b", b"solidworks b\nsolid b", 1)  # "solidworks" is no keyword
    assert read_mesh(data, "t.stl").group_names == ("solid", "b")


def test_a_solid_short_of_vertices_is_named() -> None:
    data = ascii_solids(("a", CORNERS), ("b", CORNERS + 3))
    first = data.index(b"      vertex")  # the first vertex line of solid a, taken out
    broken = data[:first] + data[data.index(b"\n", first) + 1 :]
    with pytest.raises(
        MeshFileError,
        match=r"^Solid 1 \('a'\) has 4 facets, 4 facet normals and 11 vertices; .*vertices\.$",
    ):
        read_mesh(broken, "t.stl")
    with pytest.raises(MeshFileError, match=r"^Solid 2 \('b'\) has .* \(is the file cut short\?\)"):
        read_mesh(data[: data.rindex(b"vertex")], "t.stl")


@given(st.lists(st.integers(0, 12), max_size=4))
def test_any_split_into_solids_gives_the_same_mesh(cuts: list[int]) -> None:
    """However the cube's facets are split into solids, the mesh is the one-solid mesh and
    each facet is in the group of its solid (empty solids making none)."""
    bounds = [0, *sorted(cuts), 12]
    blocks = [(f"s{i}", CUBE_CORNERS[a:b]) for i, (a, b) in enumerate(itertools.pairwise(bounds))]
    whole = read_mesh(ascii_solids(("all", CUBE_CORNERS)), "t.stl")
    mesh = read_mesh(ascii_solids(*blocks), "t.stl")
    np.testing.assert_array_equal(mesh.vertices, whole.vertices)
    np.testing.assert_array_equal(mesh.faces, whole.faces)
    kept = [name for name, corners in blocks if len(corners)]
    assert mesh.group_names == tuple(kept)
    expected = [kept.index(name) for name, corners in blocks for _ in range(len(corners))]
    np.testing.assert_array_equal(mesh.face_groups, expected)


def test_trimesh_multibody_file() -> None:
    """trimesh's models/multibody.stl: CRLF, two named bodies, each wound inconsistently
    (trimesh's own is_winding_consistent says False for both)."""
    mesh = read_mesh(DATA / "multibody.stl")
    assert mesh.group_names == ("bodyB", "bodyA")
    assert np.bincount(mesh.face_groups).tolist() == [12, 20]
    assert len(mesh.vertices) == 20


def test_trimesh_two_cubes_with_bare_endsolid() -> None:
    """trimesh's models/two_objects_mixed_case_names.stl: ``endsolid`` without a name."""
    mesh = read_mesh(DATA / "two_objects_mixed_case_names.stl")
    assert mesh.group_names == ("CubeExportedFromCAD", "TranslatedCubeExportedFromCAD")
    assert np.bincount(mesh.face_groups).tolist() == [12, 12]


@given(
    corners=st.lists(
        st.sampled_from([0.0, -0.0, 1.0, 2.5, -3.0, 1e-30, 3.4e38]), min_size=9, max_size=90
    ).map(lambda values: np.array(values[: len(values) // 9 * 9]).reshape(-1, 3, 3)),
    as_text=st.booleans(),
)
@settings(deadline=None)  # the first example may compile the weld's kernels (seconds)
def test_the_welded_points_are_distinct_as_the_analysis_takes_them(
    corners: np.ndarray, as_text: bool
) -> None:
    """An STL's vertices say they are distinct points (the analysis then skips looking for
    equal ones), and they are: the topology's own search finds none, -0.0 and 0.0 included."""
    data = ascii_stl(corners, np.zeros((len(corners), 3))) if as_text else binary_stl(corners)
    mesh = read_mesh(data, "t.stl")
    assert mesh.distinct_points
    assert same_points(mesh.vertices) is None


@pytest.mark.parametrize("name", ["multibody.stl", "soup.stl", "teapot.stl"])
def test_real_stl_points_are_distinct(name: str) -> None:
    mesh = read_mesh(DATA / name)
    assert mesh.distinct_points and same_points(mesh.vertices) is None
    checked = mesh.checked()  # the core takes the flag along, and skips the search
    assert checked.distinct_points and by_position(checked) is checked.faces


def test_other_formats_do_not_claim_distinct_points() -> None:
    assert not read_mesh(DATA / "cube.obj").distinct_points


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("where", [(0, 0, 0), (2, 1, 0), (3, 2, 2)])
def test_a_non_finite_corner_names_the_first_such_triangle(
    value: float, where: tuple[int, int, int]
) -> None:
    # Checked after the weld: the first bad point's first corner is the file's first bad
    # corner, also where a later triangle holds another bad value seen first in the table.
    corners = np.concatenate([CORNERS, CORNERS + 10.0])
    corners[where] = value
    corners[-1, 0, 1] = -value  # a second bad point, in the last triangle
    triangle = where[0] + 1
    with pytest.raises(MeshFileError, match=rf"^Triangle {triangle} \(counting from 1\) has a"):
        read_mesh(binary_stl(corners), "t.stl")
    with pytest.raises(MeshFileError, match=rf"^Triangle {triangle} \(counting from 1\) has a"):
        read_mesh(ascii_stl(corners, np.zeros((len(corners), 3))), "t.stl")
