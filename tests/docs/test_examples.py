"""The documentation's Python examples run: each page's ```python blocks, in order, in one
namespace, from the repository's root (so that they may read ``tests/data/``). Blocks fenced
otherwise (```py, ```sh, ```text) are shown, not run: they need a server or a shell."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.paths import ROOT

DOCS = ROOT / "docs"
_BLOCK = re.compile(
    r"^(?P<indent>[ \t]*)```python[ \t]*\n(?P<code>.*?)^(?P=indent)```[ \t]*$", re.M | re.S
)


def blocks(page: Path) -> list[str]:
    """The page's runnable examples, dedented (a block may sit in a list or an admonition)."""
    found = []
    for match in _BLOCK.finditer(page.read_text(encoding="utf-8")):
        indent = len(match["indent"])
        found.append("".join(line[indent:] for line in match["code"].splitlines(keepends=True)))
    return found


PAGES = sorted(page for page in DOCS.rglob("*.md") if blocks(page))


def test_the_pages_have_examples_to_run() -> None:
    assert len(PAGES) >= 3


@pytest.mark.parametrize("page", PAGES, ids=lambda page: str(page.relative_to(DOCS)))
def test_the_examples_of_a_page_run(page: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    namespace: dict[str, object] = {"__name__": "__docs__"}
    for number, code in enumerate(blocks(page), start=1):
        try:
            exec(compile(code, f"{page.name}, example {number}", "exec"), namespace)
        except Exception as error:  # the page and the example in the failure's first line
            raise AssertionError(f"{page.name}, example {number}:\n{code}") from error
