"""The chart's own toolbar: PNG and SVG downloads under the page's CSP, and no outside sharing."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from tests.browser.conftest import NewPage
from tests.browser.helpers import RIGHT, triangle_query

pytestmark = pytest.mark.browser


@pytest.mark.parametrize(
    ("title", "name", "start"),
    [
        ("Download plot as a PNG", "triangle-normal.png", b"\x89PNG"),
        ("Download plot as SVG", "triangle-normal.svg", b"<svg"),
    ],
)
def test_toolbar_downloads_the_chart(
    new_page: NewPage, title: str, name: str, start: bytes
) -> None:
    page = new_page(viewport={"width": 1280, "height": 900}, accept_downloads=True)
    page.goto(f"/?{triangle_query(*RIGHT)}")
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    page.locator("#chart").hover()
    button = page.locator(f'#chart .modebar-btn[data-title="{title}"]')
    expect(button).to_have_count(1, timeout=10_000)  # added once the page is idle
    with page.expect_download() as download:
        button.click()
    assert download.value.suggested_filename == name
    path = download.value.path()
    with open(path, "rb") as saved:
        head = saved.read(200)
    assert head.startswith(start), head[:20]
    if name.endswith(".svg"):
        with open(path, encoding="utf-8") as saved:
            assert ">area<" in saved.read()  # the chart itself, with its axis labels


def test_toolbar_has_no_outside_sharing(new_page: NewPage) -> None:
    page = new_page(viewport={"width": 1280, "height": 900})
    page.goto(f"/?{triangle_query(*RIGHT)}")
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()
    page.locator("#chart").hover()
    expect(page.locator('#chart .modebar-btn[data-title="Download plot as SVG"]')).to_have_count(
        1, timeout=10_000
    )
    titles = page.locator("#chart .modebar-btn").evaluate_all(
        "buttons => buttons.map(b => b.dataset.title)"
    )
    assert "Download plot as a PNG" in titles
    assert not [t for t in titles if "Share" in t or "Cloud" in t], titles
