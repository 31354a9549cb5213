"""The one handler set: every failure becomes an :class:`ApiError`, rendered one way.

JSON (the one error shape) for API paths, the HTML error page elsewhere. The exceptions in
:mod:`app.web.errors` know nothing of pages; only this module renders them, so nothing that
raises an error imports a template.
"""

from __future__ import annotations

import logging

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import Match

from app.web.errors import ApiError, from_validation
from app.web.headers import security_headers
from app.web.jsonio import FastJSONResponse
from app.web.templating import templates

logger = logging.getLogger(__name__)

_HTTP_SENTENCES = {
    404: "There is no page at this address.",
    405: "This address does not take that method.",
    413: "The request body is too large.",
}


def _is_api(request: Request) -> bool:
    path = request.url.path
    return path.startswith("/api/") or path == "/openapi.json"


def render_error(request: Request, error: ApiError) -> Response:
    """The error as JSON for the API, as the HTML error page for everything else."""
    if _is_api(request):
        return FastJSONResponse(error.body(), status_code=error.status_code, headers=error.headers)
    return templates.TemplateResponse(
        request,
        "error.html",
        {"error": error},
        status_code=error.status_code,
        headers=error.headers,
    )


def _allowed_methods(request: Request) -> list[str]:
    """Every method some route takes at this path (Starlette names only the first route's)."""
    routes = request.app.router.routes
    return [
        method
        for method in ("GET", "HEAD", "POST", "PUT", "PATCH", "DELETE")
        if any(
            route.matches({**request.scope, "method": method})[0] == Match.FULL for route in routes
        )
    ]


async def on_api_error(request: Request, exc: Exception) -> Response:
    assert isinstance(exc, ApiError)
    return render_error(request, exc)


async def on_validation(request: Request, exc: Exception) -> Response:
    assert isinstance(exc, RequestValidationError)
    return render_error(request, from_validation(exc.errors()))


async def on_http(request: Request, exc: Exception) -> Response:
    assert isinstance(exc, StarletteHTTPException)
    sentence = _HTTP_SENTENCES.get(exc.status_code) or str(exc.detail)
    response = render_error(request, ApiError(exc.status_code, sentence))
    response.headers.update(exc.headers or {})
    if exc.status_code == 405:
        response.headers["allow"] = ", ".join(_allowed_methods(request))
    return response


async def on_crash(request: Request, _exc: Exception) -> Response:
    logger.exception("unhandled error on %s", request.url.path)
    response = render_error(request, ApiError(500, "Something went wrong on our side."))
    # Starlette answers a crash outside every middleware, so the headers come from here.
    response.headers.update(security_headers(request.url.path))
    return response


def install(app: FastAPI) -> None:
    """Register the one set of handlers that turns every failure into an ApiError."""
    app.add_exception_handler(ApiError, on_api_error)
    app.add_exception_handler(RequestValidationError, on_validation)
    app.add_exception_handler(StarletteHTTPException, on_http)
    app.add_exception_handler(Exception, on_crash)
