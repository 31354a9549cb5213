"""export_mesh and the writers' normals, read back by trimesh and by our readers."""

from __future__ import annotations

import io

import numpy as np
import pytest
import trimesh

from mesh_normal.files import read_mesh, write_mesh
from mesh_normal.files.glb_write import split_vertices
from mesh_normal.files.rewrite import export_mesh
from mesh_normal.mesh.corners import corner_normals
from mesh_normal.mesh.vertices import vertex_normals
from tests.meshes import TETRA_FACES, TETRA_VERTICES

FLIPPED = TETRA_FACES[:, [0, 2, 1]]


def tetra(suffix: str = "obj", faces: np.ndarray = TETRA_FACES) -> bytes:
    return write_mesh(TETRA_VERTICES, faces, suffix)


def test_obj_vertex_normals_read_back_by_trimesh() -> None:
    normals = vertex_normals(TETRA_VERTICES, TETRA_FACES).normals
    data = write_mesh(TETRA_VERTICES, TETRA_FACES, "obj", normals=normals, normals_kind="vertex")
    assert data.count(b"\nvn ") == 4
    loaded = trimesh.load(io.BytesIO(data), file_type="obj", process=False)
    np.testing.assert_allclose(loaded.vertex_normals, normals, atol=1e-12)
    again = read_mesh(data, "t.obj")
    np.testing.assert_array_equal(again.file_vertex_normals, normals)


def test_glb_corner_normals_split_vertices_and_read_back_by_trimesh() -> None:
    # A tetrahedron's edges are all sharper than 30 degrees: every corner is its face's.
    corners = corner_normals(TETRA_VERTICES, TETRA_FACES).normals
    data = write_mesh(TETRA_VERTICES, TETRA_FACES, "glb", normals=corners, normals_kind="corner")
    scene = trimesh.load(io.BytesIO(data), file_type="glb", process=False)
    (mesh,) = scene.geometry.values()
    assert len(mesh.vertices) == 12 and len(mesh.faces) == 4  # three sides a vertex
    np.testing.assert_allclose(mesh.vertex_normals[mesh.faces], corners, atol=1e-6)
    np.testing.assert_allclose(mesh.vertices[mesh.faces], TETRA_VERTICES[TETRA_FACES], atol=1e-6)


def test_split_vertices_keeps_shared_normals_one_vertex() -> None:
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    same = np.tile([0.0, 0.0, 1.0], (2, 1))
    source, split, normals = split_vertices(faces, same, "face")
    assert source.tolist() == [0, 1, 2, 3] and split.tolist() == faces.tolist()
    assert normals.tolist() == [[0.0, 0.0, 1.0]] * 4


def test_ply_face_normals_read_back() -> None:
    result = export_mesh(read_mesh(tetra("ply"), "t.ply"), "ply", normals="face")
    again = read_mesh(result.data, "t.ply")
    assert again.file_face_normals is not None and result.normals_kind == "face"
    loaded = trimesh.load(io.BytesIO(result.data), file_type="ply", process=False)
    assert len(loaded.faces) == 4


def test_flip_reverses_every_face_and_the_normals_follow() -> None:
    mesh = read_mesh(tetra(), "t.obj")
    kept = export_mesh(mesh, "obj", normals="vertex")
    flipped = export_mesh(mesh, "obj", normals="vertex", winding="flip")
    assert flipped.faces_flipped == 4 and kept.faces_flipped == 0
    before = read_mesh(kept.data, "k.obj").file_vertex_normals
    after = read_mesh(flipped.data, "f.obj").file_vertex_normals
    assert before is not None and after is not None
    np.testing.assert_allclose(after, -before, atol=1e-12)


def test_fix_keeps_the_kind_of_normals_the_file_had() -> None:
    mesh = read_mesh(tetra("ply", FLIPPED), "t.ply")
    plain = export_mesh(mesh, "ply", winding="fix")
    assert plain.normals_kind is None and plain.faces_flipped == 4
    with_normals = write_mesh(
        TETRA_VERTICES,
        FLIPPED,
        "ply",
        normals=vertex_normals(TETRA_VERTICES, FLIPPED).normals,
        normals_kind="vertex",
    )
    fixed = export_mesh(read_mesh(with_normals, "n.ply"), "ply", winding="fix")
    assert fixed.normals_kind == "vertex" and "vertex normals (recomputed)" in fixed.kept
    again = read_mesh(fixed.data, "f.ply")
    assert again.file_vertex_normals is not None
    outward = vertex_normals(TETRA_VERTICES, TETRA_FACES).normals
    np.testing.assert_allclose(again.file_vertex_normals, outward, atol=1e-12)


def test_what_a_format_cannot_hold_is_named() -> None:
    mesh = read_mesh(tetra(), "t.obj")
    assert export_mesh(mesh, "stl", normals="corner").dropped == (
        "corner normals (STL holds face normals only)",
    )
    assert export_mesh(mesh, "off", normals="face").dropped == (
        "face normals (OFF holds vertex normals only)",
    )
    assert export_mesh(mesh, "glb", normals="corner").dropped == ()


def test_obj_groups_are_kept_and_texture_coordinates_named() -> None:
    text = (
        "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nusemtl red\n"
        "o one\nf 1 3 2\nf 1 2 4\ng lid\nf 1 4 3\nf 2 3 4\n"
    )
    mesh = read_mesh(text.encode(), "g.obj")
    result = export_mesh(mesh, "obj")
    again = read_mesh(result.data, "again.obj")
    assert again.group_names == mesh.group_names == ("one", "one/lid")
    assert again.face_groups is not None and mesh.face_groups is not None
    assert again.face_groups.tolist() == mesh.face_groups.tolist()
    assert result.dropped == (
        "texture coordinates (1 vt)",
        "material libraries (1 mtllib)",
        "materials (1 usemtl)",
    )


def test_off_round_trips_colours_and_normals() -> None:
    colors = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]], dtype=np.uint8)
    normals = vertex_normals(TETRA_VERTICES, TETRA_FACES).normals
    data = write_mesh(
        TETRA_VERTICES,
        TETRA_FACES,
        "off",
        vertex_colors=colors,
        normals=normals,
        normals_kind="vertex",
    )
    again = read_mesh(data, "t.off")
    assert again.vertex_colors is not None
    assert again.vertex_colors.tolist() == colors.tolist()
    np.testing.assert_array_equal(again.file_vertex_normals, normals)
    np.testing.assert_array_equal(again.vertices, TETRA_VERTICES)


def test_normals_of_an_ambiguous_shape_need_their_kind() -> None:
    square = np.zeros((3, 3))
    with pytest.raises(ValueError, match="normals_kind"):
        write_mesh(np.eye(3), [[0, 1, 2], [0, 2, 1], [1, 2, 0]], "obj", normals=square)
