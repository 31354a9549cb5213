"""The 3D view's figure: valid Plotly, the arrow along the unit normal, always drawable."""

from __future__ import annotations

import contextlib
import json
import math
import random
import subprocess
import sys
from collections.abc import Iterator
from fractions import Fraction
from typing import Any
from unittest import mock

import numpy as np
import plotly.graph_objects as go
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.calculator import view3d
from app.calculator.calculation import calculation_payload, from_doubles
from app.calculator.payloads import normal_payload
from app.calculator.view3d import view3d_figure, view_space
from mesh_normal.triangle.normal import triangle_normal
from tests.app.calculator import _view3d_numpy as reference
from tests.paths import ROOT

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
    # As long as the double range and 1 wide: in view space an edge is subnormal (not a 500).
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
    assert xyz(corners).tolist() == expected == [list(point) for point in drawn]
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
    assert [point[0] for point in points] == expected
    assert 1 <= abs(expected[0]) < 2


# --- The same figure as the former NumPy module (tests/app/calculator/_view3d_numpy.py) -------


def _numpy_dot_rounding() -> str | None:
    """How NumPy's dot of two 3-vectors rounds on this machine.

    "fused": each product added to the sum with one rounding (OpenBLAS with FMA, what
    view3d does); "plain": each product rounded, then each sum; None: neither.
    """
    rng = random.Random(0)
    fused = plain = True
    for _ in range(200):
        a = [rng.uniform(-1, 1) * 2.0 ** rng.randint(-20, 20) for _ in range(3)]
        b = [rng.uniform(-1, 1) * 2.0 ** rng.randint(-20, 20) for _ in range(3)]
        got = float(np.dot(np.array(a), np.array(b)))
        total = Fraction(a[0] * b[0])
        for x, y in zip(a[1:], b[1:], strict=True):
            total = Fraction(float(total + Fraction(x) * Fraction(y)))
        fused &= got == float(total)
        plain &= got == a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    return "fused" if fused else "plain" if plain else None


NUMPY_DOT = _numpy_dot_rounding()
needs_known_rounding = pytest.mark.skipif(
    NUMPY_DOT is None, reason="NumPy's dot rounds neither fused nor plain here"
)


@contextlib.contextmanager
def numpy_rounding() -> Iterator[None]:
    """view3d, rounding as NumPy does here (the same already, where NumPy fuses its dots)."""
    angles = np.linspace(0.35, 0.35 + 1.5 * np.pi, 40)
    with contextlib.ExitStack() as stack:
        if NUMPY_DOT == "plain":
            stack.enter_context(mock.patch.object(view3d, "_fma", lambda a, b, c: a * b + c))
        # NumPy's cos and sin may be its own SIMD ones: the reference uses those.
        stack.enter_context(mock.patch.object(view3d, "TURN_COS", np.cos(angles).tolist()))
        stack.enter_context(mock.patch.object(view3d, "TURN_SIN", np.sin(angles).tolist()))
        yield


def assert_same(new: object, old: object, path: str = "figure") -> None:
    """Equal structure, strings, ints and bools; floats within 4 ulp, zeros exactly (sign too)."""
    assert type(new) is type(old), f"{path}: {type(new).__name__} is not {type(old).__name__}"
    if isinstance(old, dict):
        assert isinstance(new, dict)
        assert list(new) == list(old), f"{path}: keys {list(new)} are not {list(old)}"
        for key, value in old.items():
            assert_same(new[key], value, f"{path}.{key}")
    elif isinstance(old, list):
        assert isinstance(new, list)
        assert len(new) == len(old), f"{path}: {len(new)} items, not {len(old)}"
        for index, (mine, theirs) in enumerate(zip(new, old, strict=True)):
            assert_same(mine, theirs, f"{path}[{index}]")
    elif isinstance(old, float):
        assert isinstance(new, float)
        if new == 0 or old == 0 or not math.isfinite(old):
            assert (new, math.copysign(1.0, new)) == (old, math.copysign(1.0, old)), path
        else:
            assert abs(new - old) <= 4 * math.ulp(max(abs(new), abs(old))), (
                f"{path}: {new!r} {old!r}"
            )
    else:
        assert new == old, f"{path}: {new!r} is not {old!r}"


def assert_same_figure(points: tuple[Point, Point, Point], swap: bool) -> None:
    payload = payload_of(points, swap)
    with numpy_rounding():
        figure = view3d_figure(payload)
    assert_same(figure, reference.view3d_figure(payload))


#: Any double; within 1e-300..1e300 and signed; small; small integers.
ANY = st.floats(allow_nan=False, allow_infinity=False)
WIDE = st.builds(
    lambda sign, digits, power: sign * digits * 10.0**power,
    st.sampled_from([-1.0, 1.0]),
    st.floats(1.0, 9.999),
    st.integers(-300, 299),
)
SMALL = st.floats(-10.0, 10.0)
WHOLE = st.integers(-5, 5).map(float)
COORDINATE = st.one_of(SMALL, WHOLE, WIDE, ANY)
POINT = st.tuples(COORDINATE, COORDINATE, COORDINATE)
SMALL_POINT = st.tuples(SMALL, SMALL, SMALL)


