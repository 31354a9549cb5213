"""The worked steps, with hand-computed numbers, and their partial."""

from __future__ import annotations

import html
import math
import re
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jinja2 import Environment, FileSystemLoader

from app.calculator.calculation import from_typed
from app.calculator.params import read_triangle
from app.calculator.steps import Step, worked_steps
from app.web.formatting import number_text
from mesh_normal.triangle.normal import TriangleNormal, triangle_normal
from tests.conftest import Page
from tests.paths import TEMPLATES

EXAMPLE = ((1, 0, 0), (0, 2, 0), (0, 0, 3))
KEYS = ["edges", "cross", "magnitude", "area", "unit", "plane", "angle", "swap"]
#: A sliver: n_z = 2**-53 - 2**-105 exactly, but plain floats round its first product to 1.
SLIVER = ((0, 0, 0), (1 + 2**-52, 1, 0), (1, 1 - 2**-53, 0))
HUGE = ((0, 0, 0), (1e200, 0, 0), (0, 1e200, 0))


def steps_of(a, b, c, swap: bool = False) -> dict[str, Step]:  # type: ignore[no-untyped-def]
    steps = worked_steps(triangle_normal(a, b, c, swap_winding=swap))
    by_key = {step.key: step for step in steps}
    assert len(by_key) == len(steps), [step.key for step in steps]
    return by_key


def line_starting(step: Step, start: str) -> str:
    found = [line for line in step.lines if line.startswith(start)]
    assert len(found) == 1, (start, step.lines)
    return found[0]


def angle_of(step: Step) -> float:
    match = re.fullmatch(r"θ = .* [=≈] (\S+)°", line_starting(step, "θ = "))
    assert match, step.lines
    return float(match.group(1).replace("−", "-"))


# --- The example: A = (1, 0, 0), B = (0, 2, 0), C = (0, 0, 3) ----------------------------------


def test_example_has_the_eight_steps_in_order() -> None:
    steps = worked_steps(triangle_normal(*EXAMPLE))
    assert [step.key for step in steps] == KEYS
    assert all(step.title and step.text for step in steps)
    assert not any(step.warn for step in steps)


def test_example_edges() -> None:
    edges = steps_of(*EXAMPLE)["edges"]
    assert "u = B − A" in edges.text and "v = C − A" in edges.text
    assert edges.lines == (
        "u = B − A",
        "u_x = b_x − a_x = 0 − 1 = −1",
        "u_y = b_y − a_y = 2 − 0 = 2",
        "u_z = b_z − a_z = 0 − 0 = 0",
        "u = (−1, 2, 0)",
        "v = C − A",
        "v_x = c_x − a_x = 0 − 1 = −1",
        "v_y = c_y − a_y = 0 − 0 = 0",
        "v_z = c_z − a_z = 3 − 0 = 3",
        "v = (−1, 0, 3)",
    )


def test_example_cross_product_shows_determinants_and_products() -> None:
    cross = steps_of(*EXAMPLE)["cross"]
    assert cross.lines == (
        "n = u × v = |e_x e_y e_z; u_x u_y u_z; v_x v_y v_z| = |e_x e_y e_z; −1 2 0; −1 0 3|",
        "n_x = |u_y u_z; v_y v_z| = |2 0; 0 3| = 2·3 − 0·0 = 6 − 0 = 6",
        "n_y = |u_z u_x; v_z v_x| = |0 −1; 3 −1| = 0·(−1) − (−1)·3 = 0 − (−3) = 3",
        "n_z = |u_x u_y; v_x v_y| = |−1 2; −1 0| = (−1)·0 − 2·(−1) = 0 − (−2) = 2",
        "n = (6, 3, 2)",
    )
    assert cross.notes == ()


