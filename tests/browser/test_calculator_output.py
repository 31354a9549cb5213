"""The calculator's output in Chromium: steps typeset as MathML, labels that follow the
precision, out-of-range values marked on the chart, and the print stylesheet."""

from __future__ import annotations

import re
from urllib.parse import urlencode

import pytest
from playwright.sync_api import Page, expect

from app.calculator.presets import PRESETS
from tests.browser.conftest import NewPage
from tests.browser.helpers import cell, open_calculator, triangle_query

pytestmark = pytest.mark.browser

EXAMPLE = triangle_query(("1", "0", "0"), ("0", "2", "0"), ("0", "0", "3"))
HUGE = urlencode(next(params for key, _, _, params in PRESETS if key == "huge"))


def chart_labels(page: Page) -> object:
    return page.evaluate("() => document.getElementById('chart').data[0].text")


def test_steps_are_typeset_mathematics_with_real_size(page: Page) -> None:
    open_calculator(page, EXAMPLE)
    formulas = page.locator("#steps math")
    assert formulas.count() >= 20
    # Chromium lays MathML out natively: every formula has a box, and a determinant (a
    # matrix between bars) is taller than a line of text.
    sizes = formulas.evaluate_all("els => els.map(e => e.getBoundingClientRect().toJSON())")
    assert all(box["width"] > 5 and box["height"] >= 8 for box in sizes), sizes
    line = page.locator('#steps .formula[data-formula="u = B − A"] math').bounding_box()
    determinant = page.locator('#steps [data-step="cross"] mtable').first.bounding_box()
    root = page.locator('#steps [data-step="magnitude"] msqrt').first.bounding_box()
    assert line and determinant and root
    assert determinant["height"] > 1.8 * line["height"]
    assert root["width"] > 20
    assert page.locator("#steps code").count() == 0
    # Not the monospace font of code.
    family = formulas.first.evaluate("e => getComputedStyle(e).fontFamily")
    assert "Math" in family and "mono" not in family.lower()


def test_steps_and_chart_labels_follow_the_precision(page: Page) -> None:
    open_calculator(page, EXAMPLE + "&swap=on")
    assert chart_labels(page) == ["−6", "−3", "−2", "7", "3.5"]
    unit_x = page.locator('#steps [data-step="unit"] mn.num', has_text="0.857").first
    expect(unit_x).to_have_text("−0.8571428571428571")
    page.locator("#precision").select_option("4")
    expect(unit_x).to_have_text("−0.8571")
    expect(cell(page, "normal")).to_have_text("(−6.0000, −3.0000, −2.0000)")
    page.wait_for_function(
        "() => document.getElementById('chart').data[0].text[0] === '−6.0000'", timeout=5000
    )
    assert chart_labels(page) == ["−6.0000", "−3.0000", "−2.0000", "7.0000", "3.5000"]
    drawn = page.locator("#chart .bartext").all_text_contents()
    assert "−6.0000" in drawn and "3.5000" in drawn
    size = page.locator("#chart .bartext").first.evaluate("e => parseFloat(e.style.fontSize)")
    assert size >= 12  # readable, never squeezed into its bar
    page.locator("#precision").select_option("full")
    expect(unit_x).to_have_text("−0.8571428571428571")


def test_huge_values_are_marked_on_the_chart(page: Page) -> None:
    open_calculator(page, HUGE)
    traces = page.evaluate("() => document.getElementById('chart').data.length")
    assert traces == 2  # the values and the hatched bars beyond the double range
    drawn = " ".join(page.locator("#chart .bartext").all_text_contents())
    assert drawn.count("beyond 1.8e308") == 3
    expect(page.locator("#chart .annotation-text")).to_contain_text("beyond the double range")
    bars = page.locator("#chart .bars path").evaluate_all(
        "els => els.filter(e => e.getBBox().width > 5).length"
    )
    assert bars >= 3  # n_z, |n| and the area are drawn, not left out


def test_print_shows_the_question_the_answer_and_the_steps_only(page: Page) -> None:
    open_calculator(page, EXAMPLE)
    page.emulate_media(media="print")
    for hidden in (
        ".site-header nav",
        "#calculator .actions",
        ".presets",
        ".precision",
        ".result-actions",
        ".view3d-card",
        ".code-card",
        ".embed-card",
        ".modebar-container",
        ".chart-card",
    ):
        for index in range(page.locator(hidden).count()):
            expect(page.locator(hidden).nth(index)).to_be_hidden()
    for shown in ("#ax", "#cz", "#result", "#steps", '#steps [data-formula="6x + 3y + 2z = 6"]'):
        expect(page.locator(shown)).to_be_visible()
    # The inputs read as text: no box around them.
    assert page.locator("#ax").evaluate("e => getComputedStyle(e).borderTopStyle") == "none"
    assert page.locator(".steps").evaluate("e => getComputedStyle(e).columnCount") == "2"
    # "Save as PDF" gives one A4 page, steps included.
    pdf = page.pdf(format="A4")
    assert len(re.findall(rb"/Type\s*/Page[^s]", pdf)) == 1
    page.emulate_media(media="screen")
    expect(page.locator(".presets")).to_be_visible()


def test_a_long_chain_wraps_before_an_equals_sign_on_a_phone(new_page: NewPage) -> None:
    page = new_page(viewport={"width": 390, "height": 844})
    open_calculator(page, EXAMPLE)
    width = page.evaluate("document.documentElement.scrollWidth")
    assert width <= 390
    formula = page.locator('#steps [data-step="magnitude"] .formula')
    pieces = formula.locator("math").evaluate_all(
        "els => els.map(e => Math.round(e.getBoundingClientRect().top))"
    )
    assert len(set(pieces)) > 1, pieces  # on more than one line
    assert formula.evaluate("e => e.scrollWidth <= e.clientWidth")  # and none cut off
