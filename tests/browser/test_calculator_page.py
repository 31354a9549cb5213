"""The calculator page in Chromium: live results, chart, permalink, swap, typing mistakes."""

from __future__ import annotations

import html
import re

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import ConsoleWatch, NewPage
from tests.browser.helpers import (
    COLLINEAR,
    FETCH_GATE,
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


def test_page_loads_without_console_errors(page: Page) -> None:
    open_calculator(page)
    expect(page).to_have_title(re.compile("Triangle normal calculator"))
    for name in FIELDS:
        expect(page.locator(f"#{name}")).to_be_editable()
    # The example triangle is rendered, and Plotly drew it once the page was ready.
    expect(cell(page, "normal")).to_have_text("(6, 3, 2)")
    assert page.evaluate("typeof window.__chartDrawnAt") == "number"
    expect(page.locator("#json-link")).to_have_attribute("href", re.compile(r"^/api/normal\?ax="))


def test_typing_a_triangle_updates_result_chart_and_address(page: Page) -> None:
    open_calculator(page)
    fill_triangle(page, *RIGHT)

    wait_for_chart_values(page, [0, 0, 1, 1, 0.5])  # the page fills the table before the chart
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")
    expect(cell(page, "unit_normal")).to_have_text("(0, 0, 1)")
    expect(cell(page, "area")).to_have_text("0.5")
    expect(cell(page, "magnitude")).to_have_text("1")
    expect(cell(page, "u")).to_have_text("(1, 0, 0)")
    expect(cell(page, "v")).to_have_text("(0, 1, 0)")
    expect(cell(page, "order")).to_have_text("order A, B, C")
    expect(cell(page, "message")).to_be_hidden()

    query = triangle_query(*RIGHT)
    expect(page).to_have_url(query_pattern(*RIGHT))
    expect(page.locator("#json-link")).to_have_attribute("href", f"/api/normal?{query}")
    expect(page.locator("#embed-code")).to_have_value(re.compile(re.escape(f'/embed?{query}"')))

    # The address is a permalink: loading it renders the same result on the server.
    response = page.reload()
    assert response is not None and response.status == 200
    html = response.text()
    assert server_cells(html)["normal"] == "(0, 0, 1)"
    assert server_cells(html)["unit_normal"] == "(0, 0, 1)"
    assert server_cells(html)["area"] == "0.5"
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")
    for name, value in zip(FIELDS, [*RIGHT[0], *RIGHT[1], *RIGHT[2]], strict=True):
        expect(page.locator(f"#{name}")).to_have_value(value)
    wait_for_chart_values(page, [0, 0, 1, 1, 0.5])


def test_swap_winding_flips_the_normal_and_back(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    swap = page.locator("#swap")
    expect(swap).not_to_be_checked()

    page.locator("label.switch").click()  # the checkbox itself is visually hidden
    expect(swap).to_be_checked()
    wait_for_chart_values(page, [0, 0, -1, 1, 0.5])
    expect(cell(page, "normal")).to_have_text("(0, 0, −1)")
    expect(cell(page, "unit_normal")).to_have_text("(0, 0, −1)")
    expect(cell(page, "order")).to_have_text("order A, C, B")
    expect(cell(page, "u-from")).to_have_text("C")
    expect(cell(page, "v-from")).to_have_text("B")
    expect(cell(page, "area")).to_have_text("0.5")
    expect(page).to_have_url(re.compile(r"[?&]swap=on(&|$)"))

    # The permalink keeps the swap: the server renders it checked and flipped.
    response = page.reload()
    assert response is not None and response.status == 200
    assert server_cells(response.text())["normal"] == "(0, 0, −1)"
    expect(swap).to_be_checked()
    wait_for_chart_values(page, [0, 0, -1, 1, 0.5])

    # And back, from the keyboard this time: Tab from the last field, then Space.
    page.locator("#cz").focus()
    page.keyboard.press("Tab")
    expect(swap).to_be_focused()
    page.keyboard.press("Space")
    expect(page.get_by_role("switch", name=re.compile("Swap winding"))).not_to_be_checked()
    wait_for_chart_values(page, [0, 0, 1, 1, 0.5])
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")
    expect(cell(page, "order")).to_have_text("order A, B, C")
    expect(page).not_to_have_url(re.compile("swap="))


def test_typing_mistake_is_named_beside_the_field_and_clears_when_fixed(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    bx = page.locator("#bx")
    error = page.locator('[data-error-for="bx"]')
    expect(error).to_be_hidden()
    expect(bx).to_have_attribute("aria-describedby", "bx-error")
    expect(error).to_have_attribute("id", "bx-error")

    bx.fill("")
    bx.press_sequentially("1..2")
    expect(error).to_have_text("B.x must be a number such as 1.5, -2e3 or 1/3, not '1..2'.")
    expect(error).to_be_visible()
    expect(bx).to_have_attribute("aria-invalid", "true")
    expect(bx).to_have_value("1..2")
    expect(cell(page, "invalid")).to_be_visible()
    expect(cell(page, "invalid")).to_have_text("Fix the highlighted field to see the normal.")
    expect(page.locator("#result")).to_have_class(re.compile(r"\bstale\b"))
    for name in FIELDS:  # only bx is blamed
        if name != "bx":
            expect(page.locator(f"#{name}")).not_to_have_attribute("aria-invalid", "true")
    # What was typed stays in the permalink, so a reload shows the same mistake.
    expect(page).to_have_url(re.compile(r"[?&]bx=1\.\.2(&|$)"))

    # An emptied field is not a mistake, only not given yet: a calm line, nothing red.
    page.locator("#cz").fill("")
    expect(page.locator("#missing-note")).to_have_text("C.z is missing.")
    expect(page.locator('[data-error-for="cz"]')).to_have_text("")
    expect(page.locator("#cz")).not_to_have_attribute("aria-invalid", "true")
    expect(cell(page, "invalid")).to_have_text("Fix the highlighted field to see the normal.")
    page.locator("#by").fill("x")  # a second mistake: the notice counts both
    expect(cell(page, "invalid")).to_have_text("Fix the highlighted fields to see the normal.")
    page.locator("#by").fill("1")

    page.locator("#cz").fill("0")
    bx.fill("2")
    wait_for_chart_values(page, [0, 0, 2, 2, 1])
    expect(error).to_be_hidden()
    expect(error).to_have_text("")
    expect(bx).not_to_have_attribute("aria-invalid", "true")
    expect(page.locator("#cz")).not_to_have_attribute("aria-invalid", "true")
    expect(cell(page, "invalid")).to_be_hidden()
    expect(page.locator("#missing-note")).to_be_hidden()
    expect(page.locator("#result")).not_to_have_class(re.compile(r"\bstale\b"))
    expect(cell(page, "normal")).to_have_text("(0, 0, 2)")
    expect(cell(page, "area")).to_have_text("1")


def test_degenerate_triangle_says_so(page: Page) -> None:
    open_calculator(page)
    fill_triangle(page, *COLLINEAR)
    wait_for_chart_values(page, [0, 0, 0, 0, 0])
    expect(cell(page, "normal")).to_have_text("(0, 0, 0)")
    expect(cell(page, "unit_normal")).to_have_text("none (degenerate triangle)")
    expect(cell(page, "area")).to_have_text("0")
    message = cell(page, "message")
    expect(message).to_be_visible()
    expect(message).to_have_class(re.compile(r"\bwarn\b"))
    expect(message).not_to_have_text("")

    # Back to a proper triangle: the warning goes away.
    fill_triangle(page, *RIGHT)
    wait_for_chart_values(page, [0, 0, 1, 1, 0.5])
    expect(cell(page, "unit_normal")).to_have_text("(0, 0, 1)")
    expect(message).to_be_hidden()


def test_copy_button_copies_the_embed_code(new_page: NewPage, base_url: str) -> None:
    page = new_page(permissions=["clipboard-read", "clipboard-write"])
    open_calculator(page, triangle_query(*RIGHT))
    button = page.locator('button[data-copy="embed-code"]')
    expect(button).to_have_text("Copy")
    button.click()
    expect(button).to_have_text("Copied")
    copied = page.evaluate("navigator.clipboard.readText()")
    assert copied == page.locator("#embed-code").input_value()
    assert f'src="{base_url}/embed?{triangle_query(*RIGHT)}"' in copied


NUMBER_CASES = {
    # Tiny, huge and negative values: JavaScript's String(x) exponent layout.
    "tiny": (
        (("0", "0", "0"), ("1e-4", "0", "0"), ("0", "1e-4", "0")),
        {"normal": "(0, 0, 1e−8)", "area": "5e−9", "u": "(0.0001, 0, 0)"},
    ),
    "huge": (
        (("0", "0", "0"), ("1e11", "0", "0"), ("0", "-1e11", "0")),
        {"normal": "(0, 0, −1e+22)", "magnitude": "1e+22", "area": "5e+21"},
    ),
    "decimals": (
        (("0.1", "0.2", "0.3"), ("1.5", "-2.25", "3"), ("-1", "0.5", "2e3")),
        {"u": "(1.4, −2.45, 2.7)"},
    ),
    # Beyond the double range: said in words, never Infinity.
    "out of range": (
        (("0", "0", "0"), ("1e200", "0", "0"), ("0", "1e200", "0")),
        {"normal": "(0, 0, out of range)", "magnitude": "out of range"},
    ),
}
RESULT_KEYS = ("order", "u", "v", "normal", "magnitude", "unit_normal", "area", "message")


def served_cells(page: Page) -> dict[str, str]:
    """The result cells as the server renders them for the page's current address."""
    answer = page.request.get(page.url)
    assert answer.status == 200, answer.status
    return server_cells(answer.text())


def server_cells(text: str) -> dict[str, str]:
    """The text of each result cell in server-rendered HTML (number spans included)."""
    cells = {}
    for key in RESULT_KEYS:
        found = re.search(rf'<(\w+)[^>]*data-key="{key}"[^>]*>(.*?)</\1>', text, re.S)
        assert found, key
        cells[key] = html.unescape(re.sub(r"<[^>]+>", "", found.group(2))).strip()
    return cells


def test_live_and_server_rendering_write_numbers_alike(page: Page) -> None:
    open_calculator(page)
    for case, ((a, b, c), expected) in NUMBER_CASES.items():
        fill_triangle(page, a, b, c)
        expect(page).to_have_url(query_pattern(a, b, c))
        for key, text in expected.items():
            expect(cell(page, key), case).to_have_text(text)
        # The cells checked above may be right already for a query typed on the way there:
        # wait for every cell to read as the server renders the final address.
        served = served_cells(page)
        for key in RESULT_KEYS:
            expect(cell(page, key), case).to_have_text(served[key])
        live = {key: cell(page, key).inner_text().strip() for key in RESULT_KEYS}
        assert "Infinity" not in str(live) and "NaN" not in str(live), (case, live)
        assert served == live, case


def test_a_slow_answer_does_not_overwrite_a_later_typing_mistake(page: Page) -> None:
    """Type a valid value, then a mistake while the first answer is still on its way."""
    page.add_init_script(FETCH_GATE)
    open_calculator(page, triangle_query(*RIGHT))
    page.evaluate("window.__holdFetches = true")

    page.locator("#bx").fill("5")  # valid: the page asks the API, and the answer is held back
    page.wait_for_function("() => window.__held >= 1")
    page.locator("#bx").fill("5..")  # a mistake, caught in the browser without a request
    expect(page.locator('[data-error-for="bx"]')).to_contain_text("'5..'")
    expect(cell(page, "invalid")).to_be_visible()

    page.evaluate("window.__openGate()")  # now the answer for bx=5 arrives
    page.wait_for_function("() => window.__settled >= 1")
    # The page has handled the late answer; nothing else is pending, so look once.
    assert page.locator("#bx").input_value() == "5.."
    assert "'5..'" in page.locator('[data-error-for="bx"]').inner_text()
    # The result must not claim to be the answer for what is in the form.
    assert cell(page, "invalid").is_visible(), (
        "the late answer for bx=5 replaced the 'Fix the highlighted field' notice; the table "
        f"shows normal {cell(page, 'normal').inner_text()} while bx holds '5..'"
    )
    assert "stale" in (page.locator("#result").get_attribute("class") or "")


def test_permalink_with_a_typo_renders_the_error_and_recovers_live(
    page: Page, console: ConsoleWatch
) -> None:
    # The page answers 422 on purpose; Chromium logs every 4xx document as a console error.
    console.allow(r"status of 422 \(Unprocessable Entity\) \(http://[^)]*/\?ax=")
    query = triangle_query(("0", "0", "0"), ("1..2", "0", "0"), ("0", "1", "0"))
    response = page.goto(f"/?{query}")
    assert response is not None and response.status == 422
    expect(page.locator('[data-error-for="bx"]')).to_contain_text("'1..2'")
    expect(page.locator("#bx")).to_have_value("1..2")
    expect(page.locator("#bx")).to_have_attribute("aria-invalid", "true")
    expect(cell(page, "invalid")).to_have_text("Fix the highlighted field to see the normal.")
    expect(cell(page, "normal")).to_have_text("—")
    expect(page.locator("#chart .main-svg")).to_have_count(0)  # no figure to draw yet

    page.locator("#bx").fill("1")
    wait_for_chart_values(page, [0, 0, 1, 1, 0.5])
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")
    expect(cell(page, "order")).to_have_text("order A, B, C")
    expect(cell(page, "invalid")).to_be_hidden()
    expect(page.locator("#bx")).not_to_have_attribute("aria-invalid", "true")
    expect(page).to_have_url(query_pattern(*RIGHT))


def test_one_wrong_value_is_one_error_and_the_rest_one_calm_line(
    page: Page, console: ConsoleWatch
) -> None:
    console.allow(r"status of 422 \(Unprocessable Entity\) \(http://[^)]*/\?ax=")
    response = page.goto("/?ax=1e999")
    assert response is not None and response.status == 422
    expect(page.locator('[aria-invalid="true"]')).to_have_count(1)
    expect(page.locator("#ax")).to_have_attribute("aria-invalid", "true")
    expect(page.locator(".field-error:not(:empty)")).to_have_count(1)
    expect(page.locator('[data-error-for="ax"]')).to_have_text(
        "A.x is beyond the double range (about ±1.8e308)."
    )
    note = page.locator("#missing-note")
    expect(note).to_have_text("A.y, A.z, B.x, B.y, B.z, C.x, C.y and C.z are missing.")
    expect(note).to_be_visible()

    # Typing keeps it so: the fields still blank are not blamed, the line shrinks.
    page.locator("#ax").fill("1")
    page.locator("#ay").fill("0")
    expect(note).to_have_text("A.z, B.x, B.y, B.z, C.x, C.y and C.z are missing.")
    expect(page.locator('[aria-invalid="true"]')).to_have_count(0)
    expect(cell(page, "invalid")).to_have_text("Fill in every coordinate to see the normal.")
    expect(cell(page, "invalid")).not_to_have_class(re.compile(r"\berror\b"))
    for name, value in zip(FIELDS[2:], ["0", "0", "2", "0", "0", "0", "3"], strict=True):
        page.locator(f"#{name}").fill(value)
    expect(note).to_be_hidden()
    expect(cell(page, "invalid")).to_be_hidden()
    expect(cell(page, "normal")).to_have_text("(6, 3, 2)")


def paste(page: Page, field: str, text: str) -> bool:
    """Paste ``text`` into a field as the browser does; whether the page took the paste over."""
    page.locator(f"#{field}").focus()
    return page.evaluate(
        """([field, text]) => {
            const data = new DataTransfer();
            data.setData("text/plain", text);
            const options = {clipboardData: data, bubbles: true, cancelable: true};
            const event = new ClipboardEvent("paste", options);
            document.getElementById(field).dispatchEvent(event);
            return event.defaultPrevented;
        }""",
        [field, text],
    )


def values(page: Page) -> list[str]:
    return [page.locator(f"#{name}").input_value() for name in FIELDS]


@pytest.mark.parametrize("text", ["1, 2, 3", "1 2 3", "(1, 2, 3)", "1\t2\t3", "[1,2,3]"])
def test_pasting_a_point_into_one_field_fills_its_x_y_and_z(page: Page, text: str) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    assert paste(page, "by", text)  # into B's middle field: B is (1, 2, 3) now
    assert values(page) == ["0", "0", "0", "1", "2", "3", "0", "1", "0"]
    wait_for_chart_values(page, [-3, 0, 1, 10**0.5, 10**0.5 / 2])
    expect(cell(page, "normal")).to_have_text("(−3, 0, 1)")
    expect(page).to_have_url(re.compile(r"[?&]bx=1&by=2&bz=3(&|$)"))


def test_pasting_nine_numbers_fills_every_field(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    paste(page, "cz", "1 0 0\n0 2 0\n0 0 3")  # rows of a spreadsheet, say
    assert values(page) == ["1", "0", "0", "0", "2", "0", "0", "0", "3"]
    expect(cell(page, "normal")).to_have_text("(6, 3, 2)")


def test_pasting_decimal_commas_and_fractions(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    paste(page, "cx", "0; 1/3; 0")
    paste(page, "bx", "2,5 0 0")
    assert values(page) == ["0", "0", "0", "2,5", "0", "0", "0", "1/3", "0"]
    expect(cell(page, "normal")).to_have_text("(0, 0, 0.8333333333333334)")  # 5/6, rounded once
    expect(page.locator('[aria-invalid="true"]')).to_have_count(0)


def test_pasting_one_number_or_words_is_an_ordinary_paste(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    assert not paste(page, "ay", "1, 2")  # two numbers are no point: the browser pastes
    assert not paste(page, "az", "abc def ghi")
    assert values(page)[3:] == ["1", "0", "0", "0", "1", "0"]  # B and C untouched


def test_fraction_typed_live_and_division_by_zero(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    page.locator("#bx").fill("1/3")
    page.locator("#cy").fill("1/15")
    expect(cell(page, "normal")).to_have_text("(0, 0, 0.022222222222222223)")  # 1/45
    page.locator("#cy").fill("1/0")
    expect(page.locator('[data-error-for="cy"]')).to_have_text(
        "C.y divides by zero; a fraction's denominator must not be 0."
    )
    expect(page.locator("#cy")).to_have_attribute("aria-invalid", "true")


STALE_PARTS = ("#result", "#steps", "#code", "#chart", "#view3d")


def opacity(page: Page, selector: str) -> float:
    return float(page.locator(selector).evaluate("el => getComputedStyle(el).opacity"))


def test_the_last_result_is_marked_stale_while_a_field_is_wrong(page: Page) -> None:
    open_calculator(page, triangle_query(*RIGHT))
    note = page.locator("#stale-note")
    expect(note).to_have_attribute("role", "status")
    assert page.locator("#result #stale-note").count() == 0  # outside the result, read apart
    expect(note).to_be_hidden()
    stale = re.compile(r"\bstale\b")

    page.locator("#bx").fill("1..2")
    expect(note).to_have_text(re.compile("for the last valid input"))
    expect(note).to_be_visible()
    for selector in STALE_PARTS:
        expect(page.locator(selector)).to_have_class(stale)
    # Dimmed: the numbers, the steps, the code, the chart and the 3D view; not the notice.
    for selector in ("#result .values", "#result .result-actions", "#steps", "#code", "#chart"):
        assert opacity(page, selector) < 0.6, selector
    assert opacity(page, "#view3d") < 0.6
    assert opacity(page, '#result [data-key="invalid"]') == 1
    expect(cell(page, "normal")).to_have_text("(0, 0, 1)")  # the old numbers, still there

    # A blank field is no valid input either.
    page.locator("#bx").fill("")
    expect(note).to_have_text(re.compile("for the last valid input"))
    expect(page.locator("#chart")).to_have_class(stale)

    page.locator("#bx").fill("2")
    wait_for_chart_values(page, [0, 0, 2, 2, 1])
    expect(note).to_be_hidden()
    expect(note).to_have_text("")
    for selector in STALE_PARTS:
        expect(page.locator(selector)).not_to_have_class(stale)
    for selector in ("#result .values", "#steps", "#code", "#chart", "#view3d"):
        assert opacity(page, selector) == 1, selector


def test_no_stale_note_without_an_earlier_result(page: Page, console: ConsoleWatch) -> None:
    console.allow(r"status of 422 \(Unprocessable Entity\) \(http://[^)]*/\?ax=")
    query = triangle_query(("0", "0", "0"), ("x", "0", "0"), ("0", "1", "0"))
    response = page.goto(f"/?{query}")
    assert response is not None and response.status == 422
    page.locator("#by").fill("y")  # still wrong: there never were numbers to call stale
    expect(page.locator('[data-error-for="by"]')).not_to_have_text("")
    expect(page.locator("#stale-note")).to_have_text("")
