"""The notebook page's pictures (written to docs/): the reports' HTML and mn.show's figures, made
by the page's own examples and drawn in Chromium with the vendored Plotly bundle (no CDN), as a
notebook shows them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Browser, Page

from tests.docs.test_examples import blocks
from tests.paths import ROOT

pytestmark = pytest.mark.browser

DOCS = ROOT / "docs"
PLOTLY = ROOT / "static" / "vendor" / "plotly" / "plotly-gl3d.min.js"
#: Largest picture we are willing to commit.
MAX_BYTES = 600_000


@pytest.fixture(scope="module")
def examples(monkeypatch_module: pytest.MonkeyPatch) -> dict[str, Any]:
    """The names the notebook page's examples define, run as the docs test runs them."""
    monkeypatch_module.chdir(ROOT)
    namespace: dict[str, Any] = {"__name__": "__docs__"}
    for code in blocks(DOCS / "notebooks.md"):
        exec(compile(code, "notebooks.md", "exec"), namespace)
    return namespace


@pytest.fixture(scope="module")
def monkeypatch_module() -> Any:
    with pytest.MonkeyPatch.context() as patch:
        yield patch


@pytest.fixture
def notebook(browser: Browser) -> Any:
    context = browser.new_context(viewport={"width": 860, "height": 600}, color_scheme="light")
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    yield page
    context.close()
    assert not errors, errors


def saved(path: Path) -> Path:
    assert 0 < path.stat().st_size <= MAX_BYTES, (path, path.stat().st_size)
    return path


def shoot_html(page: Page, html: str, name: str) -> Path:
    page.set_content(f'<body style="margin:12px;background:#fff">{html}</body>')
    page.locator("body > div").first.screenshot(path=DOCS / name, animations="disabled")
    return saved(DOCS / name)


def shoot_figure(page: Page, figure: Any, name: str, tmp_path: Path) -> Path:
    body = figure.to_html(include_plotlyjs=False, full_html=False, config={"displayModeBar": False})
    source = tmp_path / f"{name}.html"
    source.write_text(
        f'<html><head><script src="{PLOTLY.as_uri()}"></script></head>'
        f'<body style="margin:0;background:#fff">{body}</body></html>',
        encoding="utf-8",
    )
    page.goto(source.as_uri())
    page.locator(".js-plotly-plot .gl-container canvas").first.wait_for()
    page.wait_for_function("() => document.querySelector('.js-plotly-plot')._fullLayout")
    page.wait_for_timeout(500)  # the WebGL scene's first frames
    page.locator(".js-plotly-plot").first.screenshot(path=DOCS / name, animations="disabled")
    return saved(DOCS / name)


def test_the_report_pictures(notebook: Page, examples: dict[str, Any]) -> None:
    from mesh_normal.points import analyse_points

    shoot_html(notebook, examples["report"]._repr_html_(), "notebook-report.png")
    cloud_report = analyse_points(examples["cloud"]).report
    shoot_html(notebook, cloud_report._repr_html_(), "notebook-cloud-report.png")


def test_the_figure_pictures(notebook: Page, examples: dict[str, Any], tmp_path: Path) -> None:
    import mesh_normal as mn

    shoot_figure(notebook, examples["figure"], "notebook-mesh.png", tmp_path)
    shoot_figure(notebook, mn.show(examples["cloud"]), "notebook-cloud.png", tmp_path)
