"""app/mesh/view_normals.py: the face, vertex and corner normals the page can draw as arrows."""

from __future__ import annotations

import json

import numpy as np

from app.mesh import view_normals
from app.mesh.view_normals import normal_pools
from tests.app.mesh.test_view_surface import sphere


def cube() -> tuple[np.ndarray, np.ndarray]:
    """The unit cube [0, 1]^3, 12 faces wound outward."""
    vertices = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    sides = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1]]
    sides += [[2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    faces = np.array(sides)
    return vertices, faces


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    corners = vertices[faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_the_cube_offers_every_face_vertex_and_corner_normal() -> None:
    vertices, faces = cube()
    flipped = np.zeros(12, dtype=bool)
    flipped[4] = True
    pools = normal_pools(vertices, faces, face_normals(vertices, faces), flipped, vertices,
                         np.arange(8) + 100)  # fmt: skip
    face, vertex, corner = pools["face"], pools["vertex"], pools["corner"]
    assert len(face["at"]) == 12 and len(vertex["at"]) == 8 and len(corner["at"]) == 36
    assert sum(face["flipped"]) == 1 and face["flipped"][face["label"].index("face 4")]
    # A cube's vertex normal points from the centre to the corner (angle-weighted: exactly).
    for at, normal in zip(vertex["at"], vertex["normal"], strict=True):
        expected = (np.array(at) - 0.5) / np.linalg.norm(np.array(at) - 0.5)
        assert np.allclose(normal, expected, atol=1e-5)
    assert all(label.startswith("vertex 10") for label in vertex["label"])
    # With a 30° crease each corner keeps its face's own normal: an axis.
    assert all(sorted(np.abs(n)) == [0, 0, 1] for n in corner["normal"])
    # A corner arrow starts inside its face (a fifth of the way to the centroid): on one side
    # of the cube, off its edges.
    assert all(np.isin(at, [0.0, 1.0]).sum() == 1 for at in corner["at"])
    json.dumps(pools, allow_nan=False)


def test_pools_are_capped_fixed_and_corners_left_out_for_huge_meshes(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    vertices, faces = sphere(40, 80)  # 6,240 faces, 3,122 vertices
    args = (vertices, faces, face_normals(vertices, faces), np.zeros(len(faces), bool), vertices,
            np.arange(len(vertices)))  # fmt: skip
    one = normal_pools(*args)
    assert len(one["face"]["at"]) == len(one["vertex"]["at"]) == view_normals.POOL
    assert one == normal_pools(*args)
    monkeypatch.setattr(view_normals, "CORNER_FACES", 1_000)
    assert normal_pools(*args)["corner"] is None
