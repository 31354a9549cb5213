"""The 3D view's figure: valid Plotly, the arrow along the unit normal, always drawable."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from typing import Any

import numpy as np
import plotly.graph_objects as go
import pytest

from app.calculator.payloads import normal_payload
from app.calculator.view3d import view3d_figure, view_space
from mesh_normal.triangle import triangle_normal

Point = tuple[float, float, float]

EXAMPLE = ((1.0, 0.0, 0.0), (0.0, 2.0, 0.0), (0.0, 0.0, 3.0))
CASES: dict[str, tuple[Point, Point, Point]] = {
    "example": EXAMPLE,
    "right": ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "thin": ((0.0, 0.0, 0.0), (10.0, 0.0, 0.0), (5.0, 0.3, 0.2)),
    "sliver far out": (
        (1e6, 1e6, 0.0),
        (1000003.0000000001, 1000003.0, 0.0),
        (1000003.0, 1000002.9999999999, 0.0),
    ),
    "huge": ((0.0, 0.0, 0.0), (1e200, 0.0, 0.0), (0.0, 1e200, 0.0)),
    "differences overflow": ((-1.7e308, 0.0, 0.0), (1.7e308, 1e308, 0.0), (0.0, -1.7e308, 1.7e308)),
    # As long as the double range and 1 wide: in view space an edge is subnormal (was a 500).
    "sliver as long as the range": ((-1e308, 0.0, 0.0), (1e308, 1.0, 0.0), (-1e308, 0.0, 1.0)),
    "tiny": ((0.0, 0.0, 0.0), (1e-300, 0.0, 0.0), (0.0, 0.0, 1e-300)),
    "subnormal": ((0.0, 0.0, 0.0), (5e-324, 0.0, 0.0), (0.0, 5e-324, 0.0)),
    "vertical": ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (-1.0, -1.0, 0.5)),
}
DEGENERATE: dict[str, tuple[Point, Point, Point]] = {
    "collinear": ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2.0, 2.0, 2.0)),
    "vertical line": ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 5.0)),
    "one point": ((1.0, 1.0, 1.0), (1.0, 1.0, 1.0), (1.0, 1.0, 1.0)),
    "huge line": ((-1.7e308, -1.7e308, 0.0), (0.0, 0.0, 0.0), (1.7e308, 1.7e308, 0.0)),
}
ALL = {**CASES, **DEGENERATE}


def payload_of(points: tuple[Point, Point, Point], swap: bool = False) -> dict[str, Any]:
    return normal_payload(triangle_normal(*points, swap_winding=swap))


def traces(figure: dict[str, Any], name: str, kind: str | None = None) -> list[dict[str, Any]]:
    return [
        trace
        for trace in figure["data"]
        if trace["name"] == name and (kind is None or trace["type"] == kind)
    ]


def only(figure: dict[str, Any], name: str, kind: str) -> dict[str, Any]:
    (trace,) = traces(figure, name, kind)
    return trace


def xyz(trace: dict[str, Any]) -> np.ndarray:
    return np.array([trace["x"], trace["y"], trace["z"]], dtype=float).T


def numbers(value: object) -> list[float]:
    if isinstance(value, dict):
        return [x for item in value.values() for x in numbers(item)]
    if isinstance(value, list):
        return [x for item in value for x in numbers(item)]
    return [value] if isinstance(value, float | int) and not isinstance(value, bool) else []


def exact_view(points: tuple[Point, Point, Point]) -> tuple[list[list[Fraction]], Fraction]:
    """The points minus their centroid, exactly, and their largest coordinate size."""
    exact = [[Fraction(x) for x in point] for point in points]
    centroid = [sum(column, Fraction(0)) / 3 for column in zip(*exact, strict=True)]
    offsets = [[x - c for x, c in zip(point, centroid, strict=True)] for point in exact]
    return offsets, max(abs(x) for point in offsets for x in point)


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("name", list(ALL))
def test_a_valid_plotly_figure_of_plain_finite_numbers(name: str, swap: bool) -> None:
    figure = view3d_figure(payload_of(ALL[name], swap))
    go.Figure(figure, skip_invalid=False)  # raises on anything Plotly does not know
    text = json.dumps(figure, allow_nan=False)
    assert json.loads(text) == figure  # plain lists and dicts only, no NumPy leftovers
    values = numbers(figure)
    assert all(math.isfinite(x) for x in values)
    coordinates = [x for trace in figure["data"] for axis in "xyzuvw" for x in trace.get(axis, [])]
    assert coordinates and max(abs(x) for x in coordinates) < 2**23


def test_the_traces_drawn_for_a_triangle() -> None:
    figure = view3d_figure(payload_of(EXAMPLE))
    kinds = {(trace["name"], trace["type"]) for trace in figure["data"]}
    assert kinds == {
        ("face", "mesh3d"),
        ("u", "scatter3d"),
        ("v", "scatter3d"),
        ("edge", "scatter3d"),
        ("normal", "scatter3d"),
        ("normal", "cone"),
        ("front", "scatter3d"),
        ("turn", "scatter3d"),
        ("turn", "cone"),
        ("corners", "scatter3d"),
        ("axes", "scatter3d"),
    }
    face = only(figure, "face", "mesh3d")
    assert (face["i"], face["j"], face["k"]) == ([0], [1], [2])
    assert face["color"] == "#4f5bd5" and 0 < face["opacity"] < 1
    corners = only(figure, "corners", "scatter3d")
    assert corners["marker"]["color"] == ["#c2410c", "#15803d", "#1d4ed8"]
    assert only(figure, "front", "scatter3d")["text"] == ["front"]
    layout = figure["layout"]
    assert layout["scene"]["aspectmode"] == "cube"
    assert layout["paper_bgcolor"] == "rgba(0,0,0,0)"
    assert layout["title"]["text"] == "Front: A → B → C counter-clockwise"


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("name", list(CASES))
def test_the_arrow_is_the_unit_normal_from_the_centroid(name: str, swap: bool) -> None:
    payload = payload_of(CASES[name], swap)
    figure = view3d_figure(payload)
    unit = np.array(payload["unit_normal"])
    cone = only(figure, "normal", "cone")
    head = np.array([cone["u"][0], cone["v"][0], cone["w"][0]])
    np.testing.assert_allclose(head / np.linalg.norm(head), unit, rtol=0, atol=1e-12)
    shaft = xyz(only(figure, "normal", "scatter3d"))
    assert shaft[0].tolist() == [0.0, 0.0, 0.0]  # the centroid
    np.testing.assert_allclose(shaft[1] / np.linalg.norm(shaft[1]), unit, rtol=0, atol=1e-12)
    tip = xyz(cone)[0]
    np.testing.assert_allclose(tip / np.linalg.norm(tip), unit, rtol=0, atol=1e-12)
    # Scaled to the triangle: 0.6 of its longest edge, in the view.
    corners = xyz(only(figure, "corners", "scatter3d"))
    longest = max(np.linalg.norm(corners[i] - corners[i - 1]) for i in range(3))
    assert np.linalg.norm(tip) == pytest.approx(0.6 * longest)


@pytest.mark.parametrize("name", list(CASES))
def test_swapping_the_winding_flips_the_arrow_and_the_turn(name: str) -> None:
    plain, swapped = (view3d_figure(payload_of(CASES[name], swap)) for swap in (False, True))
    for axis in "uvw":
        assert only(swapped, "normal", "cone")[axis] == [
            -x for x in only(plain, "normal", "cone")[axis]
        ]
    assert swapped["layout"]["title"]["text"] == "Front: A → C → B counter-clockwise"
    for figure in (plain, swapped):
        cone = only(figure, "normal", "cone")
        normal = np.array([cone["u"][0], cone["v"][0], cone["w"][0]])
        arc = xyz(only(figure, "turn", "scatter3d"))
        turning = np.cross(arc[1] - arc[0], arc[2] - arc[1])
        assert turning @ normal > 0  # counter-clockwise seen from the arrow's tip


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("name", list(ALL))
def test_the_corners_are_labelled_where_they_are(name: str, swap: bool) -> None:
    points = ALL[name]
    payload = payload_of(points, swap)
    figure = view3d_figure(payload)
    corners = only(figure, "corners", "scatter3d")
    assert corners["text"] == ["A", "B", "C"]
    offsets, extent = exact_view(points)
    drawn, exponent = view_space([list(point) for point in points])
    if extent and not Fraction(1, 2**20) <= extent <= 2**20:
        assert 1 <= extent / Fraction(2) ** exponent < 2
    else:
        assert exponent == 0
    expected = [[float(x / Fraction(2) ** exponent) for x in point] for point in offsets]
    assert xyz(corners).tolist() == expected == drawn.tolist()
    scaled = "scaled by 2" in corners["hovertext"][0]
    assert scaled == (exponent != 0)
    assert corners["hovertext"][0].startswith("A = (")
    if not payload["degenerate"]:
        winding = [0, 1, 2] if not swap else [0, 2, 1]
        assert xyz(only(figure, "face", "mesh3d")).tolist() == [expected[i] for i in winding]


@pytest.mark.parametrize("name", ["example", "right", "thin", "huge", "tiny", "vertical"])
def test_the_face_winding_matches_the_arrow(name: str) -> None:
    for swap in (False, True):
        payload = payload_of(CASES[name], swap)
        face = xyz(only(view3d_figure(payload), "face", "mesh3d"))
        normal = np.cross(face[1] - face[0], face[2] - face[0])
        assert normal @ np.array(payload["unit_normal"]) > 0


@pytest.mark.parametrize("name", list(CASES))
def test_the_camera_looks_at_the_front(name: str) -> None:
    for swap in (False, True):
        payload = payload_of(CASES[name], swap)
        eye = view3d_figure(payload)["layout"]["scene"]["camera"]["eye"]
        direction = np.array([eye["x"], eye["y"], eye["z"]])
        assert direction @ np.array(payload["unit_normal"]) > 0.5 * np.linalg.norm(direction)
        assert math.hypot(eye["x"], eye["y"]) > 0.1  # never straight down the turntable's axis


@pytest.mark.parametrize("name", list(DEGENERATE))
def test_a_degenerate_triangle_has_points_and_no_normal(name: str) -> None:
    payload = payload_of(DEGENERATE[name])
    assert payload["degenerate"]
    figure = view3d_figure(payload)
    assert figure["layout"]["title"]["text"] == "degenerate: no normal"
    assert not [trace for trace in figure["data"] if trace["type"] in ("cone", "mesh3d")]
    assert not traces(figure, "normal") and not traces(figure, "front")
    assert only(figure, "corners", "scatter3d")["text"] == ["A", "B", "C"]
    assert traces(figure, "u") and traces(figure, "v")


def test_hover_texts_give_the_true_values() -> None:
    figure = view3d_figure(payload_of(CASES["huge"]))
    assert only(figure, "corners", "scatter3d")["hovertext"][1].startswith("B = (1e+200, 0, 0)")
    assert "u = B − A = (1e+200, 0, 0)" in only(figure, "u", "scatter3d")["hovertemplate"]
    assert "unit normal (0, 0, 1)" in only(figure, "normal", "cone")["hovertemplate"]
    assert "area out of range" in only(figure, "face", "mesh3d")["hovertemplate"]
    overflow = view3d_figure(payload_of(CASES["differences overflow"]))
    assert "out of range" in only(overflow, "u", "scatter3d")["hovertemplate"]


def test_view_space_never_overflows() -> None:
    big = 1.7e308
    assert math.isinf(-big - (-big + big + big) / 3)  # A minus the centroid, in floats
    points, exponent = view_space([[-big, 0.0, 0.0], [big, 0.0, 0.0], [big, 0.0, 0.0]])
    assert exponent == 1024  # the largest offset, about 2.27e308, is past the double range
    third = Fraction(big) / 3
    expected = [float(x / Fraction(2) ** 1024) for x in (-4 * third, 2 * third, 2 * third)]
    assert points[:, 0].tolist() == expected
    assert 1 <= abs(expected[0]) < 2
