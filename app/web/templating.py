"""The one Jinja environment every page renders with, and its filters.

Pages call ``templates.TemplateResponse(request, name, context)``; tests read
``response.template.name`` and ``response.context`` instead of scraping the HTML.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fastapi.templating import Jinja2Templates
from markupsafe import Markup

from app.web.formatting import number_text as people_number
from app.web.jsonio import json_bytes
from app.web.links import public_url
from app.web.static import static_url

TEMPLATES_DIR = Path(__file__).resolve().parents[2] / "templates"


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
templates.env.globals["static_url"] = static_url
templates.env.globals["public_url"] = public_url
templates.env.filters["num"] = number_text
templates.env.filters["json_script"] = json_script
