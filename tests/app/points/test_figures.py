"""The point-cloud view's pieces against numbers worked out by hand: the light, the shading,
the strokes' sample, the cameras, and how the diagnosis reads (app.points.page.verdict)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.points.figures import (
    NO_NORMAL,
    UNDECIDED,
    VIEW_NORMALS,
    light,
    shading,
    stroke_sample,
    view_figure,
)
from app.points.page import verdict
from mesh_normal.points.analysis import analyse_points


def sphere(count: int = 400) -> np.ndarray:
    rng = np.random.default_rng(5)
    points = rng.normal(size=(count, 3))
    return points / np.linalg.norm(points, axis=1, keepdims=True)  # type: ignore[no-any-return]


def test_the_light_is_over_the_cameras_shoulder() -> None:
    # z up: the camera's direction (1.25, -1.25, 0.9) / 1.98368 = (0.63014, -0.63014, 0.45370),
    # raised by 0.6 of z: (0.63014, -0.63014, 1.05370), of length 1.38002.
    assert light("z") == pytest.approx([0.45662, -0.45662, 0.76354], abs=1e-4)
    for up in "xyz":
        toward = light(up)
        assert np.linalg.norm(toward) == pytest.approx(1.0)
        assert int(np.argmax(toward)) == "xyz".index(up)  # more above than beside


def test_shading_is_lambert_on_one_side_and_either_way_when_the_side_is_unknown() -> None:
    normals = np.array(
        [
            [0.0, 0.0, 1.0],  # facing the light: 0.3 + 0.7 = 1
            [0.6, 0.0, 0.8],  # 0.3 + 0.7 * 0.8 = 0.86
            [1.0, 0.0, 0.0],  # edge on: the ambient 0.3
            [0.0, 0.0, -1.0],  # turned away: the ambient 0.3
            [0.0, 0.0, -1.0],  # turned away but not oriented: lit as a line, 1
            [0.0, 0.0, -1.0],  # side undecided: lit as a line, in the undecided range
            [0.0, 0.0, 0.0],  # no normal
        ]
    )
    valid = np.array([True] * 6 + [False])
    sided = np.array([True, True, True, True, False, False, False])
    undecided = np.array([False] * 5 + [True, False])
    codes = shading(normals, valid, sided, undecided, np.array([0.0, 0.0, 1.0]))
    assert codes == [100, 86, 30, 30, 100, UNDECIDED + 100, NO_NORMAL]


def test_strokes_are_few_spread_and_only_where_there_is_a_normal() -> None:
    shown = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]])
    valid = np.array([True, False, True, True])
    assert stroke_sample(shown, valid).tolist() == [0, 2, 3]
    line = np.stack([np.arange(5000.0), np.zeros(5000), np.zeros(5000)], axis=1)
    chosen = stroke_sample(line, np.ones(5000, dtype=bool), limit=10)
    assert 1 <= len(chosen) <= 10 and np.all(np.diff(chosen) > 0)
    # The first point of each of up to 10 cells along the line: evenly apart, end to end.
    assert chosen.min() == 0 and chosen.max() > 4000 and np.diff(chosen).max() < 1000
    assert not len(stroke_sample(shown, np.zeros(4, dtype=bool)))


def test_the_view_frames_the_cloud_for_each_up_axis_and_caps_the_strokes() -> None:
    points = sphere(2000) * [4.0, 1.0, 1.0] + [100.0, 0.0, 0.0]  # long in x, far from 0
    view = view_figure(analyse_points(points, k=12))
    assert view["strokes"] <= VIEW_NORMALS < view["shown"]
    assert len(view["figure"]["data"][1]["x"]) == 3 * view["strokes"]
    for up, camera in view["cameras"].items():
        assert camera["up"][up] == 1 and camera["center"] == {"x": 0.0, "y": 0.0, "z": 0.0}
        eye = np.array([camera["eye"][axis] for axis in "xyz"])
        # The scene is 4 by 1 by 1 in data units, 4**(2/3) by 4**(-1/3) by 4**(-1/3) in scene
        # units: the camera stands outside its bounding sphere, not nearer than the box's ends.
        assert np.linalg.norm(eye) > np.linalg.norm([4 ** (2 / 3), 4 ** (-1 / 3), 4 ** (-1 / 3)])
    # A sphere oriented outward: points facing the light are bright, the far side dark.
    codes = np.array(view["colors"]["light"]["z"]["color"])
    assert codes.max() >= 99 and codes.min() <= 31 and codes.max() < NO_NORMAL


def test_orient_none_lights_every_normal_as_a_line() -> None:
    # Oriented outward, the half of a sphere turned away from the light gets the ambient alone;
    # not oriented, a normal is lit either way: only those edge on to the light are that dark.
    oriented = view_figure(analyse_points(sphere(), k=12))["colors"]["light"]["z"]["color"]
    assert np.mean(np.array(oriented) <= 31) > 0.4
    view = view_figure(analyse_points(sphere(), k=12, orient="none"))
    codes = np.array(view["colors"]["light"]["z"]["color"])
    assert np.mean(codes <= 31) < 0.05
    assert {trace["name"] for trace in view["figure"]["data"][1:]} == {"normals, side not asked"}


def test_the_verdict_is_ok_only_when_nothing_was_found() -> None:
    report = analyse_points(sphere(), k=12).report
    assert verdict(report) == "ok"
    sharp = dataclasses.replace(report, counts=dataclasses.replace(report.counts, sharp=3))
    assert verdict(sharp) == "warn"  # each has its side's normal, but worth a look
    found = dataclasses.replace(report, diagnosis=["12 points have a normal whose side ..."])
    assert verdict(found) == "warn"
    # One point in ten without a normal is still a warning; more is an error.
    assert verdict(dataclasses.replace(report, with_normal=360)) == "warn"
    assert verdict(dataclasses.replace(report, with_normal=359)) == "error"
