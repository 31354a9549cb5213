"""HTML pages: the calculator, its live parts, the embeddable chart and the API docs."""

from __future__ import annotations

from typing import Any
from urllib.parse import urlencode

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse

from app.calculator.calculation import calculation_payload, from_typed, result_math
from app.calculator.chart import bar_figure
from app.calculator.params import read_triangle
from app.calculator.presets import COORDINATE_FIELDS, EXAMPLE, PRESETS
from app.calculator.snippets import snippets
from app.calculator.steps import worked_steps
from app.calculator.view3d import view3d_figure
from app.web.errors import ApiError, clip
from app.web.jsonio import FastJSONResponse
from app.web.templating import templates

router = APIRouter(include_in_schema=False)


def _calculation(request: Request) -> dict[str, Any]:
    """What every page shows for its query: typed values, errors, result, payload and chart."""
    query = request.query_params
    given = any(name in query for name in COORDINATE_FIELDS)
    parsed = read_triangle(query if given else {**EXAMPLE, **query})
    context: dict[str, Any] = {
        "typed": parsed.typed,
        "swap": parsed.swap,
        "errors": parsed.errors,
        "missing": parsed.missing,
        "missing_line": parsed.missing_line(),
        "problem": None if parsed.valid else parsed.first_error(),
        "result": None,
        "payload": None,
        "figure": None,
        "calculation": None,
        "result_math": {},
    }
    swap_text = "on" if parsed.swap else query.get("swap") if "swap" in parsed.errors else None
    params = {**parsed.typed, **({"swap": swap_text} if swap_text else {})}
    context["query"] = urlencode(params)
    if parsed.valid:
        calc = from_typed(parsed)
        context["result"] = calc.result
        context["calculation"] = calc
        context["payload"] = calculation_payload(calc)
        context["result_math"] = result_math(calc, context["payload"])
        context["figure"] = bar_figure(context["payload"])
    return context


def _with_details(context: dict[str, Any]) -> dict[str, Any]:
    """Add what only the calculator shows (presets, steps, 3D view, code); /embed skips it."""
    result, payload = context["result"], context["payload"]
    return {
        **context,
        "presets": PRESETS,
        "steps": None if result is None else worked_steps(result, context["calculation"].exact),
        "view3d": None if payload is None else view3d_figure(payload),
        "snippets": [] if payload is None else snippets(payload, context["calculation"].typed),
    }


def _status(context: dict[str, Any]) -> int:
    return 200 if context["problem"] is None else 422


@router.get("/", response_class=HTMLResponse)
def calculator(request: Request) -> HTMLResponse:
    context = _with_details(_calculation(request))
    response = templates.TemplateResponse(
        request, "index.html", context, status_code=_status(context)
    )
    response.headers["link"] = (
        f'</api/normal?{context["query"]}>; rel="alternate"; type="application/json"'
    )
    return response


#: The page's parts that live updates re-render, by element id and template.
PARTS = {"result": "_result.html", "steps": "_steps.html", "code": "_code.html"}


@router.get("/partials")
def partials(request: Request) -> FastJSONResponse:
    """The page's live parts for a query: HTML from the same templates, plus the figures.

    Always 200, so that a typing mistake is data for the page, not a failed request.
    """
    context = _with_details(_calculation(request))
    html = {
        element: templates.get_template(name).render({**context, "request": request})
        for element, name in PARTS.items()
    }
    return FastJSONResponse(
        {
            "query": context["query"],
            "errors": context["errors"],
            "missing": context["missing"],
            "html": html,
            "figure": context["figure"],
            "view3d": context["view3d"],
        }
    )


#: The embed's colours: "auto" follows the reader's prefers-color-scheme, the others fix them to
#: match the page around the frame.
EMBED_THEMES = ("auto", "light", "dark")


def _with_theme(context: dict[str, Any], theme: str) -> dict[str, Any]:
    """Refuse an unknown theme as the API refuses an unknown value: one sentence, no chart."""
    if theme in EMBED_THEMES:
        return {**context, "theme": theme}
    sentence = f"theme must be auto, light or dark, not {clip(theme)!r}."
    return {
        **context,
        "theme": "auto",
        "figure": None,
        "errors": {"theme": sentence, **context["errors"]},
        "problem": ApiError(422, sentence, "theme"),
    }


@router.get("/embed", response_class=HTMLResponse)
def embed(request: Request) -> HTMLResponse:
    theme = request.query_params.get("theme", "auto")
    context = _with_theme(_calculation(request), theme)
    return templates.TemplateResponse(request, "embed.html", context, status_code=_status(context))


@router.get("/docs", response_class=HTMLResponse)
def docs(request: Request) -> HTMLResponse:
    """Swagger UI from our own files, started by an external script (no inline script)."""
    return templates.TemplateResponse(request, "docs.html", {"openapi_url": "/openapi.json"})
