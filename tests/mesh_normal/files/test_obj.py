from __future__ import annotations

import numpy as np
import pytest
import trimesh

from mesh_normal.files import MeshFileError, read_mesh
from tests.meshes import TETRA_FACES, TETRA_VERTICES
from tests.paths import DATA


def obj(text: str) -> bytes:
    return text.strip().replace("\n    ", "\n").encode()


def test_tetrahedron() -> None:
    lines = [f"v {x} {y} {z}" for x, y, z in TETRA_VERTICES.tolist()]
    lines += [f"f {a} {b} {c}" for a, b, c in (TETRA_FACES + 1).tolist()]
    mesh = read_mesh("\n".join(lines).encode(), "t.obj")
    assert mesh.format == "obj" and mesh.source_faces == 4 and mesh.notes == ()
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)
    np.testing.assert_array_equal(mesh.faces, TETRA_FACES)
    assert mesh.file_corner_normals is None and mesh.file_vertex_normals is None


@pytest.mark.parametrize("name", ["cube.obj", "cow.obj"])
def test_samples_match_trimesh(name: str) -> None:
    """Without unused vertices or texture seams trimesh keeps the file's arrays too."""
    mesh = read_mesh((DATA / name).read_bytes(), name)
    reference = trimesh.load_mesh(DATA / name, process=False)
    np.testing.assert_array_equal(mesh.vertices, reference.vertices)
    np.testing.assert_array_equal(mesh.faces, reference.faces)


def test_keeps_unused_vertices_and_order_and_does_not_split_at_seams() -> None:
    data = obj("""
    # an unused vertex first, then a quad whose corners repeat with other texture coordinates
    v 9 9 9
    v 0 0 0
    v 1 0 0
    v 1 1 0
    v 0 1 0
    vt 0 0
    vt 1 0
    vt 1 1
    vt 0 1
    vt 0.5 0.5
    f 2/1 3/2 4/3
    f 2/5 4/4 5/3
    """)
    mesh = read_mesh(data, "seam.obj")
    np.testing.assert_array_equal(
        mesh.vertices, [[9, 9, 9], [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    )
    np.testing.assert_array_equal(mesh.faces, [[1, 2, 3], [1, 3, 4]])
    trimesh_mesh = trimesh.load(trimesh.util.wrap_as_stream(data), file_type="obj", process=False)
    assert len(trimesh_mesh.vertices) != 5  # why we parse OBJ ourselves


def test_polygons_negative_indices_and_statements() -> None:
    data = obj("""
    mtllib a.mtl
    o thing
    v 0 0 0 1.0
    v 1 0 0 0.5 0.5 0.5
    v 1 1 0
    v 0 1 0
    g group
    usemtl red
    s off
    f -4 -3 -2 -1
    l 1 2
    p 3
    v 0.5 0.5 1
    f 1 2 3 4 -1
    f 1 \\
      3 5
    """)
    mesh = read_mesh(data, "poly.obj")
    np.testing.assert_array_equal(
        mesh.faces, [[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 2, 4]]
    )
    assert mesh.source_faces == 3
    assert mesh.notes == (
        "Triangulated 1 quad and 1 larger polygon as fans from each one's first corner.",
        "1 polygon is not planar (largest deviation 38.4 % of its size); its triangles follow "
        "the file's corners.",
        "Skipped 1 line ('l') and 1 point ('p') elements: only faces are read.",
    )


def test_corner_and_vertex_normals() -> None:
    data = obj("""
    v 0 0 0
    v 1 0 0
    v 0 1 0
    vn 0 0 1
    vn 0 0 -1
    f 1//1 2//1 3//1
    """)
    mesh = read_mesh(data, "n.obj")
    np.testing.assert_array_equal(mesh.file_corner_normals, [[[0, 0, 1]] * 3])
    np.testing.assert_array_equal(mesh.file_vertex_normals, [[0, 0, 1]] * 3)
    mixed = read_mesh(data + b"\nf 1//1 3//2 2//1", "n.obj")  # vertex 3 gets two normals
    assert mixed.file_vertex_normals is None
    np.testing.assert_array_equal(mixed.file_corner_normals[1, 1], [0, 0, -1])
    full = read_mesh(data.replace(b"//", b"/1/") + b"\nvt 0 0", "n.obj")
    np.testing.assert_array_equal(full.file_corner_normals, mesh.file_corner_normals)


def test_mixed_corner_forms() -> None:
    mesh = read_mesh(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1 2/1 3//", "m.obj")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2]])


def test_exact_floats() -> None:
    value = 0.1 + 0.2
    mesh = read_mesh(f"v {value!r} 1e-300 -2.5\nv 1 0 0\nv 0 1 0\nf 1 2 3".encode(), "e.obj")
    assert mesh.vertices[0].tolist() == [value, 1e-300, -2.5]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4",
            "Line 4: vertex index 4 is out of range; the file has 3 vertex statements.",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0", "Line 4: vertex index 0 is not valid"),
        ("v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0", "Line 2: vertex index -2 reaches back before"),
        ("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3", "vertex 2 (line 2) include nan"),
        ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3", "Line 2: 'v' needs 3 numbers, but has 2."),
        ("v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3", "Line 2: 'x' is not a number."),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a", "The face corner 'a' is not an index"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0", "The file holds no faces."),
        ("# nothing\n", "The file holds no vertices and no faces."),
    ],
)
def test_errors_name_the_line(text: str, message: str) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(text.encode(), "bad.obj")
    assert message in str(error.value)
    assert error.value.status_code == 400


