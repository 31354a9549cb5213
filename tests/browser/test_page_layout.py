"""The calculator's layout and keyboard paths: result on a phone's first screen, a skip link,
chart toolbars out of the Tab order, the 3D view's touch hint and its toolbar beside the title."""

from __future__ import annotations

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import NewPage
from tests.browser.helpers import open_calculator

pytestmark = pytest.mark.browser

PHONE = {"viewport": {"width": 390, "height": 844}, "is_mobile": True, "has_touch": True}

BOX = (
    "(selector) => { const r = document.querySelector(selector).getBoundingClientRect(); "
    "return {top: r.top, bottom: r.bottom, left: r.left, right: r.right}; }"
)

IN_TOOLBAR = "() => Boolean(document.activeElement.closest('.modebar'))"


def box(page: Page, selector: str) -> dict[str, float]:
    return page.evaluate(BOX, selector)


def show_3d(page: Page) -> None:
    page.locator("#view3d").scroll_into_view_if_needed()
    page.locator("#view3d[data-drawn]").wait_for(timeout=20_000)


def test_phone_shows_the_result_on_the_first_screen(new_page: NewPage) -> None:
    page = new_page(**PHONE)
    open_calculator(page)
    result = box(page, "#result-card")
    assert result["top"] < 700, result  # it was 1,087 px down, below the presets
    assert box(page, ".presets-card")["top"] > result["bottom"]  # the presets come after


def test_desktop_keeps_the_presets_under_the_form_and_the_result_beside_it(page: Page) -> None:
    open_calculator(page)
    form, result = box(page, ".form-card"), box(page, "#result-card")
    presets = box(page, ".presets-card")
    assert result["top"] == form["top"] and result["left"] > form["right"]
    assert (
        0 < presets["top"] - form["bottom"] <= 17
    )  # one grid gap (1rem), however tall the right column
    assert presets["left"] == form["left"]


def test_the_skip_link_is_the_first_tab_stop_and_moves_focus_to_the_result(page: Page) -> None:
    open_calculator(page)
    link = page.get_by_role("link", name="Skip to result")
    expect(link).not_to_be_in_viewport()  # out of sight until it has focus
    page.locator("body").focus()
    page.keyboard.press("Tab")
    expect(link).to_be_focused()
    expect(link).to_be_in_viewport()
    page.keyboard.press("Enter")
    expect(page.locator("#result-card")).to_be_focused()
    page.keyboard.press("Tab")  # the next stop is the result's own first control
    expect(page.locator("#precision")).to_be_focused()


def test_tab_from_the_last_input_never_enters_a_chart_toolbar(page: Page) -> None:
    open_calculator(page)
    show_3d(page)
    page.locator("#chart").hover()  # Plotly adds the bar chart's toolbar once the page is idle
    page.locator("#chart .modebar-btn").first.wait_for(state="attached")
    page.locator("#view3d .modebar-btn").first.wait_for(state="attached")
    page.locator("#cz").focus()
    for _ in range(30):
        page.keyboard.press("Tab")
        assert not page.evaluate(IN_TOOLBAR), page.evaluate("document.activeElement.outerHTML")
    toggles = page.locator("button.chart-tools")
    expect(toggles).to_have_count(2)  # one for the chart, one for the 3D view


def test_the_chart_tools_button_opens_the_toolbar_to_the_keyboard(page: Page) -> None:
    open_calculator(page)
    page.locator("#chart").hover()
    page.locator("#chart .modebar-btn").first.wait_for(state="attached")
    toggle = page.locator(".chart-card button.chart-tools")
    toggle.focus()
    expect(toggle).to_be_in_viewport()
    page.keyboard.press("Enter")
    assert page.evaluate(IN_TOOLBAR)
    page.keyboard.press("Tab")
    assert page.evaluate(IN_TOOLBAR)  # its buttons follow one another
    page.keyboard.press("Escape")
    expect(toggle).to_be_focused()
    tabindexes = page.locator("#chart .modebar-btn").evaluate_all(
        "buttons => buttons.map(b => b.getAttribute('tabindex'))"
    )
    assert set(tabindexes) == {"-1"}, tabindexes


def test_the_3d_hint_says_pinch_on_a_touch_screen(new_page: NewPage) -> None:
    mouse = new_page()
    open_calculator(mouse)
    expect(mouse.locator("#view3d-hint")).to_have_text("(drag to rotate, scroll to zoom)")
    touch = new_page(**PHONE)
    open_calculator(touch)
    assert touch.evaluate("matchMedia('(pointer: coarse)').matches")
    expect(touch.locator("#view3d-hint")).to_have_text("(drag to rotate, pinch to zoom)")


@pytest.mark.parametrize("width", [390, 1280])
def test_the_3d_toolbar_does_not_cover_its_title(new_page: NewPage, width: int) -> None:
    page = new_page(viewport={"width": width, "height": 900})
    open_calculator(page)
    show_3d(page)
    page.locator("#view3d").hover()
    page.locator("#view3d .modebar").wait_for()
    title, toolbar = box(page, "#view3d .gtitle"), box(page, "#view3d .modebar")
    assert title["right"] > title["left"] > 0
    apart = toolbar["left"] >= title["right"] or toolbar["top"] >= title["bottom"]
    assert apart, (title, toolbar)


def test_the_mesh_views_hint_says_pinch_on_a_touch_screen(new_page: NewPage) -> None:
    for options, shown, hidden, words in (
        ({}, ".hint-mouse", ".hint-touch", "(drag to rotate, scroll to zoom)"),
        (PHONE, ".hint-touch", ".hint-mouse", "(drag to rotate, pinch to zoom)"),
    ):
        page = new_page(**options)
        response = page.goto("/mesh/sample/cube")
        assert response is not None and response.status == 200
        title = page.locator("#mesh-view-title")
        expect(title.locator(shown)).to_be_visible()
        expect(title.locator(shown)).to_have_text(words)
        expect(title.locator(hidden)).to_be_hidden()
