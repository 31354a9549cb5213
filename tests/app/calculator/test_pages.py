"""HTML pages: the calculator (/), the embeddable chart (/embed), the API docs and error pages."""

from __future__ import annotations

import json
from urllib.parse import parse_qsl, urlencode, urlsplit

import pytest

from app.web.formatting import number_text
from tests.conftest import EXAMPLE_QUERY, Page

FIELDS = ["ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz"]


def page(client, path: str, params=None, status: int = 200):  # type: ignore[no-untyped-def]
    response = client.get(path, params=params)
    assert response.status_code == status, response.text[:500]
    assert response.headers["content-type"] == "text/html; charset=utf-8"
    return response, Page(response.text)


def vec(values) -> str:  # type: ignore[no-untyped-def]
    """As the page shows a vector to people: JavaScript's digits, the real minus sign."""
    return "(" + ", ".join("out of range" if x is None else number_text(x) for x in values) + ")"


def figure_data(html: Page):  # type: ignore[no-untyped-def]
    """The parsed JSON of the page's one <script type="application/json" id="figure-data">."""
    found = [
        (attrs, content) for attrs, content in html.scripts if attrs.get("id") == "figure-data"
    ]
    assert len(found) == 1, found
    attrs, content = found[0]
    assert attrs.get("type") == "application/json"
    return json.loads(content)


# --- The calculator ---------------------------------------------------------------------------


