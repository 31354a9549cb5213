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
from starlette.requests import ClientDisconnect
from starlette.routing import Match, Mount
from starlette.staticfiles import StaticFiles

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
    """Every method some route takes at this path (Starlette names only the first route's).

    HEAD goes with GET (:class:`app.web.middleware.HeadAsGet`). A path under a mount (the
    static files) takes what the mounted app takes: GET and HEAD.
    """
    scope = request.scope
    if isinstance(scope.get("endpoint"), StaticFiles):
        return ["GET", "HEAD"]
    routes = [route for route in request.app.router.routes if not isinstance(route, Mount)]
    methods = [
        method
        for method in ("GET", "POST", "PUT", "PATCH", "DELETE")
        if any(route.matches({**scope, "method": method})[0] == Match.FULL for route in routes)
    ]
    return [*methods[:1], "HEAD", *methods[1:]] if methods[:1] == ["GET"] else methods


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


#: What Python's tempfile says when no folder it tries (TMPDIR, /tmp, /var/tmp, ...) is writable.
NO_TEMP_DIR = "No usable temporary directory"

#: The answer then: the server's own state, said as such (not a 500, not the user's fault).
NO_TEMP_DIR_SENTENCE = (
    "The server has no writable temporary folder for this request; "
    "its operator must give it one (a tmpfs at /tmp)."
)


async def on_file_not_found(request: Request, exc: Exception) -> Response:
    """A missing temporary folder is a 503 that says so; any other missing file is a crash."""
    assert isinstance(exc, FileNotFoundError)
    if NO_TEMP_DIR not in str(exc):
        return await on_crash(request, exc)
    logger.error("%s: %s (mount a tmpfs at /tmp)", request.url.path, exc)
    return render_error(request, ApiError(503, NO_TEMP_DIR_SENTENCE))


async def on_disconnect(request: Request, exc: Exception) -> Response:
    """A client that left while its body was being read: one line in the log, no traceback
    (hundreds of them must not flood it); the answer goes nowhere."""
    assert isinstance(exc, ClientDisconnect)
    logger.info("client left while sending its request to %s", request.url.path)
    return Response(status_code=499)


async def on_crash(request: Request, _exc: Exception) -> Response:
    logger.exception("unhandled error on %s", request.url.path)
    response = render_error(request, ApiError(500, "Something went wrong on our side."))
    # Starlette answers a crash outside every middleware, so the headers come from here.
    response.headers.update(security_headers(request.url.path))
    return response


def install(app: FastAPI) -> None:
    """Register the one set of handlers that turns every failure into an ApiError (a missing
    temporary folder, where something needs one, into a 503 that says so)."""
    app.add_exception_handler(FileNotFoundError, on_file_not_found)
    app.add_exception_handler(ClientDisconnect, on_disconnect)
    app.add_exception_handler(ApiError, on_api_error)
    app.add_exception_handler(RequestValidationError, on_validation)
    app.add_exception_handler(StarletteHTTPException, on_http)
    app.add_exception_handler(Exception, on_crash)
