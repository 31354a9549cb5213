"""Colours: vertex colours read from PLY and OBJ, face colours from PLY, written back where the
format holds them (and through the fix), named where dropped."""

from __future__ import annotations

import struct

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.files import LoadedMesh, read_mesh, write_mesh
from mesh_normal.files.loaded import build
from mesh_normal.files.write import unkept
from mesh_normal.mesh.orientation import orient
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


# --- face colours ---------------------------------------------------------------------------

#: A square (a quad) and a pyramid tip (two triangles), as in a PLY file's face element.
SQUARE_TIP = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1]])
POLYGONS = [[0, 1, 2, 3], [0, 4, 1], [1, 4, 2]]
POLYGON_COLORS = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255]], dtype=np.uint8)


def ply_face_colors(encoding: str, colors: np.ndarray, kind: str) -> bytes:
    """PLY with ``red green blue [alpha]`` on its faces, after the corners and a normal."""
    names = ["red", "green", "blue", "alpha"][: colors.shape[1]]
    header = "\n".join(
        [
            "ply",
            f"format {encoding} 1.0",
            f"element vertex {len(SQUARE_TIP)}",
            *(f"property double {axis}" for axis in "xyz"),
            f"element face {len(POLYGONS)}",
            "property list uchar int vertex_indices",
            "property float nz",
            *(f"property {kind} {name}" for name in names),
            "end_header\n",
        ]
    ).encode()
    if encoding == "ascii":
        rows = "".join(" ".join(map(repr, point)) + "\n" for point in SQUARE_TIP.tolist())
        rows += "".join(
            f"{len(p)} {' '.join(map(str, p))} 1 {' '.join(map(repr, c))}\n"
            for p, c in zip(POLYGONS, colors.tolist(), strict=True)
        )
        return header + rows.encode()
    end = ">" if encoding == "binary_big_endian" else "<"
    body = SQUARE_TIP.astype(end + "f8").tobytes()
    item = np.dtype(colors.dtype).newbyteorder(end)
    for polygon, color in zip(POLYGONS, colors, strict=True):
        body += struct.pack(f"{end}B{len(polygon)}if", len(polygon), *polygon, 1.0)
        body += color.astype(item).tobytes()
    return header + body


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
@pytest.mark.parametrize(
    ("colors", "kind"),
    [
        (POLYGON_COLORS, "uchar"),
        (np.array([[1, 0, 0, 1], [0, 0.5, 0, 1], [0, 0, 1, 0.25]], dtype=np.float32), "float"),
    ],
    ids=["uchar", "float-rgba"],
)
def test_ply_face_colours_follow_each_polygons_triangles(
    encoding: str, colors: np.ndarray, kind: str
) -> None:
    mesh = read_mesh(ply_face_colors(encoding, colors, kind), "f.ply")
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3], [0, 4, 1], [1, 4, 2]])
    assert mesh.face_colors is not None and mesh.face_colors.dtype == colors.dtype
    np.testing.assert_array_equal(mesh.face_colors, colors[[0, 0, 1, 2]])  # the quad's twice
    assert not mesh.face_colors.flags.writeable
    assert mesh.vertex_colors is None


def test_ply_face_colours_round_trip_bit_for_bit() -> None:
    colors = np.array([[0.1, 0.2, 0.3, 1.0], [1 / 3, 0, 1, 0.5], [0, 0, 0, 0], [1, 1, 1, 1]])
    data = write_mesh(TETRA_VERTICES, TETRA_FACES, "ply", face_colors=colors, vertex_colors=UCHAR)
    header = data[: data.index(b"end_header")].decode()
    assert header.endswith(
        "property double red\nproperty double green\nproperty double blue\nproperty double alpha\n"
    )
    again = read_mesh(data, "again.ply")
    assert again.face_colors is not None and again.face_colors.tobytes() == colors.tobytes()
    assert again.vertex_colors is not None and again.vertex_colors.tobytes() == UCHAR.tobytes()


def test_face_colours_are_named_where_dropped() -> None:
    assert unkept("stl", None, POLYGON_COLORS) == ["face colours (STL holds none)"]
    assert unkept("obj", UCHAR, POLYGON_COLORS) == ["face colours (OBJ holds none)"]
    assert unkept("stl", FLOAT_RGBA, POLYGON_COLORS) == [
        "vertex colours (STL holds none)",
        "face colours (STL holds none)",
    ]
    assert unkept("ply", FLOAT_RGBA, FLOAT_RGBA) == []
    plain = write_mesh(TETRA_VERTICES, TETRA_FACES, "obj")
    assert write_mesh(TETRA_VERTICES, TETRA_FACES, "obj", face_colors=UCHAR) == plain


def test_write_mesh_refuses_face_colours_of_the_wrong_shape() -> None:
    with pytest.raises(ValueError, match=r"face_colors must have shape \(4, 3\) or \(4, 4\)"):
        write_mesh(TETRA_VERTICES, TETRA_FACES, "ply", face_colors=UCHAR[:3])