def test_comments_may_follow_vertices_and_faces() -> None:
    mesh = read_mesh(
        b"v 0 0 0 # origin\nv 1 0 0\nv 0 1 0\nf 1 2 3 # the lid\nf 1 3 2#under\n", "c.obj"
    )
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 1]]
    assert mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


SQUARE_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nvn 0 0 -1\n"


@pytest.mark.parametrize(
    "faces",
    [
        "f 1// 2// 3//\nf 1// 3// 4//",  # empty normal fields (the NumPy broadcasting failure)
        "f 1/ 2/ 3/\nf 1/ 3/ 4/",  # empty texture fields
        "f 1/1/ 2/1/ 3/1/\nf 1/1/ 3/1/ 4/1/",  # a texture, an empty normal
        "f 1// 2//1 3//\nf 1//2 3// 4//1",  # some corners with a normal, some without
        "f 1 2/ 3//\nf 1/1/ 3/1 4",  # every form in one file
        "f 1// 2// 3//\nf 1 3 4",  # forms differing between faces
        # One slash a corner on average, as in v/vt, but not in each: corner by corner.
        "f 1 2/1/1 3/1\nf 1/1 3 4/1",
        "f 1/1 2 3/1/1\nf 1 3/1/1 4/1",
    ],
)
def test_empty_fields_read_as_other_readers_do_and_drop_partial_normals(faces: str) -> None:
    mesh = read_mesh((SQUARE_OBJ + faces).encode(), "empty.obj")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3]])
    assert mesh.source_faces == 2
    assert mesh.file_corner_normals is None and mesh.file_vertex_normals is None


@pytest.mark.parametrize(
    "faces",
    [
        "f 1//1 2//1 3//1\nf 1//2 3//2 4//2",
        "f 1//1 2/1/1 3//1\nf 1/1/2 3//2 4/1/2",  # an empty texture field beside full corners
        "f 1//-2 2//-2 3//-2\nf 1//-1 3//-1 4//-1",  # negative normal indices
    ],
)
def test_empty_texture_fields_keep_the_normals(faces: str) -> None:
    mesh = read_mesh((SQUARE_OBJ + faces).encode(), "normals.obj")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(mesh.file_corner_normals, [[[0, 0, 1]] * 3, [[0, 0, -1]] * 3])


