"""With JavaScript off the form still works: a GET submit and a page rendered by the server."""

from __future__ import annotations

import json
import re

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import ConsoleWatch, NewPage
from tests.browser.helpers import FIELDS, RIGHT, cell, fill_triangle, query_pattern

pytestmark = pytest.mark.browser


@pytest.fixture
def no_js_page(new_page: NewPage) -> Page:
    page = new_page(java_script_enabled=False)
    response = page.goto("/")
    assert response is not None and response.status == 200
    return page


def submit(page: Page) -> int:
    with page.expect_response(re.compile(r"/\?ax=")) as answer:
        page.get_by_role("button", name="Calculate").click()
    page.wait_for_load_state()
    return answer.value.status


def test_submit_renders_the_result_on_the_server(no_js_page: Page) -> None:
    page = no_js_page
    assert page.evaluate("1 + 1") == 2  # evaluate still works; the page's own scripts do not
    expect(page.locator("noscript")).to_have_count(2)  # the chart and the 3D view
    expect(page.locator("#chart[data-drawn]")).to_have_count(0)

    fill_triangle(page, *RIGHT)
    assert submit(page) == 200
    expect(page).to_have_url(query_pattern(*RIGHT))
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")
    expect(cell(page, "unit_normal")).to_have_text("(0, 0, 1)")
    expect(cell(page, "area")).to_have_text("0.5")
    expect(cell(page, "order")).to_have_text("order A, B, C")
    expect(cell(page, "invalid")).to_be_hidden()
    for name, value in zip(FIELDS, [*RIGHT[0], *RIGHT[1], *RIGHT[2]], strict=True):
        expect(page.locator(f"#{name}")).to_have_value(value)
    # The chart data is in the page for later, and the links follow the query.
    figure = json.loads(page.locator("#figure-data").text_content() or "null")
    assert figure["data"][0]["x"] == [0, 0, 1, 1, 0.5]
    expect(page.locator("#json-link")).to_have_attribute("href", re.compile(r"bx=1&"))

    page.locator("label.switch").click()
    expect(page.locator("#swap")).to_be_checked()
    assert submit(page) == 200
    expect(page).to_have_url(re.compile(r"[?&]swap=on(&|$)"))
    expect(page.locator("#swap")).to_be_checked()
    expect(cell(page, "normal")).to_have_text("(0, 0, −1)")
    expect(cell(page, "order")).to_have_text("order A, C, B")


def test_typo_is_named_beside_the_field_and_kept(no_js_page: Page, console: ConsoleWatch) -> None:
    # The page answers 422 on purpose; Chromium logs every 4xx document as a console error.
    console.allow(r"status of 422 \(Unprocessable Entity\) \(http://[^)]*/\?ax=")
    page = no_js_page
    fill_triangle(page, *RIGHT)
    page.locator("#bx").fill("1..2")
    page.locator("#cz").fill("")
    assert submit(page) == 422

    bx_error = page.locator('[data-error-for="bx"]')
    expect(bx_error).to_be_visible()
    expect(bx_error).to_have_text("B.x must be a number such as 1.5, -2e3 or 1/3, not '1..2'.")
    expect(page.locator("#bx")).to_have_value("1..2")
    expect(page.locator("#bx")).to_have_attribute("aria-invalid", "true")
    # A blank field is not given yet: one calm line, not an error.
    expect(page.locator('[data-error-for="cz"]')).to_have_text("")
    expect(page.locator("#missing-note")).to_have_text("C.z is missing.")
    expect(page.locator("#cz")).not_to_have_attribute("aria-invalid", "true")
    expect(page.locator("#ax")).not_to_have_attribute("aria-invalid", "true")
    expect(cell(page, "invalid")).to_have_text("Fix the highlighted field to see the normal.")
    expect(cell(page, "normal")).to_have_text("—")

    page.locator("#bx").fill("1")
    page.locator("#cz").fill("0")
    assert submit(page) == 200
    expect(bx_error).to_be_hidden()
    expect(page.locator("#bx")).not_to_have_attribute("aria-invalid", "true")
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")


def test_steps_are_typeset_without_javascript(no_js_page: Page) -> None:
    # MathML is the browser's own: the server's steps need no script to look like maths.
    page = no_js_page
    cross = page.locator('#steps [data-step="cross"]')
    # The 3×3 twice, three 2×2 twice (names, then numbers), and n as a column.
    expect(cross.locator("mtable")).to_have_count(9)
    box = cross.locator("mtable").first.bounding_box()
    assert box is not None and box["width"] > 40 and box["height"] > 40
    root = page.locator('#steps [data-step="magnitude"] msqrt').first.bounding_box()
    assert root is not None and root["width"] > 20
    # The full numbers, with the real minus sign, as the server wrote them.
    expect(page.locator('#steps [data-formula="u = (−1, 2, 0)"]')).to_be_visible()
