"""The 3D views' cameras (app.web.camera): the up axis, the scene's units and the framing,
against numbers worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.web.camera import FRAME_MARGIN, HALF_FIELD, Scene, cameras, framing, up_axis


def test_up_axis_comes_from_the_format() -> None:
    assert up_axis("glb") == up_axis("gltf") == "y"  # glTF: Y-up by its spec
    assert up_axis("obj") == "y"
    assert up_axis("stl") == up_axis("3mf") == up_axis("ply") == "z"
    assert up_axis("las") == up_axis("xyz") == up_axis("pcd") == "z"  # scans: the ground is x, y


def test_the_scene_divides_by_the_ranges_geometric_mean() -> None:
    # Ranges 4, 1 and 2: their geometric mean is 2, the middle (2, 0.5, 1).
    scene = Scene.of(np.array([[0.0, 0.0, 0.0], [4.0, 1.0, 2.0]]))
    assert scene.unit == pytest.approx(2.0)
    assert scene.middle.tolist() == [2.0, 0.5, 1.0]
    assert scene.radius == pytest.approx(math.sqrt(2**2 + 0.5**2 + 1**2) / 2)
    # A flat cloud: Plotly draws a range of zero as 2 wide.
    flat = Scene.of(np.array([[0.0, 0.0, 5.0], [8.0, 1.0, 5.0]]))
    assert flat.unit == pytest.approx(16 ** (1 / 3))
    assert flat.place(np.array([8.0, 1.0, 5.0])) == pytest.approx(
        {"x": round(4 / 16 ** (1 / 3), 5), "y": round(0.5 / 16 ** (1 / 3), 5), "z": 0.0}
    )


def test_framing_by_hand() -> None:
    # From -y looking at +y, z up: right is +x. A point 1 to the right is across 1 at depth 0,
    # so the camera stands focal * margin away, focal = 1 / tan(22.5°) = 1 + √2.
    direction, up = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    placed = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    assert framing(direction, up, placed) == pytest.approx((1 + math.sqrt(2)) * 1.15)
    # A point towards the camera needs no more than its depth (nothing across).
    assert framing(direction, up, np.array([[0.0, -3.0, 0.0]])) == pytest.approx(3.0)


def test_every_point_lands_within_the_margin_and_one_on_it() -> None:
    rng = np.random.default_rng(7)
    placed = rng.normal(size=(200, 3)) * [3.0, 1.0, 0.5]
    direction = np.array([1.25, -1.25, 0.9]) / np.linalg.norm([1.25, -1.25, 0.9])
    up = np.array([0.0, 0.0, 1.0])
    distance = framing(direction, up, placed)
    right = np.cross(-direction, up)
    right /= np.linalg.norm(right)
    upward = np.cross(right, -direction)
    depth = distance - placed @ direction
    across = np.maximum(np.abs(placed @ right), np.abs(placed @ upward)) / depth
    assert across.max() * FRAME_MARGIN == pytest.approx(math.tan(HALF_FIELD))


def test_cameras_look_from_each_up_axis_side_at_the_framed_distance() -> None:
    points = np.array([[0.0, 0.0, 0.0], [2.0, 2.0, 2.0]])
    scene = Scene.of(points)
    views = cameras(scene, points)
    assert set(views) == {"x", "y", "z"}
    for up, view in views.items():
        assert view["up"][up] == 1 and view["center"] == {"x": 0.0, "y": 0.0, "z": 0.0}
        eye = np.array([view["eye"][axis] for axis in "xyz"])
        assert eye["xyz".index(up)] < eye.max()  # from the side, a little above
        assert eye @ eye > 1.0  # outside the unit cube the scene is drawn in