@pytest.mark.parametrize("corner", ["/3", "1/2/3/4", "1/x", "1//y", "x//", "//4", "//", "4////"])
@pytest.mark.parametrize("where", ["f 1// 3// {}", "f {} 1// 3//"])
def test_a_broken_corner_names_its_line(corner: str, where: str) -> None:
    text = SQUARE_OBJ + f"f 1// 2// 3//\n\n{where.format(corner)}"
    with pytest.raises(MeshFileError) as error:
        read_mesh(text.encode(), "bad.obj")
    assert str(error.value) == (
        f"The face corner {corner!r} is not an index, nor index/texture, "
        "index//normal or index/texture/normal (line 10)."
    )


def test_objects_and_groups_are_kept_per_triangle() -> None:
    data = obj("""
    v 0 0 0
    v 1 0 0
    v 0 1 0
    v 1 1 0
    f 1 2 3
    o Box
    f 1 2 3 4
    g side  a   # several names, spaced and commented
    f 1 2 3
    g
    f 3 2 1
    o Lid
    f 1 2
    f 1 2 3
    g side a
    f 1 3 2
    o Box
    g\tside a
    f 1 2 3
    g empty
    o Box
    f 2 3 4
    """)
    mesh = read_mesh(data, "groups.obj")
    # The quad's two triangles share their group; the two-corner face gives no triangle.
    assert mesh.group_names == ("default", "Box", "Box/side a", "Lid", "Lid/side a")
    assert mesh.face_groups is not None and not mesh.face_groups.flags.writeable
    np.testing.assert_array_equal(mesh.face_groups, [0, 1, 1, 2, 1, 3, 4, 2, 1])
    assert len(mesh.face_groups) == len(mesh.faces)


def test_groups_are_numbered_by_their_first_triangle_and_empty_ones_left_out() -> None:
    data = obj("""
    v 0 0 0
    v 1 0 0
    v 0 1 0
    g unused
    g second
    g first
    g second
    f 1 2 3
    g first
    f 1 3 2
    """)
    mesh = read_mesh(data, "order.obj")
    assert mesh.group_names == ("second", "first")
    np.testing.assert_array_equal(mesh.face_groups, [0, 1])


def test_a_file_without_o_or_g_has_no_groups() -> None:
    mesh = read_mesh(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3", "plain.obj")
    assert mesh.face_groups is None and mesh.group_names is None
    single = read_mesh(b"o only\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2", "one.obj")
    assert single.group_names == ("only",)
    np.testing.assert_array_equal(single.face_groups, [0, 0])


def test_line_continuations_join_any_statement() -> None:
    data = (
        b"v 0 \\\n 0 0\r\n"  # a vertex split in two, Windows line ends around it
        b"v 1 \\   \r\n"  # spaces after the backslash still continue it
        b"0 0 \\\r\n"
        b"\r\n"  # ...onto an empty line: the vertex is complete before it
        b"v \\\n0 \\\n1 \\\n0\n"  # three continuations
        b"f 1 \\\n2 \\\n3\n"
        b"f 1 3 2 \\"  # the file ends inside a continued face
    )
    mesh = read_mesh(data, "continued.obj")
    assert mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 1]]


def test_a_comment_ending_in_a_backslash_does_not_swallow_the_next_line() -> None:
    data = b"# saved in C:\\models\\\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    assert read_mesh(data, "comment.obj").vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


def test_errors_in_continued_lines_name_their_first_line() -> None:
    data = b"v 0 0 0\nv 1 \\\n x 0\nv 0 1 0\nf 1 2 3\n"
    with pytest.raises(MeshFileError, match=r"^Line 2: 'x' is not a number\.$"):
        read_mesh(data, "bad.obj")
    data = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 \\\n 3\nf 1 \\\n2 9\n"
    with pytest.raises(MeshFileError, match=r"^Line 7: vertex index 9 is out of range"):
        read_mesh(data, "bad.obj")


