"""The code to paste runs and prints the page's numbers for the user's points.

The NumPy, pure-Python and trimesh snippets run here in a fresh interpreter (``-W error``, so a
division by zero in a degenerate case would fail); Open3D and Blender are only checked as text.
"""

from __future__ import annotations

import ast
import math
import subprocess
import sys
from dataclasses import FrozenInstanceError
from html.parser import HTMLParser
from typing import Any, NamedTuple

import pytest

from app.calculator.calculation import calculation_payload, from_typed
from app.calculator.params import read_triangle
from app.calculator.payloads import normal_payload
from app.calculator.presets import PRESETS
from app.calculator.snippets import Snippet, snippets
from app.web.templating import templates
from mesh_normal.triangle.normal import triangle_normal
from tests.paths import ROOT

GENERAL = ((1.5, -2.25, 0.1), (4.0, 0.5, -3.0), (0.3, 7.0, 2.5))
UNIT_RIGHT = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))

#: A naive double computation of these points differs from the exact one by a few rounding
#: errors: u and v round once, each cross component rounds its two products and their
#: difference (error <= ~2 ulp of |u||v|, which is about |n| for a well-shaped triangle), and
#: |n| and n / |n| add a rounding each. A few ulps are below 1e-15 relative to the vector's size.
ROUNDING = 1e-15

#: trimesh crosses (B - A) x (C - B) instead of (B - A) x (C - A), so its roundings differ more.
TRIMESH = 1e-12


class Case(NamedTuple):
    name: str
    points: tuple[tuple[float, float, float], ...]
    swap: bool
    #: Every float step is exact or one correctly rounded operation on exact values, so the
    #: snippets print the page's numbers bit for bit (small integers: u, v and n are exact).
    exact: bool

    def payload(self) -> dict[str, Any]:
        return normal_payload(triangle_normal(*self.points, swap_winding=self.swap))


CASES = [
    Case("unit right triangle", UNIT_RIGHT, False, True),
    Case("swapped winding", UNIT_RIGHT, True, True),
    # |n| = 7 is exact, so n / |n| is one correctly rounded division, like the page's.
    Case("page example", ((1.0, 0.0, 0.0), (0.0, 2.0, 0.0), (0.0, 0.0, 3.0)), False, True),
    Case("general, decimals", GENERAL, False, False),
    Case("general, decimals, swapped", GENERAL, True, False),
    Case("collinear", ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2.0, 2.0, 2.0)), False, True),
]
IDS = [case.name for case in CASES]


