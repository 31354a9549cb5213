"""The calculator page's newer parts: 3D view, worked steps, code to paste, presets, downloads,
display precision, phone layout and keyboard use."""

from __future__ import annotations

import csv
import io
import json
import math
import re
from pathlib import Path
from urllib.parse import urlencode

import pytest
from playwright.sync_api import Locator, Page, expect

from app.calculator.presets import PRESETS
from app.calculator.snippets import snippets
from tests.browser.conftest import NewPage
from tests.browser.helpers import (
    COLLINEAR,
    FIELDS,
    RIGHT,
    cell,
    fill_triangle,
    open_calculator,
    query_pattern,
    triangle_query,
    wait_for_chart_values,
)

pytestmark = pytest.mark.browser

CLIPBOARD = {"permissions": ["clipboard-read", "clipboard-write"]}
EXAMPLE_UNIT = [6 / 7, 3 / 7, 2 / 7]


def mark_window(page: Page) -> None:
    """A marker that only survives as long as no full page load happens."""
    page.evaluate("() => { window.__noReload = 'still here'; }")


def assert_not_reloaded(page: Page) -> None:
    assert page.evaluate("() => window.__noReload") == "still here", "the page was reloaded"


def page_payload(page: Page) -> dict:
    return json.loads(page.locator("#result-json").text_content() or "null")


# --- 1. The 3D view ---------------------------------------------------------------------------

NORMAL_ARROW = """() => {
    const el = document.getElementById('view3d');
    if (!el.dataset.drawn || !el.data) return null;
    const cone = el.data.find((t) => t.name === 'normal' && t.type === 'cone');
    const title = el.layout && el.layout.title;
    return cone ? {d: [cone.u[0], cone.v[0], cone.w[0]],
                   title: typeof title === 'string' ? title : title && title.text} : null;
}"""


def show_3d(page: Page) -> None:
    page.locator("#view3d").scroll_into_view_if_needed()
    page.locator("#view3d[data-drawn]").wait_for(timeout=20_000)


def wait_for_arrow(page: Page, unit: list[float], title: str) -> None:
    """Wait until the drawn 3D normal arrow points along ``unit`` under ``title``."""
    page.wait_for_function(
        """([want, title]) => {
            const el = document.getElementById('view3d');
            if (!el.dataset.drawn || !el.data || !el.layout) return false;
            const t = el.layout.title;
            if ((typeof t === 'string' ? t : t && t.text) !== title) return false;
            const cone = el.data.find((c) => c.name === 'normal' && c.type === 'cone');
            if (!cone) return false;
            const d = [cone.u[0], cone.v[0], cone.w[0]];
            const size = Math.hypot(...d);
            return size > 0 && d.every((x, i) => Math.abs(x / size - want[i]) < 1e-9);
        }""",
        arg=[unit, title],
    )


def test_3d_view_draws_the_normal_and_follows_the_swap(page: Page) -> None:
    open_calculator(page)
    page.evaluate("() => { window.__basicPlotly = window.Plotly; }")
    expect(page.locator("#view3d[data-drawn]")).to_have_count(0)  # below the fold: not yet
    show_3d(page)
    arrow = page.evaluate(NORMAL_ARROW)
    assert arrow is not None, "no normal cone in the 3D view"
    size = math.hypot(*arrow["d"])
    unit = page_payload(page)["unit_normal"]
    assert unit == EXAMPLE_UNIT
    assert [x / size for x in arrow["d"]] == pytest.approx(unit, abs=1e-9)
    assert arrow["title"] == "Front: A → B → C counter-clockwise"
    names = set(page.evaluate("() => document.getElementById('view3d').data.map(t => t.name)"))
    assert {"face", "u", "v", "edge", "normal", "front", "turn", "corners", "axes"} <= names
    expect(page.locator("#view3d canvas").first).to_be_attached()

    # The swap flips the arrow and the title says the new order.
    page.locator("label.switch").click()
    expect(cell(page, "order")).to_have_text("order A, C, B")
    wait_for_arrow(page, [-x for x in unit], "Front: A → C → B counter-clockwise")

    # The gl3d bundle did not replace the page's Plotly: the bar chart still redraws.
    assert page.evaluate("() => window.Plotly === window.__basicPlotly")
    assert not page.evaluate("() => 'scatter3d' in window.Plotly.PlotSchema.get().traces"), (
        "window.Plotly is gl3d"
    )
    fill_triangle(page, *RIGHT)  # swap still on: n = (0, 0, -1)
    wait_for_chart_values(page, [0, 0, -1, 1, 0.5])
    wait_for_arrow(page, [0, 0, -1], "Front: A → C → B counter-clockwise")
    page.locator("label.switch").click()
    wait_for_chart_values(page, [0, 0, 1, 1, 0.5])
    wait_for_arrow(page, [0, 0, 1], "Front: A → B → C counter-clockwise")
    assert page.evaluate("() => window.Plotly === window.__basicPlotly")


