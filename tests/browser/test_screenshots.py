"""Desktop and phone screenshots of the calculator (written to docs/), and the phone layout."""

from __future__ import annotations

from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import NewPage
from tests.browser.helpers import cell
from tests.paths import ROOT

pytestmark = pytest.mark.browser

DOCS = ROOT / "docs"
PHONE = {
    "viewport": {"width": 390, "height": 844},
    "device_scale_factor": 2,
    "is_mobile": True,
    "has_touch": True,
}
#: Largest screenshot we are willing to commit.
MAX_BYTES = 1_500_000
README_ADDRESS = "http://127.0.0.1:8000"


def settle(page: Page) -> None:
    """Wait for the example's result, the drawn chart and the web fonts; no animation left."""
    expect(cell(page, "normal")).to_have_text("(6, 3, 2)")
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    page.evaluate("() => document.fonts.ready.then(() => true)")
    page.wait_for_function("() => document.getAnimations().every(a => a.playState !== 'running')")


def draw_3d_view(page: Page) -> None:
    """Scroll the lazy 3D view into sight, wait for its drawing, then go back to the top."""
    page.locator("#view3d").scroll_into_view_if_needed()
    page.locator("#view3d[data-drawn] canvas").first.wait_for(timeout=20_000)
    page.evaluate("() => window.scrollTo(0, 0)")


def save(page: Page, name: str, base_url: str) -> Path:
    # The test server's port changes every run; show the address the README uses instead, so
    # the committed pictures only change when the page does.
    page.locator("#embed-code").evaluate(
        "(code, [here, shown]) => { code.value = code.value.split(here).join(shown); }",
        [base_url, README_ADDRESS],
    )
    DOCS.mkdir(exist_ok=True)
    path = DOCS / name
    page.screenshot(path=path, full_page=True, animations="disabled", caret="hide")
    assert 0 < path.stat().st_size <= MAX_BYTES, (path, path.stat().st_size)
    return path


def no_horizontal_scroll(page: Page) -> tuple[int, int]:
    return page.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")


def test_desktop_screenshot(page: Page, base_url: str) -> None:
    page.set_viewport_size({"width": 1280, "height": 900})
    page.goto("/")
    settle(page)
    draw_3d_view(page)
    scroll_width, width = no_horizontal_scroll(page)
    assert scroll_width <= width, (scroll_width, width)
    save(page, "screenshot-desktop.png", base_url)


def test_phone_screenshot_and_no_horizontal_scroll(new_page: NewPage, base_url: str) -> None:
    page = new_page(**PHONE)
    page.goto("/")
    settle(page)
    draw_3d_view(page)
    scroll_width, width = no_horizontal_scroll(page)
    assert width == 390
    assert scroll_width <= width, f"the page scrolls sideways: {scroll_width} > {width}"
    for name in ("ax", "cz"):  # comfortable touch targets
        box = page.locator(f"#{name}").bounding_box()
        assert box is not None and box["height"] >= 44, (name, box)
    save(page, "screenshot-phone.png", base_url)

    page.goto("/embed")
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    scroll_width, width = no_horizontal_scroll(page)
    assert scroll_width <= width, f"/embed scrolls sideways: {scroll_width} > {width}"
