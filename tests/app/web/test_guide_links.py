"""The pages' links to the guide (``MESH_DOCS_URL``): shown where they explain what a page shows
when the operator set the documentation site's address, absent otherwise, and every one aimed at
a heading that exists in docs/."""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from app.config import Settings
from app.main import create_app
from tests.app.points.test_page import cylinder_xyz
from tests.conftest import Page
from tests.meshes import CUBE_ONE_FLIPPED_OBJ
from tests.paths import ROOT

DOCS = "https://docs.example.org/"


def guide_links(text: str) -> set[str]:
    """Every link to the guide on a page: the ``rel="help"`` ones."""
    return {
        str(attributes["href"])
        for tag, attributes in Page(text).elements
        if tag == "a" and attributes.get("rel") == "help"
    }


@pytest.fixture(scope="module")
def with_docs() -> Iterator[TestClient]:
    app = create_app(settings=Settings(in_process=True, docs_url=DOCS))
    with TestClient(app, raise_server_exceptions=False) as client:
        yield client


@pytest.fixture(scope="module")
def without_docs() -> Iterator[TestClient]:
    app = create_app(settings=Settings(in_process=True, docs_url=None))
    with TestClient(app, raise_server_exceptions=False) as client:
        yield client


def pages(client: TestClient) -> dict[str, str]:
    """The pages that link to the guide, by name: their HTML."""
    found = {path: client.get(path) for path in ("/docs", "/", "/mesh", "/points")}
    cube = {"file": ("cube.obj", CUBE_ONE_FLIPPED_OBJ.encode())}
    found["mesh report"] = client.post("/mesh", files=cube)
    found["mesh fragment"] = client.post("/mesh", params={"part": "report"}, files=cube)
    found["mesh sample"] = client.get("/mesh/sample/inside-out")
    found["points report"] = client.post("/points", files={"file": ("c.xyz", cylinder_xyz())})
    for name, response in found.items():
        assert response.status_code == 200, (name, response.text[:500])
    return {name: response.text for name, response in found.items()}


#: What each page links to, below ``MESH_DOCS_URL``.
EXPECTED = {
    "/docs": {"calculator/#json-api", "meshes/#the-mesh-api", "points/#the-point-cloud-api"},
    "/": {"calculator/#what-it-computes", "calculator/#json-api"},
    "/mesh": {"meshes/#what-is-checked-and-the-rules", "meshes/#the-weld-tolerance"},
    "/points": {
        "points/#how-normals-are-estimated",
        "points/#orientation",
        "points/#neighbourhoods",
    },
    "mesh report": {
        "meshes/#the-weld-tolerance",
        "meshes/#winding-and-orientation",
        "meshes/#what-is-checked-and-the-rules",
        "meshes/#the-diagnosis",
    },
    "mesh fragment": {
        "meshes/#winding-and-orientation",
        "meshes/#what-is-checked-and-the-rules",
        "meshes/#the-diagnosis",
    },
    "mesh sample": {
        "meshes/#the-weld-tolerance",
        "meshes/#winding-and-orientation",
        "meshes/#what-is-checked-and-the-rules",
        "meshes/#the-diagnosis",
    },
    "points report": {
        "points/#how-normals-are-estimated",
        "points/#orientation",
        "points/#neighbourhoods",
        "points/#points-without-a-normal",
    },
}


def test_with_a_docs_address_the_pages_link_to_the_guide(with_docs: TestClient) -> None:
    found = {name: guide_links(text) for name, text in pages(with_docs).items()}
    assert found == {name: {DOCS + page for page in links} for name, links in EXPECTED.items()}


def test_without_one_there_is_no_link_and_no_word_of_it(without_docs: TestClient) -> None:
    for name, text in pages(without_docs).items():
        assert guide_links(text) == set(), name
        assert "the guide" not in text.lower(), name
        assert 'id="guide-' not in text, name


@pytest.mark.parametrize(
    ("address", "link"),
    [
        ("https://example.org", "https://example.org/calculator/#json-api"),
        ("http://example.org/mesh/docs", "http://example.org/mesh/docs/calculator/#json-api"),
        ("https://example.org:8443/docs/", "https://example.org:8443/docs/calculator/#json-api"),
    ],
)
def test_the_address_and_the_page_are_joined_by_one_slash(address: str, link: str) -> None:
    app = create_app(settings=Settings(in_process=True, docs_url=address))
    with TestClient(app, raise_server_exceptions=False) as client:
        assert link in guide_links(client.get("/docs").text)


def slug(heading: str) -> str:
    """The anchor mkdocs (Python-Markdown's toc) makes of a heading."""
    text = unicodedata.normalize("NFKD", heading.replace("`", "")).encode("ascii", "ignore")
    words = re.sub(r"[^\w\s-]", "", text.decode()).strip().lower()
    return re.sub(r"[-\s]+", "-", words)


def anchors(page: str) -> set[str]:
    """The anchors of the headings of docs/``page``.md, outside code blocks."""
    found, fenced = set(), False
    for line in (ROOT / "docs" / f"{page}.md").read_text().splitlines():
        if line.startswith("```"):
            fenced = not fenced
        elif not fenced and (heading := re.match(r"#{1,6} (.+?)\s*#*$", line)):
            found.add(slug(heading.group(1)))
    return found


def test_every_link_to_the_guide_names_a_heading_of_its_page() -> None:
    links = {
        link
        for template in (ROOT / "templates").glob("*.html")
        for link in re.findall(r"guide_url\('([^']*)'\)", template.read_text())
    }
    assert {link for name in EXPECTED for link in EXPECTED[name]} == links
    for link in links:
        page, _, anchor = link.partition("/#")
        assert anchor in anchors(page), f"docs/{page}.md has no heading whose anchor is {anchor}"
