"""/docs: Swagger UI from the app's own files, under the app's strict CSP."""

from __future__ import annotations

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import NewPage
from tests.browser.helpers import FIELDS

pytestmark = pytest.mark.browser

PATHS = {
    "/api/normal",
    "/api/normal.csv",
    "/api/normals",
    "/api/chart",
    "/api/mesh",
    "/api/mesh/normals",
    "/api/mesh/fix",
    "/api/mesh/export",
    "/api/mesh/sample/{name}",
    "/api/points",
    "/api/points/normals",
}


def test_docs_show_the_operations_and_try_them(page: Page, base_url: str) -> None:
    requests: list[str] = []
    page.on("request", lambda request: requests.append(request.url))
    response = page.goto("/docs")
    assert response is not None and response.status == 200
    csp = response.headers["content-security-policy"]
    assert "script-src 'self';" in csp and "unsafe-eval" not in csp, csp

    paths = page.locator(".opblock-summary-path")
    expect(paths.first).to_be_visible()
    # GET and POST /api/normal, GET /api/normal.csv, POST /api/normals, GET /api/chart, and
    # POST /api/mesh, /api/mesh/normals, /api/mesh/fix, /api/mesh/export, GET
    # /api/mesh/sample/{name}, POST /api/points, /api/points/normals
    expect(paths).to_have_count(12)
    assert {text.strip() for text in paths.all_inner_texts()} == PATHS
    expect(page.get_by_text("Mesh Normal Calculator").first).to_be_visible()
    expect(page.get_by_role("link", name="← Back to the calculator")).to_have_attribute("href", "/")

    # "Try it out" works under the CSP: Swagger UI calls the API from the page.
    operation = page.locator("#operations-normals-get_chart_api_chart_get")
    operation.locator(".opblock-summary").click()
    for name in FIELDS:
        operation.locator(f'tr[data-param-name="{name}"] input').fill(
            {"bx": "1", "cy": "1"}.get(name, "0")
        )
    # Pressed from the keyboard, not clicked: on a loaded machine Swagger UI's re-renders after
    # each fill can keep the button from counting as "stable" for Playwright's whole timeout, and
    # what is tested here is the request the page then makes, not the pointer.
    execute = operation.get_by_role("button", name="Execute")
    expect(execute).to_be_enabled()
    execute.press("Enter")
    expect(
        operation.locator(".live-responses-table tbody .response-col_status").first
    ).to_have_text("200")
    expect(operation.locator(".live-responses-table .microlight").first).to_contain_text('"bar"')

    # Everything came from the app itself: no CDN, no validator badge, no fonts from elsewhere.
    outside = [url for url in requests if not url.startswith((base_url, "data:"))]
    assert not outside, outside


@pytest.mark.parametrize(("scheme", "dark"), [("dark", True), ("light", False)])
def test_docs_follow_the_colour_scheme_and_name_operations_in_words(
    new_page: NewPage, scheme: str, dark: bool
) -> None:
    page = new_page(color_scheme=scheme)
    page.goto("/docs")
    post_normal = page.locator("#operations-normals-post_normal_api_normal_post")
    expect(post_normal.locator(".opblock-summary-description")).to_have_text(
        "Normal of one triangle"
    )
    expect(page.get_by_text("Post Normal", exact=True)).to_have_count(0)
    background = page.evaluate(
        "getComputedStyle(document.querySelector('.swagger-ui')).backgroundColor"
    )
    assert (background == "rgb(28, 32, 34)") is dark, background  # Swagger UI's dark mode