def test_example_length_area_and_unit_normal() -> None:
    steps = steps_of(*EXAMPLE)
    assert steps["magnitude"].lines == (
        "|n| = √(n_x² + n_y² + n_z²) = √(6² + 3² + 2²) = √(36 + 9 + 4) = √(49) = 7",
    )
    assert steps["area"].lines == ("area = |n| / 2 = 7 / 2 = 3.5",)
    unit = steps["unit"]
    # 6/7, 3/7 and 2/7 are not doubles: the step says "≈", and says what "≈" means.
    assert line_starting(unit, "n̂_x") == f"n̂_x = n_x / |n| = 6 / 7 ≈ {number_text(6 / 7)}"
    assert line_starting(unit, "n̂_z") == f"n̂_z = n_z / |n| = 2 / 7 ≈ {number_text(2 / 7)}"
    assert (
        line_starting(unit, "n̂ = ") == f"n̂ = ({number_text(6 / 7)}, {number_text(3 / 7)}, "
        f"{number_text(2 / 7)})"
    )
    assert any("≈" in note for note in unit.notes)


def test_example_plane() -> None:
    plane = steps_of(*EXAMPLE)["plane"]
    assert plane.lines == (
        "d = n · A = n_x·a_x + n_y·a_y + n_z·a_z = 6·1 + 3·0 + 2·0 = 6",
        "6x + 3y + 2z = 6",
    )
    # B and C satisfy it as well, checked by hand: 6·0 + 3·2 + 2·0 = 6 and 2·3 = 6.
    assert plane.notes == ()


def test_example_angle_between_u_and_v() -> None:
    angle = steps_of(*EXAMPLE)["angle"]
    assert line_starting(angle, "u · v") == (
        "u · v = u_x·v_x + u_y·v_y + u_z·v_z = (−1)·(−1) + 2·0 + 0·3 = 1 + 0 + 0 = 1"
    )
    assert line_starting(angle, "|u × v|") == "|u × v| = |n| = 7"
    assert "atan2(7, 1) ≈" in line_starting(angle, "θ")
    expected = math.degrees(math.acos(1 / (math.sqrt(5) * math.sqrt(10))))
    assert angle_of(angle) == pytest.approx(expected, rel=1e-14)
    assert "atan2" in angle.text and "0°" in angle.text


def test_example_swap_explains_the_sign() -> None:
    swap = steps_of(*EXAMPLE)["swap"]
    assert "v × u = −(u × v)" in swap.lines
    assert "A, C, B: n = −(6, 3, 2) = (−6, −3, −2)" in swap.lines
    assert "|n| = 7 and area = 3.5 either way" in swap.lines
    assert "changes sign" in swap.text


# --- Swapped winding --------------------------------------------------------------------------


def test_swapped_winding_uses_c_first_and_negates_n() -> None:
    steps = steps_of(*EXAMPLE, swap=True)
    edges = steps["edges"]
    assert "u = C − A" in edges.text and "v = B − A" in edges.text
    assert edges.lines[:2] == ("u = C − A", "u_x = c_x − a_x = 0 − 1 = −1")
    assert "v = B − A" in edges.lines and "v = (−1, 2, 0)" in edges.lines
    assert steps["cross"].lines[-1] == "n = (−6, −3, −2)"
    assert "√((−6)² + (−3)² + (−2)²) = √(36 + 9 + 4)" in steps["magnitude"].lines[0]
    assert steps["area"].lines == ("area = |n| / 2 = 7 / 2 = 3.5",)
    assert steps["plane"].lines[-1] == "−6x − 3y − 2z = −6"
    assert "A, B, C: n = −(−6, −3, −2) = (6, 3, 2)" in steps["swap"].lines
    assert "You listed the corners as A, C, B" in steps["swap"].text
    # The angle between the edges does not depend on which is called u.
    assert angle_of(steps["angle"]) == angle_of(steps_of(*EXAMPLE)["angle"])


# --- Degenerate triangles ---------------------------------------------------------------------


def test_collinear_points_explain_no_normal_no_plane_and_zero_angle() -> None:
    steps = steps_of((1, 1, 1), (2, 2, 2), (3, 3, 3))
    assert steps["cross"].lines[-1] == "n = (0, 0, 0)"
    assert any("lie on one line" in note for note in steps["cross"].notes)
    assert steps["magnitude"].lines[0].endswith("= √(0) = 0")
    assert steps["unit"].warn and "no unit normal" in steps["unit"].notes[0]
    assert steps["plane"].lines == () and "no plane" in steps["plane"].notes[0]
    angle = steps["angle"]
    assert angle_of(angle) == 0
    assert "atan2(0, 6) = 0°" in line_starting(angle, "θ")
    assert "same way (0°)" in angle.notes[0]
    assert "either way" in steps["swap"].notes[0]