def test_build_checks_the_face_colours() -> None:
    mesh = build("off", TETRA_VERTICES, TETRA_FACES, source_faces=4, face_colors=UCHAR)
    assert mesh.face_colors is not None and mesh.face_colors.dtype == np.uint8
    with pytest.raises(AssertionError, match="for 4 triangles"):
        build("off", TETRA_VERTICES, TETRA_FACES, source_faces=4, face_colors=UCHAR[:2])


def fixed_ply(mesh: LoadedMesh) -> tuple[LoadedMesh, np.ndarray]:
    """The mesh read, oriented by the fix, written as PLY and read again; and the fix's flips."""
    fixed = orient(mesh.checked())
    data = write_mesh(
        mesh.vertices,
        fixed.faces,
        "ply",
        vertex_colors=mesh.vertex_colors,
        face_colors=mesh.face_colors,
    )
    return read_mesh(data, "fixed.ply"), fixed.flipped


#: The tetrahedron with its first face turned inside out, each face its own colour.
FLIPPED = np.array([TETRA_FACES[0][::-1], *TETRA_FACES[1:]])


def test_the_fix_keeps_each_face_its_colour() -> None:
    """Flipping a face reverses its corners in its own row: the rows stay in order."""
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=FLOAT_RGBA, face_colors=UCHAR)
    mesh = read_mesh(data, "flipped.ply")
    again, flipped = fixed_ply(mesh)
    assert flipped.tolist() == [True, False, False, False]
    turns = [np.roll(TETRA_FACES[0], k).tolist() for k in range(3)]
    assert again.faces[0].tolist() in turns  # the flipped face, back in place
    np.testing.assert_array_equal(again.faces[1:], FLIPPED[1:])  # the others untouched
    assert again.face_colors is not None and again.face_colors.tobytes() == UCHAR.tobytes()
    assert again.vertex_colors is not None
    assert again.vertex_colors.tobytes() == FLOAT_RGBA.tobytes()


@pytest.mark.parametrize(
    "name",
    [
        "off_face_colors.off",
        "off_whitespace.off",
        "gltf/cube_vertex_colors.glb",
        "threemf_basematerials.3mf",
        "colors_meshlab.ply",
    ],
)
def test_real_files_colours_survive_the_fix(name: str) -> None:
    mesh = read_mesh((DATA / name).read_bytes(), name)
    again, _ = fixed_ply(mesh)
    for before, after in (
        (mesh.vertex_colors, again.vertex_colors),
        (mesh.face_colors, again.face_colors),
    ):
        assert (before is None) == (after is None)
        if before is not None and after is not None:
            assert after.dtype == before.dtype and after.tobytes() == before.tobytes()
    assert mesh.vertex_colors is not None or mesh.face_colors is not None


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.integers(3, 7), min_size=1, max_size=8),
    st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]),
    st.integers(0, 2**32 - 1),
)
def test_every_triangle_has_its_polygons_colour(sizes: list[int], encoding: str, seed: int) -> None:
    """Convex polygons of any size in a row: triangle i of polygon p has p's colour, in file
    order, and the colours survive a PLY round trip bit for bit."""
    rng = np.random.default_rng(seed)
    colors = rng.integers(0, 256, size=(len(sizes), 4)).astype(np.uint8)
    points, polygons = [], []
    for size in sizes:  # each polygon its own regular polygon on z = len(polygons)
        angles = 2 * np.pi * np.arange(size) / size
        polygons.append(list(range(len(points), len(points) + size)))
        points += [(float(np.cos(a)), float(np.sin(a)), float(len(polygons))) for a in angles]
    header = (
        f"ply\nformat {encoding} 1.0\nelement vertex {len(points)}\nproperty double x\n"
        "property double y\nproperty double z\n"
        f"element face {len(polygons)}\nproperty list uchar int vertex_indices\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
        "end_header\n"
    ).encode()
    if encoding == "ascii":
        body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in points) + "".join(
            f"{len(p)} {' '.join(map(str, p))} {' '.join(map(str, c))}\n"
            for p, c in zip(polygons, colors.tolist(), strict=True)
        )
        data = header + body.encode()
    else:
        end = ">" if encoding == "binary_big_endian" else "<"
        data = header + np.array(points, dtype=end + "f8").tobytes()
        for polygon, color in zip(polygons, colors, strict=True):
            data += struct.pack(f"{end}B{len(polygon)}i", len(polygon), *polygon)
            data += color.tobytes()
    mesh = read_mesh(data, "p.ply")
    expected = np.repeat(colors, [size - 2 for size in sizes], axis=0)
    assert mesh.face_colors is not None
    np.testing.assert_array_equal(mesh.face_colors, expected)
    again = read_mesh(write_mesh(mesh.vertices, mesh.faces, "ply", face_colors=mesh.face_colors))
    assert again.face_colors is not None and again.face_colors.tobytes() == expected.tobytes()
