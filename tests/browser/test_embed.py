"""The embeddable chart: it draws, links back, and other sites may frame it (but not the page)."""

from __future__ import annotations

import re
from urllib.parse import quote

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import ConsoleWatch, NewPage
from tests.browser.helpers import COLLINEAR, RIGHT, triangle_query

pytestmark = pytest.mark.browser

FRAME_REFUSED = r"frame-ancestors 'none'"


def test_embed_draws_the_chart_and_links_to_the_calculator(page: Page, base_url: str) -> None:
    query = triangle_query(*RIGHT)
    response = page.goto(f"/embed?{query}")
    assert response is not None and response.status == 200
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    assert page.evaluate("document.getElementById('chart').data[0].x") == [0, 0, 1, 1, 0.5]
    link = page.get_by_role("link", name=re.compile("Open in Mesh Normal Calculator"))
    # Relative (the Host header never goes into a link): it opens the calculator of the server
    # that the frame came from.
    expect(link).to_have_attribute("href", f"/?{query}")
    assert link.evaluate("a => a.href") == f"{base_url}/?{query}"
    expect(link).to_have_attribute("target", "_blank")
    expect(link).to_have_attribute("rel", re.compile(r"\bnoopener\b"))
    # The embed is only the chart: no form, no site header.
    expect(page.locator("form")).to_have_count(0)
    expect(page.locator(".site-header")).to_have_count(0)


def test_embed_of_a_degenerate_triangle_shows_the_message(page: Page) -> None:
    page.goto(f"/embed?{triangle_query(*COLLINEAR)}")
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    expect(page.locator(".embed-main .message")).to_be_visible()


def test_embed_with_a_typo_shows_the_error_and_no_chart(page: Page, console: ConsoleWatch) -> None:
    # The page answers 422 on purpose; Chromium logs every 4xx document as a console error.
    console.allow(r"status of 422 \(Unprocessable Entity\) \(http://[^)]*/embed\?")
    query = triangle_query(("0", "0", "0"), ("1..2", "0", "0"), ("0", "1", "0"))
    response = page.goto(f"/embed?{query}")
    assert response is not None and response.status == 422
    expect(page.locator(".message.error")).to_contain_text("B.x must be")
    expect(page.locator("#chart")).to_have_count(0)


def test_another_site_can_frame_the_embed(page: Page, framing_host: str, base_url: str) -> None:
    src = f"{base_url}/embed?{triangle_query(*RIGHT, swap=True)}"
    response = page.goto(f"{framing_host}/frame?src={quote(src, safe='')}")
    assert response is not None and response.status == 200
    framed = page.frame_locator("#framed")
    framed.locator("#chart[data-drawn] .main-svg").first.wait_for()
    expect(
        framed.get_by_role("link", name=re.compile("Open in Mesh Normal Calculator"))
    ).to_be_visible()
    frame = page.frame(name="framed")
    assert frame is not None and frame.url == src
    assert frame.evaluate("document.getElementById('chart').data[0].x") == [0, 0, -1, 1, 0.5]


def test_the_calculator_page_refuses_to_be_framed(
    page: Page, framing_host: str, base_url: str, console: ConsoleWatch
) -> None:
    console.allow(FRAME_REFUSED)  # the browser's own report of the refusal, expected here
    src = f"{base_url}/?{triangle_query(*RIGHT)}"
    with page.expect_console_message(lambda message: "frame-ancestors" in message.text):
        page.goto(f"{framing_host}/frame?src={quote(src, safe='')}")
    # The blocked frame commits an error page a moment after the console message: poll for it.
    page.wait_for_function(
        """(base) => { const f = document.getElementById('framed');
                       let url = null;
                       try { url = f && f.contentWindow && f.contentWindow.location.href; }
                       catch (error) { return true; }  // cross-origin: not the calculator
                       return Boolean(url) && !url.startsWith(base); }""",
        arg=base_url,
        timeout=10_000,
    )
    # An error page, not the calculator (Chromium may drop the blocked frame's name, so the
    # frame is found as the page's child, not by name).
    frames = page.main_frame.child_frames
    assert len(frames) == 1
    assert not frames[0].url.startswith(base_url), frames[0].url
    expect(page.frame_locator("#framed").locator("#calculator")).to_have_count(0)
    assert console.matching(FRAME_REFUSED)


def test_framing_headers(page: Page) -> None:
    embed = page.request.get(f"/embed?{triangle_query(*RIGHT)}")
    assert "frame-ancestors *" in embed.headers["content-security-policy"]
    assert "x-frame-options" not in embed.headers
    calculator = page.request.get(f"/?{triangle_query(*RIGHT)}")
    assert "frame-ancestors 'none'" in calculator.headers["content-security-policy"]
    assert calculator.headers["x-frame-options"] == "DENY"


BACKGROUND = "() => getComputedStyle(document.body).backgroundColor"


@pytest.mark.parametrize(
    ("scheme", "theme", "background"),
    [
        ("light", "dark", "rgb(23, 28, 44)"),  # the dark card, whatever the reader prefers
        ("dark", "light", "rgb(255, 255, 255)"),
        ("dark", "auto", "rgb(23, 28, 44)"),  # auto follows the reader
    ],
)
def test_embed_theme_sets_its_colours(
    new_page: NewPage, scheme: str, theme: str, background: str
) -> None:
    page = new_page(color_scheme=scheme)
    page.goto(f"/embed?{triangle_query(*RIGHT)}&theme={theme}")
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    assert page.evaluate(BACKGROUND) == background
    # The chart's text follows the theme too (light grey on the dark card).
    dark = background != "rgb(255, 255, 255)"
    font = page.evaluate("document.getElementById('chart').layout.font.color")
    assert (font == "#c3cade") is dark, font
