from __future__ import annotations

import numpy as np
import pytest

from mesh_normal.files import MeshFileError, read_mesh
from tests.paths import DATA

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
    assert mesh.face_colors is None  # one face of three has a colour: named, not guessed
    assert mesh.notes[-1] == (
        "The OFF face colours were not read: only some faces have one, or they are not all 3 "
        "or 4 numbers (colour-map indices, say, which this reader does not resolve)."
    )


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


TIP = b"""COFF
5 3 0
0 0 0 255 0 0 255
1 0 0 0 255 0 255
1 1 0 0 0 255 128
0 1 0 10 20 30 0
0.5 0.5 1 1 2 3 4
4 0 1 2 3 {a}
3 0 4 1 {b}
3 1 4 2 {c}
"""


def test_coff_vertex_colours_and_integer_face_colours() -> None:
    mesh = read_mesh(
        TIP.replace(b"{a}", b"255 0 0").replace(b"{b}", b"0 255 0").replace(b"{c}", b"0 0 255"),
        "c.off",
    )
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.uint8
    assert mesh.vertex_colors[:, 3].tolist() == [255, 255, 128, 0, 4]
    assert mesh.face_colors is not None and mesh.face_colors.dtype == np.uint8
    # the quad's two triangles both get its colour
    assert mesh.face_colors.tolist() == [[255, 0, 0], [255, 0, 0], [0, 255, 0], [0, 0, 255]]
    assert mesh.notes == ("Triangulated 1 quad as fans from each one's first corner.",)


def test_float_face_colours_with_alpha() -> None:
    data = (
        TIP.replace(b"{a}", b"1 0 0 0.5")
        .replace(b"{b}", b"0 1.0 0 1")
        .replace(b"{c}", b"0 0 1 0.25")
    )
    mesh = read_mesh(data, "c.off")
    assert mesh.face_colors is not None and mesh.face_colors.dtype == np.float64
    np.testing.assert_array_equal(mesh.face_colors[:, 3], [0.5, 0.5, 1, 0.25])


@pytest.mark.parametrize(
    ("a", "words"),
    [(b"7", "colour-map indices"), (b"300 0 0", "integers must be 0 to 255")],
)
def test_face_colours_that_cannot_be_read_are_named(a: bytes, words: str) -> None:
    data = (
        TIP.replace(b"{a}", a)
        .replace(b"{b}", b"0 255 0" if a != b"7" else b"8")
        .replace(b"{c}", b"0 0 255" if a != b"7" else b"9")
    )
    mesh = read_mesh(data, "c.off")
    assert mesh.face_colors is None
    assert words in mesh.notes[-1]
    assert mesh.vertex_colors is not None


def test_stoff_colours_come_before_the_texture_coordinates() -> None:
    data = b"STCOFF\n3 1 0\n0 0 0 1 0 0 0.5 0.5\n1 0 0 0 1 0 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n"
    mesh = read_mesh(data, "st.off")
    assert mesh.vertex_colors is not None
    np.testing.assert_array_equal(mesh.vertex_colors, np.eye(3))


def test_trimesh_cube_with_face_colours_and_comments() -> None:
    mesh = read_mesh((DATA / "off_face_colors.off").read_bytes(), "comments.off")
    assert mesh.face_colors is not None and mesh.face_colors.shape == (12, 4)
    np.testing.assert_array_equal(
        mesh.face_colors[::2, :3],
        [[1, 0, 0], [0.3, 0.4, 0], [0.2, 0.5, 0.1], [0.1, 0.6, 0.2], [0, 0.7, 0.3], [0, 1, 0]],
    )
    np.testing.assert_array_equal(mesh.face_colors[::2], mesh.face_colors[1::2])
    assert np.all(mesh.face_colors[:, 3] == 0.75)


def test_counts_glued_to_the_keyword_after_whitespace() -> None:
    glued = read_mesh((DATA / "off_whitespace.off").read_bytes(), "whitespace.off")
    spaced = read_mesh((DATA / "off_face_colors.off").read_bytes(), "comments.off")
    np.testing.assert_array_equal(glued.vertices, spaced.vertices)
    np.testing.assert_array_equal(glued.faces, spaced.faces)
    assert glued.face_colors is not None and spaced.face_colors is not None
    np.testing.assert_array_equal(glued.face_colors, spaced.face_colors)
    with pytest.raises(MeshFileError, match="does not start with OFF"):
        read_mesh(b"OFFX 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "x.off")


# --- The plain-file path (numbers by line, in chunks) gives what the line-by-line path gives ---

PLAIN = b"OFF\n5 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 1 2 3\n3 0 4 1\n3 1 4 2\n"


def _outcome(read: object, data: bytes) -> object:
    try:
        mesh = read(data)  # type: ignore[operator]
    except MeshFileError as error:
        return str(error), error.status_code
    except OverflowError as error:  # read_mesh words it: the same for both paths
        return type(error), str(error)
    return mesh.vertices.tolist(), mesh.faces.tolist(), mesh.notes, mesh.source_faces


@pytest.mark.parametrize(
    "data",
    [
        PLAIN,
        PLAIN.replace(b"\n", b"\r\n"),
        PLAIN.rstrip(b"\n"),  # no line end after the last face
        PLAIN.replace(b"0 1 0\n", b"0 1 0\n\n   \n"),  # blank lines are skipped
        PLAIN.replace(b"0.5 0.5 1", b"5e-1 +.5 1."),
        PLAIN.replace(b"0.5 0.5 1", b"nan 0.5 1"),
        PLAIN.replace(b"0.5 0.5 1", b"0x1p3 0.5 1"),
        PLAIN.replace(b"0.5 0.5 1", b"0.5 0.5"),
        PLAIN.replace(b"0.5 0.5 1", b"0.5 0.5 1 7"),
        PLAIN.replace(b"3 0 4 1", b"3 0 4"),
        PLAIN.replace(b"3 0 4 1", b"3 0 4 1.0"),
        PLAIN.replace(b"3 0 4 1", b"3 0 4 1e0"),
        PLAIN.replace(b"3 0 4 1", b"3 0 4 -1"),
        PLAIN.replace(b"3 0 4 1", b"3 0 4 99999999999999999999"),
        PLAIN.replace(b"3 0 4 1", b"2 0 4"),
        PLAIN.replace(b"3 0 4 1", b"3 0 4 1 255 0 0"),
        PLAIN.replace(b"5 3 0", b"5 4 0"),
        PLAIN.replace(b"5 3 0", b"5 0 0"),
        PLAIN.replace(b"\n3 1 4 2", b"\r3 1 4 2"),
        PLAIN + b"trailing words\n",
        PLAIN + b"7 8 9\n",
    ],
)
def test_plain_path_agrees_with_the_line_by_line_path(data: bytes) -> None:
    from mesh_normal.files.off import _read_rows, read_off

    assert _outcome(read_off, data) == _outcome(_read_rows, data)


def test_plain_path_reads_across_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    from mesh_normal.files import off

    monkeypatch.setattr(off, "_CHUNK", 7)  # a chunk of a line or two
    assert off._read_plain(PLAIN) is not None
    assert _outcome(off.read_off, PLAIN) == _outcome(off._read_rows, PLAIN)