def test_real_file_with_two_objects_keeps_them() -> None:
    """trimesh's models/two_objects.obj: a cube (12 faces) then a tetrahedron (4)."""
    mesh = read_mesh((DATA / "two_objects.obj").read_bytes(), "two_objects.obj")
    assert mesh.group_names == ("cube", "tetra")
    np.testing.assert_array_equal(mesh.face_groups, [0] * 12 + [1] * 4)
    assert mesh.faces[12:].min() == 8  # the tetrahedron uses its own four vertices


def test_real_blender_file_with_vertex_double_slash_normal_faces() -> None:
    """trimesh's models/cube_compressed.obj: ``f 2//1 4//1 1//1``, one ``vn`` per side."""
    mesh = read_mesh((DATA / "cube_compressed.obj").read_bytes(), "cube_compressed.obj")
    assert mesh.faces.shape == (12, 3) and mesh.group_names == ("Cube",)
    assert mesh.faces[0].tolist() == [1, 3, 0]
    corners = mesh.vertices[mesh.faces]
    geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    stored = mesh.file_corner_normals
    assert stored is not None and np.all(stored == stored[:, :1])  # one normal per face
    cosines = np.einsum("ij,ij->i", geometric, stored[:, 0]) / np.linalg.norm(geometric, axis=1)
    assert np.all(cosines > 0.999)  # each side's vn is its own outward normal
    assert mesh.file_vertex_normals is None  # corners of a cube get three normals each


def test_group_names_are_utf8_and_latin1_only_when_not() -> None:
    body = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    utf8 = read_mesh("o Würfel 立方体\n".encode() + body, "u.obj")
    assert utf8.group_names == ("Würfel 立方体",)
    latin1 = read_mesh("o Würfel\n".encode("latin-1") + body, "l.obj")  # b"\xfc": not UTF-8
    assert latin1.group_names == ("Würfel",)


# --- Chunks of lines: the same mesh and the same sentences as all lines at once -------------

CHUNKED = (
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
    "f 1//1 2//1 3//1\nf 1//1 3//1 4//1\nf 1//1 2//1 4//1\nf 2//1 3//1 4//1\n"
)


@pytest.mark.parametrize(
    "text",
    [
        CHUNKED,
        CHUNKED.replace("f 2//1 3//1 4//1", "f 2 3 4"),  # the last chunk has no normals
        CHUNKED.replace("f 1//1 2//1 3//1", "f 1 2 3"),  # the first chunk has none
        CHUNKED.replace("f 2//1 3//1 4//1", "f 2//1 3//1 4//1 # a lid"),
        CHUNKED.replace("f 2//1 3//1 4//1", "f 2//1 3/x/1 4//1"),
        CHUNKED.replace("f 2//1 3//1 4//1", "f 2//1 3//1 9//1"),
        CHUNKED.replace("v 0 1 0", "v 0 1"),
        CHUNKED.replace("v 0 1 0", "v 0 1 zero"),
    ],
)
def test_chunks_of_lines_read_as_one(monkeypatch: pytest.MonkeyPatch, text: str) -> None:
    def outcome() -> object:
        try:
            mesh = read_mesh(text.encode(), "c.obj")
        except MeshFileError as error:
            return str(error)
        normals = mesh.file_corner_normals
        return mesh.vertices.tolist(), mesh.faces.tolist(), normals is None, mesh.notes

    whole = outcome()
    monkeypatch.setattr("mesh_normal.files.obj._TEXT_CHUNK", 1)  # a chunk a line
    assert outcome() == whole


def test_written_in_chunks_as_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    from mesh_normal.files.obj import write_obj

    points, faces = np.array(TETRA_VERTICES, dtype=float), np.array(TETRA_FACES)
    colors = np.arange(12, dtype=np.uint8).reshape(4, 3)
    whole = write_obj(points, faces), write_obj(points, faces, colors)
    monkeypatch.setattr("mesh_normal.files.obj._CHUNK", 1)
    assert (write_obj(points, faces), write_obj(points, faces, colors)) == whole
    assert whole[0].endswith(b"\nf 2 3 4\n") or whole[0].endswith(b"\n")
