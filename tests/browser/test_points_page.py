"""The point-cloud page in Chromium: upload, the diagnosis, the 3D view and its controls (colour,
up axis, strokes), a download that sends the file again, the phone layout and the README's
screenshot."""

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
    assert isinstance(marker["color"][0], int) and marker["cmax"] == 300  # the light's codes

    page.get_by_role("button", name="curvature").click()
    page.wait_for_function(
        f"() => document.getElementById('points-view').dataset.drawn !== '{first}'"
    )
    marker = page.evaluate(MARKER)
    assert marker["colorscale"] and isinstance(marker["color"][0], (int, float))
    expect(page.get_by_role("button", name="curvature")).to_have_attribute("aria-pressed", "true")
    expect(page.get_by_role("button", name="normal, under a light")).to_have_attribute(
        "aria-pressed", "false"
    )

    with page.expect_download() as info:
        page.locator("button[data-points-download=xyz]").click()
    download = info.value
    assert download.suggested_filename == "cylinder-normals.xyz"
    rows = Path(download.path()).read_text().split("\n")
    assert len([row for row in rows if row.strip() and not row.startswith("#")]) == 289
    expect(page.locator("#points-download-status")).to_contain_text("1 point has no normal")


CAMERA = "() => document.getElementById('points-view')._fullLayout.scene.camera"
TRACES = "() => document.getElementById('points-view').data.map(t => [t.name, t.visible])"


def redrawn(page: Page, before: str) -> str:
    page.wait_for_function(
        f"() => document.getElementById('points-view').dataset.drawn !== '{before}'"
    )
    return page.locator("#points-view").get_attribute("data-drawn") or ""


def test_the_up_axis_turns_the_camera_the_strokes_toggle_and_a_warning_reads_as_one(
    page: Page,
) -> None:
    upload(page, radius="0.5")  # the far point has no neighbour within 0.5: a warning
    expect(page.locator("#points-diagnosis")).to_have_class("message warn")
    expect(page.locator("#points-status")).to_have_class("mesh-status message warn")
    expect(page.locator("#points-diagnosis .severity.severity-warning")).to_have_text("Check")
    drawn = wait_for_view(page)
    cameras = page.evaluate(
        "() => JSON.parse(document.getElementById('points-view-data').textContent).cameras"
    )
    camera = page.evaluate(CAMERA)
    assert camera["up"] == {"x": 0, "y": 0, "z": 1}  # XYZ: Z-up
    assert camera["eye"] == pytest.approx(cameras["z"]["eye"])  # the server's fitted camera
    expect(page.locator("#points-up")).to_be_visible()

    page.select_option("#points-up", "y")
    drawn = redrawn(page, drawn)
    camera = page.evaluate(CAMERA)
    assert camera["up"] == {"x": 0, "y": 1, "z": 0}
    assert camera["eye"] == pytest.approx(cameras["y"]["eye"])
    lit = page.evaluate(
        "() => JSON.parse(document.getElementById('points-view-data').textContent).colors.light.y"
    )
    assert page.evaluate(MARKER)["color"] == lit["color"]  # the light follows the up axis

    assert page.evaluate(TRACES)[1] == ["normals", True]  # strokes start shown
    page.locator("#points-strokes").uncheck()
    redrawn(page, drawn)
    assert page.evaluate(TRACES)[1] == ["normals", False]
    assert page.evaluate(CAMERA)["up"] == {"x": 0, "y": 1, "z": 0}  # the view stays as it was


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
