"""mkdocs hooks: pages that are written from the code at build time."""

from __future__ import annotations

from typing import Any


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    return markdown
