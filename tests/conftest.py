"""Shared fixtures: the app under test and a client for it, and the one error-shape check."""

from __future__ import annotations

import json
import warnings
from collections.abc import Iterator
from html.parser import HTMLParser

import pytest

with warnings.catch_warnings():
    # Starlette 1.x warns once, when its test client is first imported, that it would rather
    # use httpx2; httpx is what the project pins. Silence exactly that warning, only here.
    warnings.filterwarnings(
        "ignore", message=r"Using `httpx` with `starlette\.testclient` is deprecated"
    )
    from fastapi.testclient import TestClient

from app.main import create_app

#: The calculator's example, as query parameters (the page opens with it).
EXAMPLE_QUERY = {
    "ax": "1",
    "ay": "0",
    "az": "0",
    "bx": "0",
    "by": "2",
    "bz": "0",
    "cx": "0",
    "cy": "0",
    "cz": "3",
}


@pytest.fixture(scope="session")
def client() -> Iterator[TestClient]:
    with TestClient(create_app(), raise_server_exceptions=False) as test_client:
        yield test_client


def assert_error(response, status: int, field: str | None, *words: str) -> dict:  # type: ignore[no-untyped-def]
    """The one error shape: exactly {"error": one sentence, "field": name or null}.

    ``status`` is the exact status expected; ``words`` must all appear in the sentence.
    Returns the body for further checks.
    """
    assert response.status_code == status, (response.status_code, response.text)
    assert response.headers["content-type"].startswith("application/json"), response.headers
    body = json.loads(response.text)  # strict about the text, not just what httpx makes of it
    assert isinstance(body, dict), body
    assert set(body) == {"error", "field"}, body
    assert body["field"] == field, body
    sentence = body["error"]
    assert isinstance(sentence, str) and sentence.strip() == sentence and sentence, body
    # One sentence: it starts with a capital or with the field's own name, ends with a full
    # stop, and has no other sentence end inside (decimals like 1.5 and "e.g." are fine).
    assert sentence[0].isupper() or (field is not None and sentence.startswith(field)), sentence
    assert sentence.endswith("."), sentence
    inner = sentence[:-1]
    assert ". " not in inner.replace("e.g. ", "").replace("i.e. ", ""), sentence
    assert "\n" not in sentence, sentence
    for word in words:
        assert word in sentence, (word, sentence)
    for leak in ("Traceback", "pydantic", "ValidationError", "{'type'", "'loc'"):
        assert leak not in sentence, (leak, sentence)
    return body


VOID = frozenset(
    {
        "area",
        "base",
        "br",
        "col",
        "embed",
        "hr",
        "img",
        "input",
        "link",
        "meta",
        "source",
        "track",
        "wbr",
    }
)


class Page(HTMLParser):
    """Just enough of an HTML page: every element's attributes, scripts, and text by id."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.elements: list[tuple[str, dict[str, str | None]]] = []
        self.scripts: list[tuple[dict[str, str | None], str]] = []
        self._open: list[tuple[str, str | None, list[str]]] = []
        self._texts: dict[str, list[str]] = {}
        self.feed(text)
        self.close()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        attributes = dict(attrs)
        self.elements.append((tag, attributes))
        if tag == "script":
            self.scripts.append((attributes, ""))
        if tag not in VOID:
            key = attributes.get("id")
            if key is None and attributes.get("data-key") is not None:
                key = f"data-key={attributes['data-key']}"
            self._open.append((tag, key, []))

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.elements.append((tag, dict(attrs)))

    def handle_endtag(self, tag: str) -> None:
        while self._open:
            name, element_id, parts = self._open.pop()
            if element_id is not None:
                self._texts[element_id] = parts
            if name == tag:
                break

    def handle_data(self, data: str) -> None:
        if self._open and self._open[-1][0] == "script":
            attributes, content = self.scripts[-1]
            self.scripts[-1] = (attributes, content + data)
        for _, _, parts in self._open:
            parts.append(data)

    def find(self, tag: str, **wanted: str) -> list[dict[str, str | None]]:
        """Elements with that tag whose attributes include ``wanted`` (``class_`` = class)."""
        wanted = {key.rstrip("_"): value for key, value in wanted.items()}
        return [
            attrs
            for name, attrs in self.elements
            if name == tag and all(attrs.get(key) == value for key, value in wanted.items())
        ]

    def one(self, tag: str, **wanted: str) -> dict[str, str | None]:
        found = self.find(tag, **wanted)
        assert len(found) == 1, (tag, wanted, found)
        return found[0]

    def text(self, element_id: str) -> str:
        """The text inside the element with that id, whitespace collapsed."""
        return " ".join("".join(self._texts[element_id]).split())

    def cells(self) -> dict[str, str]:
        """{data-key: text} for the result cells (elements with a data-key and no id)."""
        prefix = "data-key="
        return {
            key.removeprefix(prefix): " ".join("".join(parts).split())
            for key, parts in self._texts.items()
            if key.startswith(prefix)
        }

    def urls(self) -> list[str]:
        """Every src and href in the page."""
        return [
            value
            for _, attrs in self.elements
            for key, value in attrs.items()
            if key in ("src", "href") and value is not None
        ]
