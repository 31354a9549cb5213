from __future__ import annotations

import numpy as np
import pytest
import trimesh

from mesh_normal.files import MeshFileError, read_mesh


def scene() -> trimesh.Scene:
    result = trimesh.Scene()
    result.add_geometry(
        trimesh.creation.box(),
        node_name="box",
        transform=trimesh.transformations.translation_matrix([5, 0, 0]),
    )
    result.add_geometry(
        trimesh.creation.icosphere(1), node_name="ball", transform=np.diag([2.0, 1, 1, 1])
    )
    return result


@pytest.mark.parametrize("file_format", ["glb", "gltf"])
def test_primitives_joined_with_transforms(file_format: str) -> None:
    source = scene()
    if file_format == "glb":
        data = source.export(file_type="glb", include_normals=True)
    else:
        data = source.export(file_type="gltf", embed_buffers=True, include_normals=True)[
            "model.gltf"
        ]
    mesh = read_mesh(data, f"scene.{file_format}")
    assert mesh.format == file_format
    expected = source.to_geometry()
    assert len(mesh.vertices) == len(expected.vertices) and len(mesh.faces) == len(expected.faces)
    np.testing.assert_allclose(np.sort(mesh.vertices, axis=0), np.sort(expected.vertices, axis=0))
    assert mesh.vertices[:, 0].max() == pytest.approx(5.5)  # the box moved, the ball stretched
    assert mesh.file_vertex_normals is not None
    np.testing.assert_allclose(np.linalg.norm(mesh.file_vertex_normals, axis=1), 1)
    assert "Joined 2 primitives with their node transforms applied." in mesh.notes


def test_mirroring_node_reverses_winding() -> None:
    source = trimesh.Scene()
    source.add_geometry(trimesh.creation.box(), node_name="box", transform=np.diag([-1.0, 1, 1, 1]))
    mesh = read_mesh(source.export(file_type="glb"), "m.glb")
    assert trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).volume > 0
    assert any("Reversed the winding" in note for note in mesh.notes)


def test_external_buffers_are_named() -> None:
    data = (
        b'{"asset": {"version": "2.0"}, "buffers": [{"uri": "model.bin", '
        b'"byteLength": 12}], "meshes": []}'
    )
    with pytest.raises(MeshFileError):
        read_mesh(data, "x.gltf")