# --- 2. Worked steps --------------------------------------------------------------------------


def step(page: Page, key: str):
    return page.locator(f'#steps [data-step="{key}"]')


def math_line(page: Page, key: str, formula: str) -> Locator:
    """A step's formula, by its plain text."""
    return step(page, key).locator(f'.formula[data-formula="{formula}"]')


def test_worked_steps_show_the_users_numbers_and_follow_live_edits(page: Page) -> None:
    open_calculator(page, triangle_query(("1", "0", "0"), ("0", "2", "0"), ("0", "0", "3")))
    mark_window(page)
    for key, formula in (
        ("cross", "n_x = |u_y u_z; v_y v_z| = |2 0; 0 3| = 2·3 − 0·0 = 6 − 0 = 6"),
        ("cross", "n_y = |u_z u_x; v_z v_x| = |0 −1; 3 −1| = 0·(−1) − (−1)·3 = 0 − (−3) = 3"),
        ("edges", "u = (−1, 2, 0)"),
        ("plane", "6x + 3y + 2z = 6"),
        ("area", "area = |n| / 2 = 7 / 2 = 3.5"),
    ):
        expect(math_line(page, key, formula)).to_have_count(1)
    expect(step(page, "magnitude").locator("math msqrt")).to_have_count(4)

    # New points: the steps follow without a reload.
    fill_triangle(page, ("0", "0", "0"), ("2", "0", "0"), ("0", "5", "0"))
    new_z = "n_z = |u_x u_y; v_x v_y| = |2 0; 0 5| = 2·5 − 0·0 = 10 − 0 = 10"
    expect(math_line(page, "cross", new_z)).to_have_count(1)
    expect(math_line(page, "plane", "6x + 3y + 2z = 6")).to_have_count(0)
    expect(math_line(page, "area", "area = |n| / 2 = 10 / 2 = 5")).to_have_count(1)
    assert_not_reloaded(page)

    # Degenerate: the steps explain why there is no normal and no plane.
    fill_triangle(page, *COLLINEAR)
    expect(step(page, "cross")).to_contain_text(
        "The three points lie on one line, so the triangle has no area and no normal direction."
    )
    expect(step(page, "unit")).to_contain_text("There is no unit normal")
    expect(step(page, "plane")).to_contain_text("There is no plane")
    expect(step(page, "plane").locator(".message.warn")).to_be_visible()
    assert_not_reloaded(page)


