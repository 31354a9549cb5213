"""The point-cloud page in Chromium: upload, the diagnosis, the 3D view and its colour toggle,
a download that sends the file again, the phone layout and the README's screenshot."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import FilePayload, Page, expect

from tests.browser.conftest import NewPage
from tests.paths import ROOT

pytestmark = pytest.mark.browser

DOCS = ROOT / "docs"
SCREENSHOT_LIMIT = 400 * 1024


def cloud_file(
    name: str = "cylinder.xyz", rings: int = 8, around: int = 36, outlier: bool = True
) -> FilePayload:
    """A cylinder of ``rings`` rings of ``around`` points, with one isolated point far away."""
    angles = np.linspace(0, 2 * np.pi, around, endpoint=False)
    heights = np.linspace(0, 1.4, rings)
    rows = [(np.cos(a), np.sin(a), z) for z in heights for a in angles.tolist()]
    if outlier:
        rows.append((30.0, 30.0, 30.0))
    text = "".join(f"{x:.9f} {y:.9f} {z:.9f}\n" for x, y, z in rows)
    return {"name": name, "mimeType": "text/plain", "buffer": text.encode()}


def upload(page: Page, radius: str = "", cloud: FilePayload | None = None) -> None:
    response = page.goto("/points")
    assert response is not None and response.status == 200
    page.wait_for_load_state("load")
    if radius:
        page.locator("details.mesh-options summary").click()
        page.fill("#points-radius", radius)
    page.set_input_files("#points-file", files=[cloud or cloud_file()])
    page.locator("#points-report-title").wait_for()
    page.locator("#points-histogram[data-drawn] .main-svg").first.wait_for()


def wait_for_view(page: Page) -> str:
    page.locator("#points-view").scroll_into_view_if_needed()
    page.locator("#points-view[data-drawn]").wait_for(timeout=20_000)
    expect(page.locator("#points-view canvas").first).to_be_attached()
    return page.locator("#points-view").get_attribute("data-drawn") or ""


MARKER = "() => document.getElementById('points-view').data[0].marker"


def test_uploading_a_cloud_shows_the_diagnosis_view_and_toggle(page: Page) -> None:
    upload(page, radius="0.5")
    expect(page.locator("#points-status")).to_contain_text("288 of 289 points have a normal")
    expect(page.locator("#points-diagnosis")).to_contain_text("fewer than 3 points")
    expect(page.locator("#points-view-caption")).to_contain_text("Showing all 289 points")
    first = wait_for_view(page)
    marker = page.evaluate(MARKER)
    assert str(marker["color"][0]).startswith("rgb(")

    page.get_by_role("button", name="curvature").click()
    page.wait_for_function(
        f"() => document.getElementById('points-view').dataset.drawn !== '{first}'"
    )
    marker = page.evaluate(MARKER)
    assert marker["colorscale"] and isinstance(marker["color"][0], (int, float))
    expect(page.get_by_role("button", name="curvature")).to_have_attribute("aria-pressed", "true")
    expect(page.get_by_role("button", name="normal direction")).to_have_attribute(
        "aria-pressed", "false"
    )

    with page.expect_download() as info:
        page.locator("button[data-points-download=xyz]").click()
    download = info.value
    assert download.suggested_filename == "cylinder-normals.xyz"
    rows = Path(download.path()).read_text().split("\n")
    assert len([row for row in rows if row.strip() and not row.startswith("#")]) == 289
    expect(page.locator("#points-download-status")).to_contain_text("1 point has no normal")


def test_phone_layout_and_desktop_screenshot(new_page: NewPage) -> None:
    page = new_page(viewport={"width": 360, "height": 740}, is_mobile=True, has_touch=True)
    upload(page)
    wait_for_view(page)
    widths = page.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")
    assert widths[0] <= widths[1], widths

    page = new_page(viewport={"width": 1280, "height": 1000}, color_scheme="dark")
    upload(page, cloud=cloud_file(rings=24, around=90, outlier=False))
    wait_for_view(page)
    page.evaluate("() => window.scrollTo(0, 0)")
    page.wait_for_timeout(300)
    path = DOCS / "points-page.png"
    page.screenshot(path=path, animations="disabled", caret="hide", scale="css")
    assert path.stat().st_size < SCREENSHOT_LIMIT, path.stat().st_size


def test_without_javascript_the_form_posts_and_the_server_renders_the_report(
    new_page: NewPage,
) -> None:
    page = new_page(java_script_enabled=False)
    page.goto("/points")
    page.locator("details.mesh-options summary").click()
    page.fill("#points-k", "12")
    page.set_input_files("#points-file", files=[cloud_file()])
    with page.expect_navigation():
        page.locator("#points-submit").click()
    expect(page.locator("#points-diagnosis")).to_contain_text("Every point has a normal")
    expect(page.locator("#points-k")).to_have_value("12")
    assert page.locator("link[rel=alternate]").get_attribute("href") == "/api/points?k=12"


def test_new_options_analyse_the_held_file_again(page: Page) -> None:
    upload(page)
    page.locator("details.mesh-options summary").click()
    page.select_option("#points-orient", "direction")
    expect(page.locator("#points-status")).to_contain_text("Give the direction x,y,z")
    page.fill("#points-direction", "0,0,1")
    page.locator("#points-direction").dispatch_event("change")
    expect(page.locator("#points-summary")).to_contain_text("Direction 0.0, 0.0, 1.0.")
    expect(page.locator("#points-report-view")).to_have_attribute(
        "data-query", "orient=direction&direction=0%2C0%2C1"
    )
