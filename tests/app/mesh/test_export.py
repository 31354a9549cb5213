"""POST /api/mesh/export: the mesh with its normals, read back by trimesh."""

from __future__ import annotations

import io

import numpy as np
import trimesh
from fastapi.testclient import TestClient

from mesh_normal.files import read_mesh, write_mesh
from tests.meshes import TETRA_FACES, TETRA_VERTICES

#: One face turned inside out, so that the fix has something to do.
FLIPPED = np.array([TETRA_FACES[0][::-1], *TETRA_FACES[1:]])


def test_export_writes_glb_normals_and_names_what_stl_drops(client: TestClient) -> None:
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply")
    response = client.post(
        "/api/mesh/export?format=glb&normals=corner&winding=fix",
        files={"file": ("t.ply", data)},
    )
    assert response.status_code == 200, response.text
    assert response.headers["x-normals"] == "corner" and response.headers["x-faces-flipped"] == "1"
    assert 'filename="t-export.glb"' in response.headers["content-disposition"]
    scene = trimesh.load(io.BytesIO(response.content), file_type="glb", process=False)
    (mesh,) = scene.geometry.values()
    assert mesh.volume > 0 and len(mesh.vertices) == 12
    stl = client.post("/api/mesh/export?format=stl&normals=corner", files={"file": ("t.ply", data)})
    assert stl.headers["x-dropped"] == "corner normals (STL holds face normals only)"
    assert stl.headers["x-normals"] == "none" and stl.headers["x-faces-flipped"] == "0"
    flip = client.post("/api/mesh/export?format=ply&winding=flip", files={"file": ("t.ply", data)})
    assert read_mesh(flip.content, "f.ply").faces.tolist() == FLIPPED[:, [0, 2, 1]].tolist()
