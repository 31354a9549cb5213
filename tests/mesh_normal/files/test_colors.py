"""Vertex colours: read from PLY and OBJ, written back in PLY and OBJ, named where dropped."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from mesh_normal.files import read_mesh, write_mesh
from mesh_normal.files.loaded import build
from mesh_normal.files.write import unkept
from tests.meshes import TETRA_FACES, TETRA_VERTICES
from tests.paths import DATA

UCHAR = np.array([[255, 0, 3], [4, 5, 6], [7, 128, 9], [0, 254, 1]], dtype=np.uint8)
FLOAT_RGBA = np.array(
    [[0.1, 0.2, 0.3, 1.0], [0.0, 0.5, 1.0, 0.25], [1 / 3, 2 / 3, 0.7, 0.0], [0.9, 0.8, 0.7, 0.6]],
    dtype=np.float32,
)


def ply_ascii(colors: np.ndarray, kind: str) -> bytes:
    names = ["red", "green", "blue", "alpha"][: colors.shape[1]]
    header = [
        "ply",
        "format ascii 1.0",
        f"element vertex {len(TETRA_VERTICES)}",
        *(f"property float {axis}" for axis in "xyz"),
        *(f"property {kind} {name}" for name in names),
        f"element face {len(TETRA_FACES)}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    rows = [
        " ".join([*map(repr, point.tolist()), *map(repr, color.tolist())])
        for point, color in zip(TETRA_VERTICES, colors, strict=True)
    ]
    faces = [f"3 {a} {b} {c}" for a, b, c in TETRA_FACES.tolist()]
    return "\n".join([*header, *rows, *faces, ""]).encode()


@pytest.mark.parametrize(("colors", "kind"), [(UCHAR, "uchar"), (FLOAT_RGBA, "float")])
def test_ply_colours_are_read_in_their_type(colors: np.ndarray, kind: str) -> None:
    mesh = read_mesh(ply_ascii(colors, kind), "c.ply")
    assert mesh.vertex_colors is not None
    assert mesh.vertex_colors.dtype == colors.dtype
    np.testing.assert_array_equal(mesh.vertex_colors, colors)
    assert not mesh.vertex_colors.flags.writeable


@pytest.mark.parametrize("colors", [UCHAR, FLOAT_RGBA], ids=["uchar", "float-rgba"])
def test_ply_colours_round_trip_bit_for_bit(colors: np.ndarray) -> None:
    data = write_mesh(TETRA_VERTICES, TETRA_FACES, "ply", vertex_colors=colors)
    again = read_mesh(data, "again.ply")
    assert again.vertex_colors is not None and again.vertex_colors.dtype == colors.dtype
    assert again.vertex_colors.tobytes() == colors.tobytes()
    header = data[: data.index(b"end_header")].decode()
    kind = "uchar" if colors.dtype == np.uint8 else "float"
    assert f"property {kind} red\n" in header
    assert ("property float alpha" in header) == (colors.shape[1] == 4)


def test_binary_big_endian_ply_colours() -> None:
    header = (
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
        "property double y\nproperty double z\nproperty uchar red\nproperty uchar green\n"
        "property uchar blue\nelement face 1\nproperty list uchar int vertex_indices\n"
        "end_header\n"
    )
    records = np.zeros(3, dtype=[("xyz", ">f8", (3,)), ("rgb", "u1", (3,))])
    records["xyz"] = TETRA_VERTICES[:3]
    records["rgb"] = UCHAR[:3]
    face = np.zeros(1, dtype=[("n", "u1"), ("i", ">i4", (3,))])
    face["n"], face["i"] = 3, [0, 1, 2]
    mesh = read_mesh(header.encode() + records.tobytes() + face.tobytes(), "b.ply")
    assert mesh.vertex_colors is not None
    np.testing.assert_array_equal(mesh.vertex_colors, UCHAR[:3])


def test_ply_without_colours_has_none() -> None:
    mesh = read_mesh(write_mesh(TETRA_VERTICES, TETRA_FACES, "ply"), "plain.ply")
    assert mesh.vertex_colors is None


def obj_text(colors: np.ndarray) -> str:
    rows = [
        f"v {' '.join(map(repr, point.tolist()))} {' '.join(map(repr, color.tolist()))}"
        for point, color in zip(TETRA_VERTICES, colors, strict=True)
    ]
    faces = [f"f {a} {b} {c}" for a, b, c in (TETRA_FACES + 1).tolist()]
    return "\n".join([*rows, *faces, ""])


def test_obj_vertex_colours_are_read_and_round_trip() -> None:
    colors = np.array([[0.1, 0.2, 0.3], [1.0, 0.0, 0.5], [1 / 3, 2 / 3, 1e-9], [0.0, 0.0, 0.0]])
    mesh = read_mesh(obj_text(colors).encode(), "c.obj")
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.float64
    np.testing.assert_array_equal(mesh.vertex_colors, colors)
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)
    data = write_mesh(mesh.vertices, mesh.faces, "obj", vertex_colors=mesh.vertex_colors)
    again = read_mesh(data, "again.obj")
    assert again.vertex_colors is not None
    assert again.vertex_colors.tobytes() == colors.tobytes()


def test_obj_without_colours_or_with_w_has_none() -> None:
    plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    weighted = "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n"
    mixed = "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n"
    for text in (plain, weighted, mixed):
        assert read_mesh(text.encode(), "x.obj").vertex_colors is None


def test_uchar_colours_go_to_obj_as_floats_between_0_and_1() -> None:
    data = write_mesh(TETRA_VERTICES, TETRA_FACES, "obj", vertex_colors=UCHAR)
    mesh = read_mesh(data, "x.obj")
    assert mesh.vertex_colors is not None
    np.testing.assert_array_equal(mesh.vertex_colors, UCHAR / 255.0)


def test_stl_holds_no_colours_and_says_so() -> None:
    plain = write_mesh(TETRA_VERTICES, TETRA_FACES, "stl")
    assert write_mesh(TETRA_VERTICES, TETRA_FACES, "stl", vertex_colors=UCHAR) == plain
    assert unkept("stl", UCHAR) == ["vertex colours (STL holds none)"]
    assert unkept("obj", FLOAT_RGBA) == ["vertex colour alpha (OBJ holds red, green and blue only)"]
    assert unkept("obj", UCHAR) == unkept("ply", FLOAT_RGBA) == unkept("stl", None) == []


def test_write_mesh_refuses_colours_of_the_wrong_shape() -> None:
    with pytest.raises(ValueError, match=r"shape \(4, 3\) or \(4, 4\)"):
        write_mesh(TETRA_VERTICES, TETRA_FACES, "ply", vertex_colors=UCHAR[:3])
    with pytest.raises(ValueError, match="shape"):
        write_mesh(TETRA_VERTICES, TETRA_FACES, "ply", vertex_colors=UCHAR[:, :2])


def test_build_keeps_the_colour_type_and_checks_the_shape() -> None:
    mesh = build("ply", TETRA_VERTICES, TETRA_FACES, source_faces=4, vertex_colors=UCHAR)
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.uint8
    assert not mesh.vertex_colors.flags.writeable
    assert UCHAR.flags.writeable  # the caller's array is not frozen
    with pytest.raises(AssertionError):
        build("ply", TETRA_VERTICES, TETRA_FACES, source_faces=4, vertex_colors=UCHAR[:2])
    assert build("ply", TETRA_VERTICES, TETRA_FACES, source_faces=4).vertex_colors is None


def test_meshlab_ply_colours_match_trimesh() -> None:
    mesh = read_mesh((DATA / "colors_meshlab.ply").read_bytes(), "colors_meshlab.ply")
    theirs = trimesh.load(DATA / "colors_meshlab.ply", process=False).visual.vertex_colors
    assert mesh.vertex_colors is not None and mesh.vertex_colors.shape == (845, 4)
    np.testing.assert_array_equal(mesh.vertex_colors, theirs)


def test_blender_ply_colours_after_texture_coordinates() -> None:
    mesh = read_mesh((DATA / "colors_blender.ply").read_bytes(), "colors_blender.ply")
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.uint8
    expected = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]  # the file's text
    assert mesh.vertex_colors.tolist() == expected


@pytest.mark.parametrize("name", ["colors_meshlab.ply", "colors_blender.ply"])
def test_real_ply_colours_round_trip(name: str) -> None:
    mesh = read_mesh((DATA / name).read_bytes(), name)
    assert mesh.vertex_colors is not None
    again = read_mesh(
        write_mesh(mesh.vertices, mesh.faces, "ply", vertex_colors=mesh.vertex_colors), name
    )
    assert again.vertex_colors is not None
    assert again.vertex_colors.tobytes() == mesh.vertex_colors.tobytes()
