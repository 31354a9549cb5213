"""The one Jinja environment every page renders with, and its filters.

Pages call ``templates.TemplateResponse(request, name, context)``; tests read
``response.template.name`` and ``response.context`` instead of scraping the HTML.
"""

from __future__ import annotations

import os
import pickle
import sys
from pathlib import Path
from typing import Any

from fastapi.templating import Jinja2Templates
from jinja2 import FileSystemBytecodeCache
from jinja2.bccache import Bucket
from markupsafe import Markup

from app.web.formatting import number_text as people_number
from app.web.jsonio import json_bytes
from app.web.links import guide_url, public_url
from app.web.static import static_url

TEMPLATES_DIR = Path(__file__).resolve().parents[2] / "templates"

#: Compiled templates, as ``__pycache__`` holds compiled modules: compiling the calculator's
#: page and the templates it extends takes about ten times as long as loading them compiled,
#: at the server's first answer. ``make env``, ``make run`` and the image fill it
#: (``python -m app.web.templating``); an entry is used only while its template's source is
#: unchanged (Jinja keeps a checksum).
CACHE_DIR = TEMPLATES_DIR / "__pycache__"


class TemplateCache(FileSystemBytecodeCache):
    """Jinja's file cache, which a server that may not write its folder (the image's) only
    reads, and which a server that cannot read an entry of it (unreadable, cut short) does
    without: a template compiled at run time then stays in memory."""

    def load_bytecode(self, bucket: Bucket) -> None:
        try:
            super().load_bytecode(bucket)
        except (OSError, EOFError, ValueError, pickle.UnpicklingError):
            bucket.reset()

    def dump_bytecode(self, bucket: Bucket) -> None:
        try:
            os.makedirs(self.directory, exist_ok=True)
            super().dump_bytecode(bucket)
        except OSError:
            pass


def json_script(value: Any) -> Markup:
    """JSON that is safe inside ``<script type="application/json">`` (NaN as null, as the API)."""
    text = json_bytes(value).decode()
    return Markup(text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026"))


def number_text(value: float | None) -> str:
    """A number for people, in JavaScript's ``String(x)`` layout with the real minus sign.

    None is out of the double range. The page's script reads either minus back.
    """
    return "out of range" if value is None else people_number(value)


templates = Jinja2Templates(directory=TEMPLATES_DIR)
templates.env.bytecode_cache = TemplateCache(str(CACHE_DIR), "%s.cache")
templates.env.globals["static_url"] = static_url
templates.env.globals["public_url"] = public_url
templates.env.globals["guide_url"] = guide_url
templates.env.filters["num"] = number_text
templates.env.filters["json_script"] = json_script


def compile_templates() -> int:
    """Compile every template into :data:`CACHE_DIR`; how many there are."""
    names = templates.env.list_templates(extensions=["html"])
    for name in names:
        templates.env.get_template(name)
    return len(names)


if __name__ == "__main__":
    sys.exit(0 if compile_templates() else 1)