def test_calculator_opens_with_the_example(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/")
    assert response.template.name == "index.html"
    assert response.context["typed"] == EXAMPLE_QUERY
    assert response.context["errors"] == {}
    assert response.context["swap"] is False
    for name in FIELDS:
        field = html.one("input", name=name)
        assert field["id"] == name
        assert field["inputmode"] == "decimal"
        assert field["type"] == "text"
        assert field["value"] == EXAMPLE_QUERY[name]
        assert "aria-invalid" not in field
        assert html.one("label", for_=name)
    swap = html.one("input", name="swap")
    assert swap["type"] == "checkbox" and "checked" not in swap
    form = html.one("form", id="calculator")
    assert form["method"] == "get" and form["action"] == "/"
    # The example's result is already on the page, without JavaScript.
    assert Page(response.text).cells()["normal"] == "(6, 3, 2)"
    assert response.context["payload"]["normal"] == [6.0, 3.0, 2.0]


def test_calculator_links_its_json_twin(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/")
    alternate = html.one("link", rel="alternate")
    assert alternate["type"] == "application/json"
    href = alternate["href"]
    assert href.startswith("/api/normal?")
    assert dict(parse_qsl(urlsplit(href).query, keep_blank_values=True)) == EXAMPLE_QUERY
    link = response.headers["link"]
    assert link == f'<{href}>; rel="alternate"; type="application/json"'
    twin = client.get(href)
    assert twin.status_code == 200
    assert twin.json() == response.context["payload"]


def test_result_is_rendered_on_the_server(client) -> None:  # type: ignore[no-untyped-def]
    query = {**EXAMPLE_QUERY, "ax": "1.5", "swap": "on"}
    response, html = page(client, "/", query)
    payload = response.context["payload"]
    assert payload["order"] == "ACB"
    assert response.context["swap"] is True
    assert "checked" in html.one("input", name="swap")
    assert html.one("input", name="ax")["value"] == "1.5"
    cells = {attrs["data-key"]: attrs for _, attrs in html.elements if "data-key" in attrs}
    assert {"u", "v", "normal", "magnitude", "unit_normal", "area", "order"} <= set(cells)
    texts = Page(response.text).cells()
    assert texts["normal"] == vec(payload["normal"])
    assert texts["u"] == vec(payload["u"])
    assert texts["v"] == vec(payload["v"])
    assert texts["unit_normal"] == vec(payload["unit_normal"])
    assert texts["magnitude"] == number_text(payload["magnitude"])
    assert texts["area"] == number_text(payload["area"])
    assert texts["order"] == "order A, C, B"
    assert number_text(payload["unit_normal"][0]) in response.text
    assert "-" not in texts["normal"] and "−" in texts["normal"]  # n = (−…, …): a real minus
    assert figure_data(html) == response.context["figure"]


def test_out_of_range_values_read_out_of_range(client) -> None:  # type: ignore[no-untyped-def]
    query = dict(zip(FIELDS, ["0", "0", "0", "1e200", "0", "0", "0", "1e200", "0"], strict=True))
    response, _ = page(client, "/", query)
    texts = Page(response.text).cells()
    assert texts["magnitude"] == "out of range"
    assert texts["normal"] == "(0, 0, out of range)"
    assert texts["unit_normal"] == "(0, 0, 1)"
    assert "largest double" in texts["message"]
    assert "Infinity" not in texts["message"] and "NaN" not in response.text


def test_degenerate_triangle_says_so(client) -> None:  # type: ignore[no-untyped-def]
    query = dict(zip(FIELDS, ["0", "0", "0", "1", "1", "1", "2", "2", "2"], strict=True))
    response, _ = page(client, "/", query)
    texts = Page(response.text).cells()
    assert texts["unit_normal"] == "none (degenerate triangle)"
    assert "one line" in texts["message"]


@pytest.mark.parametrize(
    ("name", "typed", "words"),
    [
        ("ax", "abc", "must be a number"),
        ("cz", "1e999", "double range"),
        ("bx", "0x10", "must be a number"),
    ],
)
def test_bad_value_is_shown_beside_its_field(client, name, typed, words) -> None:  # type: ignore[no-untyped-def]
    query = {**EXAMPLE_QUERY, name: typed}
    response, html = page(client, "/", query, status=422)
    assert response.template.name == "index.html"
    assert response.context["payload"] is None
    assert set(response.context["errors"]) == {name}
    sentence = response.context["errors"][name]
    assert words in sentence
    field = html.one("input", name=name)
    assert field["value"] == typed  # what was typed is kept
    assert field["aria-invalid"] == "true"
    assert field["aria-describedby"] == f"{name}-error"
    assert html.text(f"{name}-error") == sentence
    for other in FIELDS:
        if other != name:
            assert html.one("input", name=other)["value"] == EXAMPLE_QUERY[other]
            assert html.text(f"{other}-error") == ""
    assert figure_data(html) is None


def test_every_bad_field_is_shown(client) -> None:  # type: ignore[no-untyped-def]
    query = {**EXAMPLE_QUERY, "ax": "x", "cz": "y", "swap": "maybe"}
    response, html = page(client, "/", query, status=422)
    assert set(response.context["errors"]) == {"ax", "cz", "swap"}
    for name in ("ax", "cz", "swap"):
        assert html.text(f"{name}-error") == response.context["errors"][name]
    assert "Fix the highlighted fields" in response.text


def test_missing_coordinates_are_one_calm_line(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/", {"ax": "1", "by": "2", "bz": " "}, status=422)
    assert response.context["errors"] == {}
    assert response.context["missing"] == ["ay", "az", "bx", "bz", "cx", "cy", "cz"]
    assert html.text("missing-note") == "A.y, A.z, B.x, B.z, C.x, C.y and C.z are missing."
    for name in FIELDS:  # nothing is red: nothing given is wrong
        assert html.text(f"{name}-error") == ""
        assert "aria-invalid" not in html.one("input", name=name)
    assert Page(response.text).cells()["invalid"] == "Fill in every coordinate to see the normal."
    (invalid,) = [attrs for _, attrs in html.elements if attrs.get("data-key") == "invalid"]
    assert invalid["class"] == "message"  # shown, and not as an error
    assert "Fix the highlighted" not in response.text


def test_one_wrong_value_is_one_error_and_the_rest_one_line(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/", {"ax": "1e999"}, status=422)
    assert list(response.context["errors"]) == ["ax"]
    assert html.text("ax-error") == "A.x is beyond the double range (about ±1.8e308)."
    assert html.one("input", name="ax")["aria-invalid"] == "true"
    invalid = [name for name in FIELDS if "aria-invalid" in html.one("input", name=name)]
    assert invalid == ["ax"]
    assert [name for name in FIELDS if html.text(f"{name}-error")] == ["ax"]
    line = "A.y, A.z, B.x, B.y, B.z, C.x, C.y and C.z are missing."
    assert html.text("missing-note") == line
    assert Page(response.text).cells()["invalid"] == "Fix the highlighted field to see the normal."


def test_a_complete_form_has_no_missing_line(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/", EXAMPLE_QUERY)
    assert response.context["missing"] == []
    assert html.text("missing-note") == ""


def test_typed_markup_is_escaped(client) -> None:  # type: ignore[no-untyped-def]
    evil = '"><script>alert(1)</script><img src=x onerror=alert(2)>'
    response, html = page(client, "/", {**EXAMPLE_QUERY, "ay": evil}, status=422)
    assert html.one("input", name="ay")["value"] == evil
    assert "<script>alert(1)" not in response.text
    assert not html.find("img", src="x")
    assert all(
        attrs.get("src") or attrs.get("type") == "application/json" for attrs, _ in html.scripts
    )


def test_figure_data_matches_the_chart_api(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/", {**EXAMPLE_QUERY, "bz": "-4"})
    chart = client.get("/api/chart", params={**EXAMPLE_QUERY, "bz": "-4"}).json()
    assert figure_data(html) == chart == response.context["figure"]
    # "<" inside the JSON is escaped, so no "</script>" can end the block early.
    ((_, raw),) = [(a, c) for a, c in html.scripts if a.get("id") == "figure-data"]
    assert "<" not in raw and "\\u003c" in raw


# --- The page and its JSON twin agree ---------------------------------------------------------

PARITY = [
    "",
    "swap=on",
    "ax=1&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=3&swap=true",
    "ax=1&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=3&swap=1",
    "ax=1&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=3&swap=off",
    "ax=0&ay=0&az=0&bx=1.0000000000000002&by=1&bz=0&cx=1&cy=0.9999999999999999&cz=0",
    "ax=0&ay=0&az=0&bx=1e-200&by=0&bz=0&cx=0&cy=1e-200&cz=0",
    "ax=0&ay=0&az=0&bx=1e200&by=0&bz=0&cx=0&cy=1e200&cz=0",
    "ax=0&ay=0&az=0&bx=1&by=1&bz=1&cx=2&cy=2&cz=2",
    "ax=-0&ay=.5&az=5.&bx=%2B3&by=1E2&bz=-2e3&cx=%201.5%20&cy=0.1&cz=0.2",
    "ax=1.7976931348623157e308&ay=0&az=0&bx=0&by=1.7976931348623157e308&bz=0&cx=0&cy=0&cz=1",
    "ax=abc&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=3",
    "ax=1&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=1e999",
    "ax=1&by=2",
    "ax=1&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=3&swap=maybe",
]


@pytest.mark.parametrize("query", PARITY)
def test_page_payload_equals_its_json_twin(client, query: str) -> None:  # type: ignore[no-untyped-def]
    response = client.get("/?" + query)
    assert response.status_code in (200, 422)
    html = Page(response.text)
    href = html.one("link", rel="alternate")["href"]
    assert href == html.one("a", id="json-link")["href"]
    twin = client.get(href)
    context = response.context
    if context["payload"] is None:
        assert response.status_code == 422
        assert twin.status_code == 422
        # The twin names what the page names first: a wrong value, else the missing line.
        assert twin.json() == context["problem"].body()
    else:
        assert response.status_code == 200
        assert twin.status_code == 200
        # Compared as JSON text, so that 0.0 and -0.0 would differ.
        assert json.dumps(twin.json()) == json.dumps(context["payload"])
        chart = client.get("/api/chart?" + urlsplit(href).query).json()
        assert chart == context["figure"]
    if query and "ax" in query:  # the twin is the same question as the page
        given = dict(parse_qsl(query, keep_blank_values=True))
        asked = dict(parse_qsl(urlsplit(href).query, keep_blank_values=True))
        for name in FIELDS:
            assert asked[name] == given.get(name, "")


# --- /embed -----------------------------------------------------------------------------------


def test_embed_is_the_chart_and_a_link_back(client) -> None:  # type: ignore[no-untyped-def]
    query = {**EXAMPLE_QUERY, "cz": "5", "swap": "on"}
    response, html = page(client, "/embed", query)
    assert response.template.name == "embed.html"
    assert figure_data(html) == client.get("/api/chart", params=query).json()
    assert html.one("div", id="chart")
    assert not html.find("form") and not html.find("input")  # minimal: no calculator
    links = [attrs["href"] for attrs in html.find("a")]
    assert len(links) == 1
    target = urlsplit(links[0])
    assert target.path == "/"
    assert dict(parse_qsl(target.query)) == query
    assert html.find("a")[0]["target"] == "_blank"
    assert "noopener" in html.find("a")[0]["rel"]


def test_embed_with_a_bad_value_says_why(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/embed", {**EXAMPLE_QUERY, "ax": "abc"}, status=422)
    assert "A.x must be a number" in response.text
    assert not [attrs for attrs, _ in html.scripts if attrs.get("id") == "figure-data"]
    assert urlsplit(html.find("a")[0]["href"]).path == "/"


def test_embed_without_parameters_shows_the_example(client) -> None:  # type: ignore[no-untyped-def]
    _response, html = page(client, "/embed")
    assert figure_data(html)["data"][0]["x"] == [6.0, 3.0, 2.0, 7.0, 3.5]


@pytest.mark.parametrize("theme", ["auto", "light", "dark"])
def test_embed_takes_a_theme(client, theme: str) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/embed", {**EXAMPLE_QUERY, "theme": theme})
    assert response.context["theme"] == theme
    assert f"theme-{theme}" in str(html.one("body")["class"]).split()
    assert figure_data(html)["data"][0]["x"] == [6.0, 3.0, 2.0, 7.0, 3.5]


def test_embed_without_a_theme_follows_the_reader(client) -> None:  # type: ignore[no-untyped-def]
    response, _html = page(client, "/embed", EXAMPLE_QUERY)
    assert response.context["theme"] == "auto"


def test_embed_refuses_an_unknown_theme_in_one_sentence(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/embed", {**EXAMPLE_QUERY, "theme": "blue"}, status=422)
    assert html.one("p", class_="message error")
    assert "theme must be auto, light or dark, not &#39;blue&#39;." in response.text
    assert not [attrs for attrs, _ in html.scripts if attrs.get("id") == "figure-data"]
    assert response.context["errors"] == {"theme": "theme must be auto, light or dark, not 'blue'."}


# --- /docs ------------------------------------------------------------------------------------


def test_docs_work_offline(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/docs")
    assert response.template.name == "docs.html"
    urls = html.urls()
    assert urls
    for url in urls:
        parts = urlsplit(url)
        assert not parts.scheme and not parts.netloc, url  # nothing from another host
        assert url.startswith("/"), url
    assets = [url for url in urls if url.startswith("/static/")]
    assert {urlsplit(url).path for url in assets} >= {
        "/static/vendor/swagger-ui/swagger-ui-bundle.js",
        "/static/vendor/swagger-ui/swagger-ui.css",
        "/static/js/docs.js",
    }
    for url in assets:
        assert client.get(url).status_code == 200, url
    assert "http://" not in response.text and "https://" not in response.text
    root = html.one("div", id="swagger-ui")
    spec = client.get(root["data-openapi-url"])
    assert spec.status_code == 200
    assert spec.json()["info"]["title"] == "Mesh Normal Calculator"


def test_docs_script_fetches_nothing_from_elsewhere(client) -> None:  # type: ignore[no-untyped-def]
    script = client.get("/static/js/docs.js").text
    assert "http://" not in script and "https://" not in script
    assert "dataset.openapiUrl" in script


def test_openapi_lists_the_api_and_not_the_pages(client) -> None:  # type: ignore[no-untyped-def]
    spec = client.get("/openapi.json").json()
    assert set(spec["paths"]) == {
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
    assert set(spec["paths"]["/api/normal"]) == {"get", "post"}


def test_every_operation_is_named_in_words(client) -> None:  # type: ignore[no-untyped-def]
    """Swagger UI shows each summary as the operation's name; FastAPI's default is the function's
    name title-cased ("Post Normal"), which says nothing to a reader."""
    spec = client.get("/openapi.json").json()
    operations = [op for ops in spec["paths"].values() for op in ops.values()]
    summaries = [op.get("summary", "") for op in operations]
    for op, summary in zip(operations, summaries, strict=True):
        default = " ".join(op["operationId"].split("_api_")[0].split("_")).title()
        assert summary and summary != default and summary[0].isupper(), (op["operationId"], summary)
    assert len(set(summaries)) == len(summaries), summaries
    assert spec["paths"]["/api/normal"]["post"]["summary"] == "Normal of one triangle"


# --- Error pages and inline scripts -----------------------------------------------------------


def test_unknown_page_is_an_html_404(client) -> None:  # type: ignore[no-untyped-def]
    response, html = page(client, "/nope", status=404)
    assert response.template.name == "error.html"
    assert "There is no page at this address." in response.text
    assert html.one("a", class_="button primary")["href"] == "/"


PAGES = [
    ("GET", "/", 200),
    ("GET", "/?ax=abc", 422),
    ("GET", "/?" + urlencode(EXAMPLE_QUERY), 200),
    ("GET", "/embed", 200),
    ("GET", "/embed?ax=abc", 422),
    ("GET", "/docs", 200),
    ("GET", "/points", 200),
    ("GET", "/nope", 404),
    ("POST", "/", 405),
    ("GET", "/static/nope.js", 404),
]


@pytest.mark.parametrize(("method", "path", "status"), PAGES)
def test_no_inline_executable_script(client, method: str, path: str, status: int) -> None:  # type: ignore[no-untyped-def]
    response = client.request(method, path)
    assert response.status_code == status
    assert response.headers["content-type"].startswith("text/html")
    html = Page(response.text)
    assert html.scripts or status != 200 or path == "/docs"
    for attrs, content in html.scripts:
        if attrs.get("src"):
            assert not content.strip(), attrs
            assert attrs["src"].startswith("/static/"), attrs
        else:
            assert attrs.get("type") == "application/json", (attrs, content[:100])
            json.loads(content)
    for tag, attrs in html.elements:  # no inline handlers or javascript: URLs either
        assert not [key for key in attrs if key.startswith("on")], (tag, attrs)
        for key in ("href", "src", "action"):
            assert not (attrs.get(key) or "").lower().startswith("javascript:"), (tag, attrs)


# --- GET /partials: the live parts of the page ---------------------------------------------


def test_partials_render_every_live_part_from_the_page_templates(client) -> None:  # type: ignore[no-untyped-def]
    query = {**EXAMPLE_QUERY, "swap": "on"}
    parts = client.get("/partials", params=query).json()
    assert set(parts) == {"query", "errors", "missing", "html", "figure", "view3d"}
    assert parts["errors"] == {} and parts["missing"] == []
    assert set(parts["html"]) == {"result", "steps", "code"}
    page = client.get("/", params=query)
    # Each part is exactly what the full page renders in that place.
    for html in parts["html"].values():
        assert html.strip() in page.text
    assert parts["figure"] == client.get("/api/chart", params=query).json()
    assert parts["view3d"]["data"] and parts["view3d"]["layout"]
    assert "order A, C, B" in parts["html"]["result"]
    assert 'data-formula="n = (−6, −3, −2)"' in parts["html"]["steps"]


def test_partials_report_every_bad_field_with_status_200(client) -> None:  # type: ignore[no-untyped-def]
    query = {**EXAMPLE_QUERY, "ax": "abc", "cz": "", "swap": "maybe"}
    answer = client.get("/partials", params=query)
    assert answer.status_code == 200
    parts = answer.json()
    assert set(parts["errors"]) == {"ax", "swap"}
    assert parts["missing"] == ["cz"]  # blank: not wrong, not given yet
    assert parts["figure"] is None and parts["view3d"] is None
    assert "Fix the highlighted fields" in parts["html"]["result"]