def test_points_in_opposite_directions_make_180_degrees() -> None:
    angle = steps_of((0, 0, 0), (1, 0, 0), (-1, 0, 0))["angle"]
    assert angle_of(angle) == 180
    assert "opposite ways (180°)" in angle.notes[0]


def test_repeated_point_leaves_the_angle_undefined() -> None:
    steps = steps_of((1, 1, 1), (1, 1, 1), (3, 3, 3))
    assert any("Points A and B coincide" in note for note in steps["cross"].notes)
    angle = steps["angle"]
    assert "θ = atan2(0, 0): undefined" in angle.lines
    assert "u has zero length (points A and B coincide)" in angle.notes[0]


# --- Exact rounding ---------------------------------------------------------------------------


def test_sliver_explains_why_naive_floats_get_zero() -> None:
    a, b, c = SLIVER
    naive_z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    assert naive_z == 0  # the premise: plain floats call it flat
    exact_z = 2.0**-53 - 2.0**-105
    assert Fraction(exact_z) == Fraction(1 + 2**-52) * Fraction(1 - 2**-53) - 1

    steps = worked_steps(triangle_normal(*SLIVER))
    keys = [step.key for step in steps]
    assert keys == ["edges", "cross", "exact", *KEYS[2:]]
    exact = steps[2]
    assert exact.notes[0] == (
        "A naive float computation gives n = (0, 0, 0) because the products round before they "
        "are subtracted; this calculator works with the exact values and rounds once. Plain "
        "floats would call this triangle flat."
    )
    assert "n_z in floats: 1.0000000000000002·0.9999999999999999 − 1·1 → 1 − 1 → 0" in exact.lines
    assert f"exact n, rounded once = (0, 0, {number_text(exact_z)})" in exact.lines
    # The cross product itself marks the rounded products with "≈".
    assert steps[1].lines[3] == (
        "n_z = |u_x u_y; v_x v_y| = |1.0000000000000002 1; 1 0.9999999999999999| = "
        f"1.0000000000000002·0.9999999999999999 − 1·1 ≈ 1 − 1 ≈ {number_text(exact_z)}"
    )


def test_no_exact_step_when_floats_agree() -> None:
    assert "exact" not in steps_of(*EXAMPLE)
    assert "exact" not in steps_of((0.5, 0, 0), (0, 0.25, 0), (0, 0, 2))


def test_naive_overflow_shows_nan_and_says_why() -> None:
    steps = steps_of((-1e308, 0, 0), (1e308, 1, 0), (-1e308, 0, 1))
    assert "u = (out of range, 1, 0)" in steps["edges"].lines
    exact = steps["exact"]
    assert "n_z in floats: Infinity·0 − 1·0 → NaN − 0 → NaN" in exact.lines
    assert "NaN" in exact.notes[0] and "Infinity" in exact.notes[0]
    # |n| (about 2e308) is out of range, half of it is not.
    assert steps["area"].lines == ("area = |n| / 2 ≈ 1e+308",)
    assert "half of it is not" in steps["area"].notes[0]


# --- Out of range -----------------------------------------------------------------------------


def test_huge_values_are_explained_and_the_unit_normal_shown() -> None:
    steps = steps_of(*HUGE)
    cross = steps["cross"]
    assert cross.lines[-1] == "n = (0, 0, out of range)"
    assert cross.warn and "n_z" in cross.notes[0] and "out of range" in cross.notes[0]
    assert steps["magnitude"].lines == ("|n| = √(n_x² + n_y² + n_z²) = out of range",)
    assert steps["area"].lines == ("area = |n| / 2 = out of range",)
    unit = steps["unit"]
    assert unit.lines[-1] == "n̂ = (0, 0, 1)"
    assert "shown all the same" in unit.notes[0]
    plane = steps["plane"]
    assert plane.lines[-1] == "z = 0"
    assert plane.lines[0].startswith("d′ = n̂ · A = ")
    assert "unit normal instead" in plane.notes[0]
    assert angle_of(steps["angle"]) == 90
    assert "exact" not in steps  # overflow is out of range, not a rounding story