def test_a_typing_mistake_retires_the_old_steps_and_code(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    expect(step(page, "cross")).to_be_visible()
    page.locator("#ax").fill("x")
    expect(cell(page, "invalid")).to_be_visible()
    served = page.request.get(page.url).text()
    assert "The steps appear once every coordinate is a number." in served
    for part in ("#steps", "#code"):  # dimmed and inert until the mistake is fixed
        expect(page.locator(part)).to_have_class(re.compile(r"\bstale\b"))
        assert page.locator(part).evaluate("el => el.inert") is True
    page.locator("#ax").fill("0")
    for part in ("#steps", "#code"):
        expect(page.locator(part)).not_to_have_class(re.compile(r"\bstale\b"))
        assert page.locator(part).evaluate("el => el.inert") is False


# --- 3. Code to paste -------------------------------------------------------------------------


def api_payload(page: Page, query: str) -> dict:
    answer = page.request.get(f"/api/normal?{query}")
    assert answer.ok, answer.status
    return answer.json()


def test_snippets_copy_exactly_follow_live_edits_and_keep_open_sections(new_page: NewPage) -> None:
    page = new_page(**CLIPBOARD)
    query = triangle_query(("1", "0", "0"), ("0", "2", "0"), ("0", "0", "3"), swap=True)
    open_calculator(page, query)
    expected = snippets(api_payload(page, query))
    details = page.locator("#code details.snippet")
    expect(details).to_have_count(len(expected))
    for snippet in expected:  # every copy button copies its own snippet, exactly
        box = page.locator(f"#snippet-{snippet.key}")
        if box.get_attribute("open") is None:
            box.locator("summary").click()
        expect(box).to_have_attribute("open", "")
        button = box.locator("button.copy")
        button.click()
        expect(button).to_have_text("Copied")
        copied = page.evaluate("navigator.clipboard.readText()")
        assert copied == snippet.code, snippet.key
        assert copied == page.locator(f"#code-{snippet.key}").text_content()
    for key in ("trimesh", "open3d", "blender"):
        page.locator(f"#snippet-{key} summary").click()
    page.locator("label.switch").click()  # back to A, B, C
    fill_triangle(page, *RIGHT)
    expect(page.locator("#code-numpy")).to_contain_text("[0.0, 1.0, 0.0]")
    numpy, python = page.locator("#snippet-numpy"), page.locator("#snippet-python")
    numpy.locator("summary").click()  # close NumPy, keep Pure Python open
    expect(numpy).not_to_have_attribute("open", "")
    expect(python).to_have_attribute("open", "")

    page.locator("#bx").fill("1.25")
    page.locator("#cz").fill("-7.5")
    expect(page.locator("#code-python")).to_contain_text("1.25, 0.0, 0.0")
    expect(page.locator("#code-numpy")).to_contain_text("0.0, 1.0, -7.5")
    expect(page).to_have_url(re.compile(r"bx=1\.25&.*cz=-7\.5"))
    expect(numpy).not_to_have_attribute("open", "")
    expect(python).to_have_attribute("open", "")

    query = triangle_query(("0", "0", "0"), ("1.25", "0", "0"), ("0", "1", "-7.5"))
    want = {s.key: s.code for s in snippets(api_payload(page, query))}
    assert page.locator("#code-python").text_content() == want["python"]
    button = python.locator("button.copy")
    button.click()
    expect(button).to_have_text("Copied")
    assert page.evaluate("navigator.clipboard.readText()") == want["python"]


# --- 4. Presets -------------------------------------------------------------------------------

PRESET_CHECKS = {
    "right": {"unit_normal": "(0, 0, 1)", "order": "order A, B, C", "normal": "(0, 0, 1)"},
    "swapped": {"unit_normal": "(0, 0, −1)", "order": "order A, C, B"},
    "collinear": {"unit_normal": "none (degenerate triangle)", "normal": "(0, 0, 0)"},
    # (3 + 1e-10)(3 - 1e-10) - 9 = -1e-20 for the decimals typed (the doubles give -1.355e-20).
    "sliver": {"unit_normal": "(0, 0, −1)", "normal": "(0, 0, −1e−20)"},
    "huge": {
        "magnitude": "out of range",
        "normal": "(0, 0, out of range)",
        "unit_normal": "(0, 0, 1)",
    },
}
PRESET_PARAMS = {key: params for key, _, _, params in PRESETS}


def check_preset(page: Page, key: str) -> None:
    params = PRESET_PARAMS[key]
    for name, text in PRESET_CHECKS[key].items():
        expect(cell(page, name), key).to_have_text(text)
    for name in FIELDS:
        expect(page.locator(f"#{name}"), key).to_have_value(params[name])
    if params.get("swap") == "on":
        expect(page.locator("#swap")).to_be_checked()
    else:
        expect(page.locator("#swap")).not_to_be_checked()
    if key == "collinear":
        expect(cell(page, "message")).to_be_visible()
        expect(cell(page, "message")).to_have_class(re.compile(r"\bwarn\b"))


def test_presets_load_live_without_a_reload(page: Page) -> None:
    assert list(PRESET_CHECKS) == list(PRESET_PARAMS)
    open_calculator(page)
    mark_window(page)
    for key, params in PRESET_PARAMS.items():
        page.locator(f'a.preset[data-preset="{key}"]').click()
        check_preset(page, key)
        expect(page).to_have_url(re.compile(r"/\?" + re.escape(urlencode(params)) + "$"))
        assert_not_reloaded(page)
    # A live preset then an edit: the swap from "swapped" goes with the next preset.
    page.locator('a.preset[data-preset="swapped"]').click()
    expect(page.locator("#swap")).to_be_checked()
    page.locator('a.preset[data-preset="right"]').click()
    check_preset(page, "right")


def test_presets_work_without_javascript(new_page: NewPage) -> None:
    page = new_page(java_script_enabled=False)
    page.goto("/")
    for key, params in PRESET_PARAMS.items():
        with page.expect_navigation():
            page.locator(f'a.preset[data-preset="{key}"]').click()
        expect(page).to_have_url(re.compile(r"/\?" + re.escape(urlencode(params)) + "$"))
        check_preset(page, key)


# --- 5. Downloads and Copy as JSON ------------------------------------------------------------

SLIVER = PRESET_PARAMS["sliver"]


def test_downloads_carry_the_pages_numbers(new_page: NewPage) -> None:
    page = new_page(**CLIPBOARD)
    query = urlencode(SLIVER)
    open_calculator(page, query)
    shown = page_payload(page)
    api = api_payload(page, query)
    assert shown == api
    # The numbers in the table are the same doubles.
    assert (
        float(
            (cell(page, "magnitude").locator(".num").get_attribute("data-num") or "").replace(
                "−", "-"
            )
        )
        == api["magnitude"]
    )

    button = page.locator('button[data-copy="result-json"]')
    expect(button).to_have_accessible_name("Copy as JSON")
    button.click()
    expect(button).to_have_text("Copied")
    assert json.loads(page.evaluate("navigator.clipboard.readText()")) == api

    with page.expect_download() as info:
        page.locator("#download-json").click()
    download = info.value
    assert download.suggested_filename == "triangle-normal.json"
    assert json.loads(Path(download.path()).read_text()) == api

    with page.expect_download() as info:
        page.locator("#download-csv").click()
    download = info.value
    assert download.suggested_filename == "triangle-normal.csv"
    rows = list(csv.DictReader(io.StringIO(Path(download.path()).read_text())))
    assert len(rows) == 1
    row = rows[0]
    assert row["order"] == api["order"]
    numbers = {
        **{f"{p}{axis}": api[p][i] for p in "abc" for i, axis in enumerate("xyz")},
        **{f"{p}{axis}": api[p][i] for p in "uv" for i, axis in enumerate("xyz")},
        **{f"n{axis}": api["normal"][i] for i, axis in enumerate("xyz")},
        **{f"unit_{axis}": api["unit_normal"][i] for i, axis in enumerate("xyz")},
        "magnitude": api["magnitude"],
        "area": api["area"],
    }
    for column, value in numbers.items():
        assert float(row[column]) == value, column
    assert row["nz"] == "-1e-20"  # the typed decimals, exactly: (3 + 1e-10)(3 - 1e-10) - 9
    assert row["degenerate"] == "false"

    # After a live edit the links and the copied JSON follow.
    fill_triangle(page, *RIGHT)
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")
    with page.expect_download() as info:
        page.locator("#download-json").click()
    assert json.loads(Path(info.value.path()).read_text()) == api_payload(
        page, triangle_query(*RIGHT)
    )


# --- 6. Display precision ---------------------------------------------------------------------

FULL_UNIT = "(0.8571428571428571, 0.42857142857142855, 0.2857142857142857)"


def test_display_precision_rounds_the_text_only_and_persists(new_page: NewPage) -> None:
    page = new_page(locale="en-US")  # a context of its own: localStorage starts empty
    open_calculator(page)
    unit = cell(page, "unit_normal")
    expect(unit).to_have_text(FULL_UNIT)
    page.locator("#precision").select_option("2")
    expect(unit).to_have_text("(0.86, 0.43, 0.29)")
    expect(cell(page, "area")).to_have_text("3.50")
    page.locator("#precision").select_option("full")
    expect(unit).to_have_text(FULL_UNIT)
    expect(cell(page, "area")).to_have_text("3.5")

    page.locator("#precision").select_option("4")
    expect(unit).to_have_text("(0.8571, 0.4286, 0.2857)")
    page.reload()
    expect(page.locator("#precision")).to_have_value("4")
    expect(unit).to_have_text("(0.8571, 0.4286, 0.2857)")
    assert page.evaluate("localStorage.getItem('precision')") == "4"

    # Live updates keep the choice; downloads keep every digit.
    fill_triangle(page, ("0", "0", "0"), ("3", "0", "0"), ("0", "7", "1"))
    expect(cell(page, "normal")).to_have_text("(0.0000, −3.0000, 21.0000)")  # zero too
    with page.expect_download() as info:
        page.locator("#download-json").click()
    saved = json.loads(Path(info.value.path()).read_text())
    assert saved == api_payload(
        page, triangle_query(("0", "0", "0"), ("3", "0", "0"), ("0", "7", "1"))
    )
    assert saved["unit_normal"][1] == -3 / math.sqrt(450)
    expect(unit).to_have_text("(0.0000, −0.1414, 0.9899)")


# --- 7. Phone ---------------------------------------------------------------------------------


def check_phone_layout(page: Page, width: int) -> None:
    page.evaluate("() => window.scrollTo(0, document.documentElement.scrollHeight)")
    scroll_width, inner = page.evaluate(
        "() => [document.documentElement.scrollWidth, window.innerWidth]"
    )
    assert inner == width
    assert scroll_width <= width, f"the page scrolls sideways at {width}: {scroll_width}"
    too_wide = page.evaluate(
        """(width) => [...document.querySelectorAll('section, .card, pre, .math, .js-plotly-plot')]
              .filter((el) => el.getBoundingClientRect().right > width + 0.5)
              .map((el) => el.id || el.className)""",
        width,
    )
    assert not too_wide, (width, too_wide)
    for locator in (page.locator("a.preset"), page.locator("button.copy")):
        assert locator.count() >= 5
        for index in range(locator.count()):
            box = locator.nth(index).bounding_box()
            assert box is not None and box["height"] >= 36, (width, index, box)


def test_phone_layout_has_no_sideways_scroll_and_big_targets(new_page: NewPage) -> None:
    page = new_page(
        viewport={"width": 390, "height": 844},
        device_scale_factor=2,
        is_mobile=True,
        has_touch=True,
    )
    open_calculator(page)
    page.evaluate("() => document.querySelectorAll('#code details').forEach(d => d.open = true)")
    page.evaluate("() => window.scrollTo(0, document.documentElement.scrollHeight)")
    show_3d(page)
    check_phone_layout(page, 390)
    page.set_viewport_size({"width": 360, "height": 740})
    # Plotly resizes the drawn views (responsive) for the narrower screen.
    page.wait_for_function("""() => [
        ...document.querySelectorAll('#chart .main-svg, #view3d canvas')
    ].every((el) => el.getBoundingClientRect().right <= 360)""")
    check_phone_layout(page, 360)


# --- 8. Keyboard ------------------------------------------------------------------------------

FOCUSED = """() => { const el = document.activeElement;
    return el.id || (el.dataset && el.dataset.preset && 'preset:' + el.dataset.preset)
           || el.tagName + ':' + (el.textContent || '').trim().slice(0, 20); }"""


def test_keyboard_reaches_the_controls_and_enter_loads_a_preset(page: Page) -> None:
    open_calculator(page)
    mark_window(page)
    page.locator("body").focus()
    seen: list[str] = []
    for _ in range(40):
        page.keyboard.press("Tab")
        seen.append(page.evaluate(FOCUSED))
        if seen[-1] == "preset:huge":
            break
    want = [*FIELDS, "swap", "BUTTON:Calculate", *(f"preset:{key}" for key in PRESET_PARAMS)]
    positions = [seen.index(name) if name in seen else -1 for name in want]
    assert -1 not in positions, (want, seen)
    assert positions == sorted(positions), seen

    # Back to the sliver preset with Shift+Tab, then Enter.
    for _ in range(2):
        page.keyboard.press("Shift+Tab")
    assert page.evaluate(FOCUSED) == "preset:collinear"
    page.keyboard.press("Enter")
    check_preset(page, "collinear")
    page.keyboard.press("Tab")
    assert page.evaluate(FOCUSED) == "preset:sliver"
    page.keyboard.press("Enter")
    check_preset(page, "sliver")
    expect(page).to_have_url(
        query_pattern(*(tuple(SLIVER[f"{p}{a}"] for a in "xyz") for p in "abc"))
    )
    assert_not_reloaded(page)
