from __future__ import annotations

import struct

import numpy as np
import pytest
import trimesh

from mesh_normal.files import MeshFileError, read_mesh
from tests.meshes import TETRA_FACES, TETRA_VERTICES
from tests.paths import DATA

HEADER = """ply
format {format} 1.0
comment test
element vertex {vertices}
property float x
property float y
property float z
property float nx
property float ny
property float nz
property uchar red
element face {faces}
property list uchar int vertex_indices
property float nx
property float ny
property float nz
element edge 1
property int vertex1
property int vertex2
end_header
"""
SQUARE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1), (9, 9, 9)]
POLYGONS = [[0, 1, 2, 3], [0, 2, 3], [1, 0, 4, 3, 2]]


def polygon_ply(file_format: str) -> bytes:
    header = HEADER.format(format=file_format, vertices=len(SQUARE), faces=len(POLYGONS)).encode()
    if file_format == "ascii":
        body = "".join(f"{x} {y} {z} 0 0 1 5\n" for x, y, z in SQUARE)
        body += "".join(
            f"{len(p)} {' '.join(map(str, p))} 0 0 {i}\n" for i, p in enumerate(POLYGONS)
        )
        return header + (body + "0 1\n").encode()
    e = ">" if file_format == "binary_big_endian" else "<"
    body = b"".join(struct.pack(f"{e}6fB", x, y, z, 0, 0, 1, 5) for x, y, z in SQUARE)
    body += b"".join(
        struct.pack(f"{e}B{len(p)}i3f", len(p), *p, 0, 0, i) for i, p in enumerate(POLYGONS)
    )
    return header + body + struct.pack(f"{e}2i", 0, 1)