def test_sum_of_squares_too_large_but_length_fits() -> None:
    magnitude = steps_of((0, 0, 0), (1e100, 0, 0), (0, 1e100, 0))["magnitude"]
    assert magnitude.lines == ("|n| = √(n_x² + n_y² + n_z²) ≈ √(0² + 0² + (1e+200)²) ≈ 1e+200",)
    assert "the sum of squares" in magnitude.notes[0]
    assert "does not fit a double, but its square root does" in magnitude.notes[1]


def test_angle_of_a_huge_sliver_comes_from_exact_values() -> None:
    b, c = (1e200, 1e200, 0), (1e200, 1.0000000000000001e200, 0)
    angle = steps_of((0, 0, 0), b, c)["angle"]
    assert "u · v" in angle.notes[0]  # u · v is beyond the double range
    cross = Fraction(b[0]) * Fraction(c[1]) - Fraction(b[1]) * Fraction(c[0])
    dot = Fraction(b[0]) * Fraction(c[0]) + Fraction(b[1]) * Fraction(c[1])
    assert angle_of(angle) == pytest.approx(math.degrees(float(cross / dot)), rel=1e-12)


# --- Every triangle ---------------------------------------------------------------------------

coordinates = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.integers(-20, 20).map(float),
    st.floats(-10, 10),
)
points = st.tuples(coordinates, coordinates, coordinates)


def vec(values) -> str:  # type: ignore[no-untyped-def]
    return "(" + ", ".join("out of range" if x is None else number_text(x) for x in values) + ")"


def check_against_result(result: TriangleNormal, steps: list[Step]) -> None:
    by_key = {step.key: step for step in steps}
    assert [key for key in by_key if key != "exact"] == KEYS
    assert by_key["edges"].lines[4] == f"u = {vec(result.u)}"
    assert by_key["edges"].lines[9] == f"v = {vec(result.v)}"
    assert by_key["cross"].lines[-1] == f"n = {vec(result.normal)}"
    if result.unit_normal is not None:
        assert by_key["unit"].lines[-1] == f"n̂ = {vec(result.unit_normal)}"
    for step in steps:
        for line in step.lines:
            # A negative number after an operator or a product's dot is always in parentheses,
            # and every minus is the real one.
            assert not re.search(r"([−+]|·) −", line), line
            assert "-" not in line, line
            assert "nan" not in line and "inf" not in line, line
        for line, formula in zip(step.lines, step.math, strict=True):
            # One <math> a piece of a chain: as many as its relations, plus one.
            relations = len(re.findall(r" [=≈] ", line))
            assert formula.count("<math ") in (1, relations + 1), formula


@settings(max_examples=150, deadline=None)
@given(points, points, points, st.booleans())
def test_steps_agree_with_the_result_for_any_points(a, b, c, swap) -> None:  # type: ignore[no-untyped-def]
    result = triangle_normal(a, b, c, swap_winding=swap)
    check_against_result(result, worked_steps(result))


# --- The partial ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def env() -> Environment:
    environment = Environment(loader=FileSystemLoader(TEMPLATES), autoescape=True)
    environment.filters["num"] = lambda x: "out of range" if x is None else number_text(x)
    return environment


def render(env: Environment, steps: list[Step] | None) -> tuple[str, Page]:
    text = env.get_template("_steps.html").render(steps=steps)
    return text, Page(text)


def plain_text(markup: str) -> str:
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", markup)).split())