def run(code: str) -> dict[str, Any]:
    """Run a snippet in a fresh interpreter; its ``name = value`` lines, parsed.

    The working directory is the checkout, so that ``import mesh_normal`` finds the library.
    """
    result = subprocess.run(
        [sys.executable, "-W", "error", "-c", code],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    printed: dict[str, Any] = {}
    for line in result.stdout.splitlines():
        if line == "degenerate: no unit normal":
            printed["degenerate"] = True
            continue
        name, value = line.split(" = ")
        printed[name] = ast.literal_eval(value)
    return printed


def by_key(payload: dict[str, Any]) -> dict[str, Snippet]:
    return {snippet.key: snippet for snippet in snippets(payload)}


def assert_close(got: Any, want: Any, rel: float) -> None:
    """Equal when ``rel`` is 0; else within ``rel`` of the size of ``want`` (the largest
    component for a vector: a cross product's error scales with the vector, not with each
    component, so a component that cancels to nearly 0 is held to the same absolute bound)."""
    if isinstance(want, list):
        assert len(got) == len(want) == 3, (got, want)
        scale = max(map(abs, want))
        for x, y in zip(got, want, strict=True):
            assert x == y if rel == 0 else abs(x - y) <= rel * scale, (got, want)
    else:
        assert got == want if rel == 0 else math.isclose(got, want, rel_tol=rel), (got, want)


# --- The API ---------------------------------------------------------------------------------


def test_six_flavours_numpy_first_then_the_library() -> None:
    found = snippets(CASES[0].payload())
    keys = ["numpy", "mesh_normal", "python", "trimesh", "open3d", "blender"]
    assert [s.key for s in found] == keys
    assert [s.runs_in_tests for s in found] == [True, True, True, True, False, False]
    assert {s.language for s in found} == {"python"}
    assert all(s.title and s.code.endswith("\n") for s in found)
    with pytest.raises(FrozenInstanceError):
        found[0].code = ""  # type: ignore[misc]


# --- Running them ----------------------------------------------------------------------------


@pytest.mark.parametrize("key", ["numpy", "python"])
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_snippet_prints_the_page_numbers(case: Case, key: str) -> None:
    payload = case.payload()
    printed = run(by_key(payload)[key].code)
    rel = 0.0 if case.exact else ROUNDING
    assert_close(printed["normal"], payload["normal"], rel)
    assert_close(printed["magnitude"], payload["magnitude"], rel)
    assert_close(printed["area"], payload["area"], rel)
    if payload["degenerate"]:
        assert printed == {
            "normal": (0.0, 0.0, 0.0),
            "magnitude": 0.0,
            "area": 0.0,
            "degenerate": True,
        }
    else:
        assert_close(printed["unit_normal"], payload["unit_normal"], rel)


PRESET_KEYS = [key for key, *_ in PRESETS]


@pytest.mark.parametrize("key", PRESET_KEYS)
def test_mesh_normal_snippet_prints_the_page_numbers_exactly(key: str) -> None:
    """The library is the page's own computation: every number equal, out of range None."""
    payload = preset(key)
    code = by_key(payload)["mesh_normal"].code
    assert "import mesh_normal as mn" in code and "mn.triangle_normal(a, b, c" in code
    printed = run(code)
    assert printed["normal"] == tuple(payload["normal"])
    assert printed["magnitude"] == payload["magnitude"]
    assert printed["area"] == payload["area"]
    if payload["degenerate"]:
        assert printed.get("degenerate") is True and "unit_normal" not in printed
    else:
        assert printed["unit_normal"] == tuple(payload["unit_normal"])


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_mesh_normal_snippet_matches_every_case(case: Case) -> None:
    payload = case.payload()
    printed = run(by_key(payload)["mesh_normal"].code)
    assert_close(printed["normal"], payload["normal"], 0.0)
    assert printed["area"] == payload["area"]
    assert ("swap_winding=True" in by_key(payload)["mesh_normal"].code) is case.swap


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_trimesh_snippet_matches_the_page(case: Case) -> None:
    payload = case.payload()
    printed = run(by_key(payload)["trimesh"].code)
    assert math.isclose(printed["area"], payload["area"], rel_tol=TRIMESH)
    if payload["degenerate"]:
        assert printed.get("degenerate") is True and "unit_normal" not in printed
    else:
        assert_close(printed["unit_normal"], payload["unit_normal"], TRIMESH)
        assert_close(printed["normal"], payload["normal"], TRIMESH)


def test_general_triangle_is_not_exact_in_floats() -> None:
    """The tolerance above is needed: plain doubles miss the exact n_y by one ulp here."""
    payload = CASES[3].payload()
    printed = run(by_key(payload)["python"].code)
    assert printed["normal"][1] != payload["normal"][1]
    assert "last digits here may differ" in by_key(payload)["numpy"].code


# --- What they say ---------------------------------------------------------------------------


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_every_snippet_has_the_coordinates_as_round_trip_reprs(case: Case) -> None:
    payload = case.payload()
    for snippet in snippets(payload):
        for point in ("a", "b", "c"):
            text = ", ".join(repr(x) for x in payload[point])
            assert text in snippet.code, (snippet.key, text)
            assert all(float(repr(x)) == x for x in payload[point])


def test_coordinates_keep_every_digit() -> None:
    points = ((0.1 + 0.2, 1 / 3, -1e-300), (1e300, 5e-324, 2.0), (0.0, -0.0, 123456789.123))
    payload = normal_payload(triangle_normal(*points))
    for snippet in snippets(payload):
        for point in points:
            assert ", ".join(map(repr, point)) in snippet.code, snippet.key


def test_acb_order_is_honoured() -> None:
    plain, swapped = by_key(CASES[0].payload()), by_key(CASES[1].payload())
    marks = {
        "numpy": "u = c - a",
        "python": "u = tuple(c[i] - a[i]",
        "trimesh": "[[0, 2, 1]]",
        "open3d": "[[0, 2, 1]]",
        "blender": "normal(a, c, b)",
    }
    for key, mark in marks.items():
        assert "Winding A, C, B" in swapped[key].code, key
        assert mark in swapped[key].code, key
        assert "A, C, B" not in plain[key].code and mark not in plain[key].code, key
    for key in ("numpy", "python", "trimesh"):
        assert run(swapped[key].code)["unit_normal"] == (0.0, 0.0, -1.0), key


def test_blender_notes_its_unit_normal_and_precision() -> None:
    code = by_key(CASES[0].payload())["blender"].code
    assert "from mathutils.geometry import area_tri, normal" in code
    assert "returns the unit normal" in code and "counter-clockwise" in code
    assert "single-precision" in code
    assert "area_tri(a, b, c)" in code


def test_open3d_uses_its_mesh_api() -> None:
    code = by_key(CASES[0].payload())["open3d"].code
    for text in (
        "o3d.geometry.TriangleMesh()",
        "o3d.utility.Vector3dVector(vertices)",
        "o3d.utility.Vector3iVector(triangles)",
        "compute_triangle_normals()",
        "np.asarray(mesh.triangle_normals)[0]",
        "mesh.get_surface_area()",
    ):
        assert text in code, text
    compile(code, "<open3d>", "exec")
    compile(by_key(CASES[0].payload())["blender"].code, "<blender>", "exec")


def preset(key: str) -> dict[str, Any]:
    query = next(params for name, *_, params in PRESETS if name == key)
    points = [tuple(float(query[f"{p}{axis}"]) for axis in "xyz") for p in "abc"]
    return normal_payload(triangle_normal(*points, swap_winding="swap" in query))


NOTE = "# Note: the page's numbers are exact, rounded once; the floats here may differ:"


@pytest.mark.parametrize("key", ["sliver", "huge"])
def test_pathological_points_get_a_note(key: str) -> None:
    for snippet in snippets(preset(key)):
        if snippet.key == "mesh_normal":  # exact like the page: nothing may differ
            assert NOTE not in snippet.code
            compile(snippet.code, snippet.key, "exec")
            continue
        assert NOTE in snippet.code, snippet.key
        compile(snippet.code, snippet.key, "exec")


def test_sliver_snippet_still_runs_and_shows_why_the_note_is_there() -> None:
    payload = preset("sliver")
    printed = run(by_key(payload)["numpy"].code)
    assert printed.get("degenerate") is True  # the float cross product rounds n to zero
    assert not payload["degenerate"] and payload["unit_normal"] == [0.0, 0.0, -1.0]


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_ordinary_points_get_no_warning(case: Case) -> None:
    for snippet in snippets(case.payload()):
        assert NOTE not in snippet.code and "tol.zero" not in snippet.code, snippet.key


def test_trimesh_tolerance_is_noted_for_tiny_triangles() -> None:
    payload = normal_payload(triangle_normal((0, 0, 0), (1e-7, 0, 0), (0, 1e-7, 0)))
    code = by_key(payload)["trimesh"].code
    assert "tol.zero" in code
    assert run(code)["unit_normal"] == (0.0, 0.0, 0.0)


# --- The partial -----------------------------------------------------------------------------


class CodeBlocks(HTMLParser):
    """Every element's attributes, and the raw text of each <code id=...>."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.elements: list[tuple[str, dict[str, str | None]]] = []
        self.code: dict[str, str] = {}
        self._current: str | None = None
        self.feed(text)
        self.close()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.elements.append((tag, dict(attrs)))
        if tag == "code":
            self._current = dict(attrs)["id"]
            self.code[self._current or ""] = ""

    def handle_endtag(self, tag: str) -> None:
        if tag == "code":
            self._current = None

    def handle_data(self, data: str) -> None:
        if self._current is not None:
            self.code[self._current] += data


def test_partial_renders_each_snippet_with_a_copy_button() -> None:
    found = snippets(CASES[1].payload())
    html = CodeBlocks(templates.env.get_template("_code.html").render(snippets=found))
    tags = [tag for tag, _ in html.elements]
    assert "script" not in tags
    assert not [name for _, attrs in html.elements for name in attrs if name.startswith("on")]
    for snippet in found:
        element_id = f"code-{snippet.key}"
        assert html.code[element_id] == snippet.code  # what the Copy button copies
        buttons = [
            attrs
            for tag, attrs in html.elements
            if tag == "button" and attrs.get("data-copy") == element_id
        ]
        assert buttons == [
            {
                "type": "button",
                "class": "copy",
                "data-copy": element_id,
                "aria-describedby": f"{element_id}-title",
            }
        ]
        assert ("h3", {"id": f"{element_id}-title"}) in html.elements
    details = [attrs for tag, attrs in html.elements if tag == "details"]
    assert [attrs["id"] for attrs in details if "open" in attrs] == ["snippet-numpy"]
    assert len(details) == 6


def test_partial_without_snippets_says_when_they_come() -> None:
    text = templates.env.get_template("_code.html").render(snippets=[])
    assert "Code to paste" in text and "<pre" not in text


@pytest.mark.parametrize("key", PRESET_KEYS)
def test_mesh_normal_snippet_prints_the_pages_own_numbers(key: str) -> None:
    """The page computes with the typed decimals: the library snippet does too, when it matters."""
    query = next(params for name, *_, params in PRESETS if name == key)
    calc = from_typed(read_triangle(query))
    payload = calculation_payload(calc)
    code = {s.key: s for s in snippets(payload, calc.typed)}["mesh_normal"].code
    # Only the sliver's decimals (1000003.0000000001) are not doubles.
    assert ("rational_triangle_normal" in code) is (key == "sliver")
    printed = run(code)
    assert printed["normal"] == tuple(payload["normal"])
    assert printed["magnitude"] == payload["magnitude"] and printed["area"] == payload["area"]
    if key == "sliver":
        assert payload["normal"][2] == -1e-20  # (3 + 1e-10)(3 - 1e-10) - 9, exactly
        assert 'F("10000030000000001/10000000000")' in code
