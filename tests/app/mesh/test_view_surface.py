"""app/mesh/view_surface.py: the simplified surface the 3D view draws of a large mesh."""

from __future__ import annotations

import numpy as np
import pytest

from app.mesh.view_surface import display_surface


def sphere(rows: int, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed UV sphere of radius 1, wound outward: 2 * columns * (rows - 1) faces."""
    theta = np.linspace(0, np.pi, rows + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, columns, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.column_stack([np.sin(t.ravel()) * np.cos(p.ravel()),
                            np.sin(t.ravel()) * np.sin(p.ravel()), np.cos(t.ravel())])  # fmt: skip
    vertices = np.vstack([[0, 0, 1], ring, [0, 0, -1]])
    bottom = len(vertices) - 1
    at = 1 + np.arange(rows - 1)[:, None] * columns + np.arange(columns)
    right = 1 + np.arange(rows - 1)[:, None] * columns + (np.arange(columns) + 1) % columns
    faces = [np.column_stack([np.zeros(columns, int), at[0], right[0]])]
    for row in range(rows - 2):
        faces.append(np.column_stack([at[row], at[row + 1], right[row + 1]]))
        faces.append(np.column_stack([at[row], right[row + 1], right[row]]))
    faces.append(np.column_stack([at[-1], np.full(columns, bottom), right[-1]]))
    return vertices, np.concatenate(faces)


def outward(points: np.ndarray, faces: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Whether each face's normal points away from ``centre`` (a convex part wound outward)."""
    corners = points[faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return np.asarray(np.einsum("ij,ij->i", normal, corners.mean(axis=1) - centre) > 0)


@pytest.fixture(scope="module")
def ball() -> tuple[np.ndarray, np.ndarray]:
    return sphere(160, 320)  # 101,760 faces


def test_a_small_mesh_passes_through_unchanged() -> None:
    vertices, faces = sphere(8, 12)
    surface = display_surface(vertices, faces, np.array([3]), 20_000)
    assert surface.points is vertices or np.array_equal(surface.points, vertices)
    assert np.array_equal(surface.faces, faces)
    assert np.array_equal(surface.source, np.arange(len(faces)))
    assert not surface.simplified


def test_a_large_mesh_comes_near_the_target_with_every_kept_face(ball) -> None:  # type: ignore[no-untyped-def]
    vertices, faces = ball
    keep = np.arange(30_000, 30_600)  # a band of 600 faces: a patch, as problems mostly are
    surface = display_surface(vertices, faces, keep, 10_000)
    assert surface.simplified
    assert 9_000 <= len(surface.faces) <= 11_000
    # Every kept face is there, with its very corners, in the same order of corners.
    rows = np.flatnonzero(surface.source >= 0)
    assert np.array_equal(np.sort(surface.source[rows]), keep)
    kept_corners = surface.points[surface.faces[rows]]
    assert np.array_equal(kept_corners, vertices[faces[surface.source[rows]]])
    # The shape: the same bounding box, every point on the unit sphere, wound outward.
    assert np.allclose(surface.points.min(axis=0), vertices.min(axis=0), atol=0.01)
    assert np.allclose(surface.points.max(axis=0), vertices.max(axis=0), atol=0.01)
    assert np.allclose(np.linalg.norm(surface.points, axis=1), 1, atol=0.01)
    assert outward(surface.points, surface.faces, np.zeros(3)).mean() > 0.999
    assert np.isfinite(surface.points).all()
    assert surface.faces.max() < len(surface.points)


def test_the_seam_is_welded(ball) -> None:  # type: ignore[no-untyped-def]
    """Every edge of the result is shared by two faces: no crack between kept and simplified."""
    vertices, faces = ball
    surface = display_surface(vertices, faces, np.arange(50_000, 50_400), 8_000)
    sides = np.sort(surface.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, uses = np.unique(sides, axis=0, return_counts=True)
    assert (uses == 2).all()


def test_the_same_mesh_gives_the_same_surface(ball) -> None:  # type: ignore[no-untyped-def]
    vertices, faces = ball
    one = display_surface(vertices, faces, np.arange(100), 5_000)
    two = display_surface(vertices.copy(), faces.copy(), np.arange(100), 5_000)
    assert np.array_equal(one.points, two.points) and np.array_equal(one.faces, two.faces)


@pytest.mark.parametrize(
    ("scale", "offset"), [(1e-9, 0.0), (1e9, 0.0), (1.0, 1e7), (1e-6, -3e4), (1e200, 0.0)]
)
def test_tiny_huge_and_far_meshes_simplify_alike(scale: float, offset: float) -> None:
    vertices, faces = sphere(60, 120)  # 14,160 faces
    moved = vertices * scale + offset
    surface = display_surface(moved, faces, np.arange(10), 2_000)
    assert 1_700 <= len(surface.faces) <= 2_300
    assert np.isfinite(surface.points).all()
    back = (surface.points - offset) / scale
    assert np.allclose(np.linalg.norm(back, axis=1), 1, atol=0.02)
    assert np.allclose(surface.points.min(axis=0), moved.min(axis=0), rtol=0, atol=0.02 * scale)


def test_several_parts_all_stay() -> None:
    vertices, faces = sphere(40, 80)  # 6,240 faces each
    placed = [(1.0, (0, 0, 0)), (0.5, (5, 0, 0)), (2.0, (0, 9, 0))]
    parts = [(vertices * r + c, faces + i * len(vertices)) for i, (r, c) in enumerate(placed)]
    points = np.vstack([p for p, _ in parts])
    surface = display_surface(points, np.vstack([f for _, f in parts]), np.array([], int), 3_000)
    assert 2_700 <= len(surface.faces) <= 3_300
    for r, centre in [(1.0, (0, 0, 0)), (0.5, (5, 0, 0)), (2.0, (0, 9, 0))]:
        near = np.linalg.norm(surface.points - centre, axis=1)
        on = np.abs(near - r) < 0.02 * r
        assert on.sum() > 50, "each part keeps some points on its sphere"
    assert np.allclose(surface.points.min(axis=0), points.min(axis=0), atol=0.05)
    assert np.allclose(surface.points.max(axis=0), points.max(axis=0), atol=0.05)


def test_index_degenerate_faces_are_dropped_and_nan_refused() -> None:
    vertices, faces = sphere(60, 120)
    flat = np.array([[0, 0, 1], [5, 6, 5]])
    surface = display_surface(vertices, np.vstack([faces, flat]), np.array([], int), 2_000)
    f = surface.faces
    assert not ((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])).any()
    bad = vertices.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="finite"):
        display_surface(bad, faces, np.array([], int), 2_000)