def test_partial_shows_the_users_numbers(env: Environment) -> None:
    _, page = render(env, worked_steps(triangle_normal(*EXAMPLE)))
    assert len(page.find("ol", class_="steps")) == 1
    assert [attrs["data-step"] for attrs in page.find("li", class_="step")] == KEYS
    assert len(page.find("h3")) == len(KEYS)
    # Each line is a div.formula with its plain text in data-formula; a chain is one <math>
    # a piece (a phone may wrap before an "="), each with its own plain text as alttext.
    alts = [attrs["data-formula"] for attrs in page.find("div", class_="formula")]
    for expected in (
        "u_x = b_x − a_x = 0 − 1 = −1",
        "n_x = |u_y u_z; v_y v_z| = |2 0; 0 3| = 2·3 − 0·0 = 6 − 0 = 6",
        "|n| = √(n_x² + n_y² + n_z²) = √(6² + 3² + 2²) = √(36 + 9 + 4) = √(49) = 7",
        "area = |n| / 2 = 7 / 2 = 3.5",
        "6x + 3y + 2z = 6",
        "A, C, B: n = −(6, 3, 2) = (−6, −3, −2)",
    ):
        assert expected in alts, expected
    # One math box a step, each formula its own block.
    assert len(page.find("div", class_="math")) == len(KEYS)
    assert len(alts) == sum(len(step.lines) for step in worked_steps(triangle_normal(*EXAMPLE)))
    assert page.find("code") == []
    pieces = [attrs["alttext"] for attrs in page.find("math")]
    assert pieces[:4] == ["u = B − A", "u_x", "= b_x − a_x", "= 0 − 1"]
    assert all(attrs.get("displaystyle") == "true" for attrs in page.find("math"))


def test_partial_typesets_vectors_determinants_roots_and_fractions(env: Environment) -> None:
    markup, _ = render(env, worked_steps(triangle_normal(*EXAMPLE)))
    # The 3×3 and the three 2×2 determinants between bars, and u, v, n, n̂ as columns.
    assert markup.count("<mo>|</mo><mtable>") == 2 * 4
    assert markup.count("<mo>(</mo><mtable>") >= 4
    assert "<msqrt>" in markup
    assert "<mfrac><mrow><mo>|</mo><mi>n</mi><mo>|</mo></mrow><mn" in markup  # |n| / 2
    # Numbers carry their machine text, so the precision setting can rewrite them.
    assert '<mn class="num" data-num="-1">−1</mn>' in markup
    assert "sqrt(" not in markup


def test_partial_has_no_scripts_handlers_or_inline_styles(env: Environment) -> None:
    _, page = render(env, worked_steps(triangle_normal(*SLIVER)))
    assert page.scripts == []
    for _, attrs in page.elements:
        assert not any(name.startswith("on") or name == "style" for name in attrs), attrs


def test_partial_marks_special_cases_as_warnings(env: Environment) -> None:
    markup, page = render(env, worked_steps(triangle_normal((1, 1, 1), (2, 2, 2), (3, 3, 3))))
    assert page.find("p", class_="message small warn")
    assert "There is no plane" in plain_text(markup)
    _, page = render(env, worked_steps(triangle_normal(*HUGE)))
    lines = [attrs["data-formula"] for attrs in page.find("div", class_="formula")]
    assert "n = (0, 0, out of range)" in lines


def test_partial_without_a_result(env: Environment) -> None:
    markup, page = render(env, None)
    assert page.find("ol") == []
    assert "The steps appear once every coordinate is a number." in plain_text(markup)


# --- Typed decimals, read exactly -----------------------------------------------------------------


def typed_steps(query: dict[str, str]) -> dict[str, Step]:
    calc = from_typed(read_triangle(query))
    return {step.key: step for step in worked_steps(calc.result, calc.exact)}


def test_typed_decimals_are_the_steps_exact_values() -> None:
    # In doubles 0.3 - 0.1 is 0.19999999999999998; as decimals it is 1/5, shown ≈ 0.2.
    query = {"ax": "0.1", "ay": "0", "az": "0", "bx": "0.3", "by": "1", "bz": "0"}
    steps = typed_steps({**query, "cx": "0.1", "cy": "0", "cz": "1"})
    assert line_starting(steps["edges"], "u_x = ") == "u_x = b_x − a_x = 0.3 − 0.1 ≈ 0.2"
    # Collinear as decimals (not as doubles): no plane, and the steps say so.
    line = {"ax": "0.1", "ay": "0", "az": "0", "bx": "0.2", "by": "0.3", "bz": "0"}
    steps = typed_steps({**line, "cx": "0.3", "cy": "0.6", "cz": "0"})
    assert line_starting(steps["cross"], "n = (") == "n = (0, 0, 0)"
    assert steps["plane"].lines == () and steps["unit"].warn