@st.composite
def scaled_triangles(draw: st.DrawFn) -> tuple[Point, Point, Point]:
    """An ordinary triangle times 10**k, k in -300..300: huge or tiny, with its shape."""
    power = 10.0 ** draw(st.integers(-300, 300))
    a, b, c = (draw(SMALL_POINT) for _ in range(3))
    return (
        (a[0] * power, a[1] * power, a[2] * power),
        (b[0] * power, b[1] * power, b[2] * power),
        (c[0] * power, c[1] * power, c[2] * power),
    )


@st.composite
def collinear_triangles(draw: st.DrawFn) -> tuple[Point, Point, Point]:
    """A, A + j d and A + k d in integers times 2**e: exactly on a line (or one point)."""
    exponent = draw(st.integers(-1000, 1000))
    start = [draw(st.integers(-1000, 1000)) for _ in range(3)]
    step = [draw(st.integers(-50, 50)) for _ in range(3)]
    counts = [0, draw(st.integers(-3, 3)), draw(st.integers(-3, 3))]
    a, b, c = (
        tuple(math.ldexp(x + count * d, exponent) for x, d in zip(start, step, strict=True))
        for count in draw(st.permutations(counts))
    )
    return a, b, c  # type: ignore[return-value]


@st.composite
def coincident_triangles(draw: st.DrawFn) -> tuple[Point, Point, Point]:
    """Two corners at one point (any two), or all three."""
    point, other = draw(POINT), draw(POINT)
    corners = [(point, point, other), (point, other, point), (other, point, point)]
    return draw(st.sampled_from([*corners, (point, point, point)]))


@st.composite
def far_slivers(draw: st.DrawFn) -> tuple[Point, Point, Point]:
    """Corners a few hundred ulps apart, 1e3 to 1e15 from the origin: slivers and specks."""
    base = [
        draw(st.sampled_from([-1.0, 1.0])) * 10.0 ** draw(st.floats(3.0, 15.0)) for _ in range(3)
    ]
    steps = st.integers(-500, 500)
    a, b, c = (tuple(x + draw(steps) * math.ulp(x) for x in base) for _ in range(3))
    return a, b, c  # type: ignore[return-value]


TRIANGLES = st.one_of(
    st.tuples(SMALL_POINT, SMALL_POINT, SMALL_POINT),
    st.tuples(POINT, POINT, POINT),
    scaled_triangles(),
    collinear_triangles(),
    coincident_triangles(),
    far_slivers(),
)


@needs_known_rounding
@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("name", list(ALL))
def test_the_figure_is_the_numpy_modules(name: str, swap: bool) -> None:
    assert_same_figure(ALL[name], swap)


@needs_known_rounding
@settings(max_examples=400, deadline=None)
@given(TRIANGLES, st.booleans())
def test_the_figure_is_the_numpy_modules_for_any_triangle(
    points: tuple[Point, Point, Point], swap: bool
) -> None:
    assert_same_figure(points, swap)


@needs_known_rounding
def test_the_pages_payload_draws_the_numpy_modules_figure() -> None:
    """The page's own payload (exact forms, plane and all), not just the normal's."""
    payload = calculation_payload(from_doubles(*(list(point) for point in EXAMPLE)))
    with numpy_rounding():
        figure = view3d_figure(payload)
    assert_same(figure, reference.view3d_figure(payload))


def test_the_turn_angles_are_numpys_linspace() -> None:
    angles = np.linspace(0.35, 0.35 + 1.5 * np.pi, 40)
    assert [x.hex() for x in view3d.TURN_ANGLES] == [float(x).hex() for x in angles]
    for ours, numpys in ((view3d.TURN_COS, np.cos(angles)), (view3d.TURN_SIN, np.sin(angles))):
        assert all(abs(x - y) <= math.ulp(y) for x, y in zip(ours, numpys.tolist(), strict=True))


@given(st.one_of(st.floats(-1.4, 1.4), st.floats(allow_nan=False, max_value=1e12, min_value=-1e12)))
def test_the_camera_eye_rounds_as_numpy_rounds(x: float) -> None:
    """np.round(x, 4) is rint(x * 10**4) / 10**4, which round(x, 4) is not always."""
    ours, numpys = view3d._round4(x), float(np.round(x, 4))
    assert (ours, math.copysign(1.0, ours)) == (numpys, math.copysign(1.0, numpys))


@needs_known_rounding
@given(st.tuples(ANY, ANY, ANY), st.tuples(ANY, ANY, ANY))
def test_dot_products_round_as_numpys(a: Point, b: Point) -> None:
    with numpy_rounding():
        ours, length = view3d._dot(a, b), view3d._norm(a)
    with np.errstate(over="ignore", invalid="ignore"):
        numpys = float(np.dot(np.array(a), np.array(b)))
        numpys_length = float(np.linalg.norm(np.array(a)))
    for mine, theirs in ((ours, numpys), (length, numpys_length)):
        assert mine == theirs or (math.isnan(mine) and math.isnan(theirs))
        assert math.copysign(1.0, mine) == math.copysign(1.0, theirs)


def test_the_calculator_starts_without_numpy() -> None:
    """The calculator's page and API import no NumPy: the batch endpoint imports it when used."""
    code = "import app.calculator.pages, app.calculator.api, sys; print('numpy' in sys.modules)"
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == "False", done.stderr