@pytest.mark.parametrize("file_format", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_polygons_normals_and_extra_properties(file_format: str) -> None:
    mesh = read_mesh(polygon_ply(file_format), "p.ply")
    np.testing.assert_array_equal(mesh.vertices, SQUARE)  # the unused vertex 5 is kept
    np.testing.assert_array_equal(
        mesh.faces, [[0, 1, 2], [0, 2, 3], [0, 2, 3], [1, 0, 4], [1, 4, 3], [1, 3, 2]]
    )
    np.testing.assert_array_equal(mesh.file_vertex_normals, [[0, 0, 1]] * 6)
    np.testing.assert_array_equal(mesh.file_face_normals[:, 2], [0, 0, 1, 2, 2, 2])
    assert mesh.source_faces == 3
    assert mesh.notes == (
        "Triangulated 1 quad and 1 larger polygon as fans from each one's first corner.",
        "1 polygon is not planar (largest deviation 38.4 % of its size); its triangles follow "
        "the file's corners.",
        "Ignored elements this reader does not use: edge (1).",
    )


@pytest.mark.parametrize("name", ["sphere.ply", "ant.ply", "nut.ply", "airplane.ply"])
def test_samples_match_trimesh(name: str) -> None:
    """All-triangle files: trimesh keeps the file's arrays, and so do we (float32 as declared)."""
    mesh = read_mesh((DATA / name).read_bytes(), name)
    reference = trimesh.load_mesh(DATA / name, process=False)
    np.testing.assert_array_equal(mesh.vertices, reference.vertices)
    np.testing.assert_array_equal(mesh.faces, reference.faces)


def test_trimesh_reorders_mixed_polygons() -> None:
    """Why we parse PLY ourselves: trimesh groups triangulated faces by polygon size."""
    kwargs = trimesh.exchange.ply.load_ply(trimesh.util.wrap_as_stream(polygon_ply("ascii")))
    ours = read_mesh(polygon_ply("ascii"), "p.ply").faces
    assert not np.array_equal(kwargs["faces"], ours)


def test_tetrahedron_ascii() -> None:
    text = (
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
        "property double z\nelement face 4\nproperty list uchar uint vertex_index\n"
        "end_header\n"
    )
    text += "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in TETRA_VERTICES.tolist())
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in TETRA_FACES.tolist())
    mesh = read_mesh(text.encode())
    assert mesh.format == "ply"
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)
    np.testing.assert_array_equal(mesh.faces, TETRA_FACES)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d[:-60], "ends inside its face elements"),
        (lambda d: d.replace(b"element vertex 6", b"element vertex 600"), "600 vertex elements"),
        (
            lambda d: d.replace(b"format binary_little_endian", b"format binary_middle"),
            "not ascii, binary_little_endian or binary_big_endian",
        ),
        (lambda d: d.replace(b"end_header", b"end_heade"), "no 'end_header'"),
        (lambda d: d.replace(b"property float x", b"property quad x"), "Line 5 of the PLY header"),
    ],
)
def test_broken_binary(edit, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(MeshFileError, match=message):
        read_mesh(edit(polygon_ply("binary_little_endian")), "p.ply")


@pytest.mark.parametrize(
    ("polygon", "message"),
    [
        (
            "3 0 1 7",
            "Face 0 \\(counting from 0\\) refers to vertex 7 \\(counting from 0\\), but the "
            "file has only 6.",
        ),
        (
            "3 0 -1 2",
            "Face 0 \\(counting from 0\\) refers to vertex -1; vertex indices cannot be negative.",
        ),
    ],
)
def test_index_out_of_range(polygon: str, message: str) -> None:
    data = polygon_ply("ascii").replace(b"4 0 1 2 3 0 0 0", polygon.encode() + b" 0 0 0")
    with pytest.raises(MeshFileError, match=message):
        read_mesh(data, "p.ply")


def test_nan_vertex() -> None:
    data = polygon_ply("ascii").replace(b"1 1 0 0 0 1 5", b"1 nan 0 0 0 1 5")
    with pytest.raises(MeshFileError, match="vertex 2 \\(counting from 0\\) include nan"):
        read_mesh(data, "p.ply")


#: Faces as MeshLab writes them with per-corner texture coordinates, and per-corner colours
#: (``9 r g b r g b r g b``) that its header does not declare: as in trimesh's
#: ``models/fuze_ascii.ply``.
MESHLAB_FACES = """ply
format ascii 1.0
comment VCGLIB generated
comment TextureFile fuze uv.jpg
element vertex 4
property float x
property float y
property float z
property uchar red
property uchar green
property uchar blue
property uchar alpha
element face 4
property list uchar int vertex_indices
property list uchar float texcoord
property uchar red
property uchar green
property uchar blue
property uchar alpha
end_header
"""


def meshlab_faces(extra: str) -> bytes:
    rows = "".join(f"{x} {y} {z} 10 20 30 255 \n" for x, y, z in TETRA_VERTICES.tolist())
    faces = "".join(
        f"3 {a} {b} {c} 6 0.1 0.2 0.3 0.4 0.5 0.6 {extra}\n" for a, b, c in TETRA_FACES.tolist()
    )
    return (MESHLAB_FACES + rows + faces).encode()


def test_lines_longer_than_the_header_keep_their_corners_only() -> None:
    mesh = read_mesh(meshlab_faces("9 1 1 1 1 1 1 1 1 1"), "fuze_ascii.ply")
    np.testing.assert_array_equal(mesh.faces, TETRA_FACES)
    assert mesh.vertex_colors is not None
    assert mesh.vertex_colors.tolist() == [[10, 20, 30, 255]] * 4
    assert mesh.face_colors is None  # "9 1 1 1" would be a wrong colour
    assert mesh.notes == (
        "4 of the 4 face lines of the PLY file hold more numbers than its header declares; "
        "only their vertex_indices were read, not texcoord, red, green, blue, alpha.",
    )


def test_lines_that_fit_the_header_keep_every_property() -> None:
    mesh = read_mesh(meshlab_faces("255 128 0 255"), "fuze_ascii.ply")
    assert mesh.face_colors is not None and mesh.face_colors.dtype == np.uint8
    assert mesh.face_colors.tolist() == [[255, 128, 0, 255]] * 4
    assert mesh.notes == ()


def test_a_line_shorter_than_the_header_is_still_an_error() -> None:
    with pytest.raises(MeshFileError, match=r"has '0\.2' where a list length should be"):
        read_mesh(meshlab_faces("255 128"), "short.ply")


def test_numbers_after_the_last_element_are_named() -> None:
    data = meshlab_faces("255 128 0 255") + b"7 7 7\n"
    assert read_mesh(data, "x.ply").notes == (
        "Ignored 3 numbers after the PLY file's last element.",
    )


# --- ASCII read a chunk of words at a time: the same as all the words at once ---------------

_HEAD = (
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
)
_BODY = "0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0.1 0 0 255\n0 1 0 9 9 9\n3 0 1 2\n3 0 2 3\n"


@pytest.mark.parametrize(
    "body",
    [
        _BODY,
        _BODY.replace("\n", "\r\n"),
        _BODY.rstrip("\n"),
        _BODY.replace("3 0 2 3", "4 0 1 2 3"),  # lists of two sizes
        _BODY.replace("3 0 2 3", "3.0 0 2 3"),
        _BODY.replace("3 0 2 3", "03 0 2 3"),
        _BODY.replace("1 1 0.1", "1 1 x"),
        _BODY.replace("3 0 2 3\n", ""),  # short
        _BODY + "7 7\n",  # numbers over
        _BODY.replace("3 0 2 3", "3 0 2 3 8 8"),  # a line longer than its header
    ],
)
def test_ascii_chunks_read_as_all_words(monkeypatch: pytest.MonkeyPatch, body: str) -> None:
    from mesh_normal.files import ply

    def outcome() -> object:
        try:
            mesh = read_mesh((_HEAD + body).encode(), "c.ply")
        except MeshFileError as error:
            return str(error)
        colors = mesh.vertex_colors
        return mesh.vertices.tolist(), mesh.faces.tolist(), colors.tolist(), mesh.notes  # type: ignore[union-attr]

    monkeypatch.setattr(ply, "_read_chunks", lambda *_: False)
    whole = outcome()
    monkeypatch.undo()
    monkeypatch.setattr(ply, "_CHUNK", 3)  # a line or so a chunk
    assert outcome() == whole
    assert ply._read_chunks([ply._Element("vertex", 1, [("x", "f8")])], b"1\n2\n") is False


def test_a_plain_ascii_file_is_read_in_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    from mesh_normal.files import ply

    monkeypatch.setattr(ply, "_CHUNK", 3)
    _, elements, start = ply._header((_HEAD + _BODY).encode())
    assert ply._read_chunks(elements, (_HEAD + _BODY).encode()[start:])
    assert elements[1].data["vertex_indices"].tolist() == [[0, 1, 2], [0, 2, 3]]  # type: ignore[attr-defined]
