"""One error shape for every bad request: ``{"error": "<one sentence>", "field": ...}``.

Every failure, whatever raised it (our own checks, pydantic, Starlette's routing, the body
limit), ends here as an :class:`ApiError`, and :func:`install` registers the one handler
that renders it: JSON for API paths, an HTML page elsewhere.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import Match

from app.config import BATCH_LIMIT
from app.web.headers import security_headers

logger = logging.getLogger(__name__)


class ApiError(Exception):
    """A request the service refuses, with the status, a sentence and the field to blame."""

    def __init__(self, status_code: int, error: str, field: str | None = None) -> None:
        super().__init__(error)
        self.status_code = status_code
        self.error = error
        self.field = field

    def body(self) -> dict[str, str | None]:
        return {"error": self.error, "field": self.field}


ERROR_SCHEMA = {
    "type": "object",
    "properties": {
        "error": {"type": "string", "description": "One sentence saying what is wrong."},
        "field": {"type": ["string", "null"], "description": "The input to blame, as written."},
    },
    "required": ["error", "field"],
    "additionalProperties": False,
}

#: Documented error responses for every API route.
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    status: {"description": text, "content": {"application/json": {"schema": ERROR_SCHEMA}}}
    for status, text in (
        (400, "The body is not valid JSON."),
        (413, "The body or the batch is too large."),
        (415, "The body is not sent as application/json."),
        (422, "An input is missing or not a finite number, or a vector has the wrong length."),
    )
}


def field_name(location: Sequence[str | int]) -> str | None:
    """Name an input as the user wrote it: ``ax``, ``a[0]``, ``triangles[4][1][2]``."""
    parts = list(location)
    if parts and parts[0] in ("body", "query", "path"):
        parts = parts[1:]
    if not parts:
        return None
    name = str(parts[0])
    for part in parts[1:]:
        name += f"[{part}]" if isinstance(part, int) else f".{part}"
    return name


def clip(text: str) -> str:
    """What the user typed, cut to 20 characters for an error sentence."""
    return text if len(text) <= 20 else text[:17] + "..."


def describe(value: Any) -> str:
    """A few words for what the user sent instead, without echoing a huge value."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return f"the string {clip(value)!r}"
    if isinstance(value, list | tuple):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return "an object"
    return f"{value!r}"


def from_validation(errors: Sequence[Any]) -> ApiError:
    """Turn the first pydantic or FastAPI validation error into one sentence."""
    first = errors[0]
    kind = first.get("type", "")
    location = tuple(first.get("loc", ()))
    field = field_name(location)
    given = first.get("input")
    context = first.get("ctx") or {}
    if kind == "json_invalid":
        reason = context.get("error", "it cannot be parsed")
        where = location[-1] if location and isinstance(location[-1], int) else None
        at = f" at character {where}" if where is not None else ""
        return ApiError(400, f"The request body is not valid JSON: {reason}{at}.")
    if field is None:
        if isinstance(given, bytes | bytearray):
            return ApiError(
                422,
                "The request body must be a JSON object sent with Content-Type: application/json.",
            )
        if kind == "missing":
            return ApiError(422, "The request body is missing; send a JSON object.")
        return ApiError(422, f"The request body must be a JSON object, not {describe(given)}.")
    if field == "triangles" and kind == "too_long":
        count = context.get("actual_length")
        got = f" ({count:,} were sent)" if isinstance(count, int) else ""
        return ApiError(
            413,
            f"A batch holds at most {BATCH_LIMIT:,} triangles{got}; "
            "split it into several requests.",
            field,
        )
    return ApiError(422, _sentence(kind, field, given, context), field)


def _sentence(kind: str, field: str, given: Any, context: dict[str, Any]) -> str:
    if kind == "missing":
        return f"{field} is missing."
    if kind in ("float_type", "float_parsing", "int_type"):
        return f"{field} must be a JSON number, not {describe(given)}."
    if kind == "finite_number":
        return (
            f"{field} must be a finite number within the double range (about ±1.8e308); "
            "NaN, Infinity and larger numbers are not accepted."
        )
    if kind in ("too_short", "too_long"):
        is_triangle = field.startswith("triangles[") and field.count("[") == 1
        size = "3 points" if is_triangle else "3 numbers"
        actual = context.get("actual_length")
        return f"{field} must hold exactly {size}, not {actual}."
    if kind in ("list_type", "tuple_type"):
        return f"{field} must be a list, not {describe(given)}."
    if kind in ("bool_type", "bool_parsing"):
        return f"{field} must be true or false, not {describe(given)}."
    if kind in ("literal_error", "enum"):
        expected = context.get("expected", "one of the listed values")
        return f"{field} must be {expected}, not {describe(given)}."
    if kind in ("greater_than_equal", "less_than_equal"):
        bound = context.get("ge", context.get("le"))
        side = "at least" if kind == "greater_than_equal" else "at most"
        return f"{field} must be {side} {bound}, not {describe(given)}."
    if kind == "extra_forbidden":
        return f"{field} is not a field of this request."
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        return f"{field} must be a JSON object, not {describe(given)}."
    return f"{field} is not valid ({kind.replace('_', ' ')})."


def _is_api(request: Request) -> bool:
    path = request.url.path
    return path.startswith("/api/") or path == "/openapi.json"


async def _render(request: Request, error: ApiError) -> Response:
    if _is_api(request):
        return JSONResponse(error.body(), status_code=error.status_code)
    from app.calculator.pages import (
        error_page,  # the page layer renders HTML; imported late to avoid a cycle
    )

    return error_page(request, error)


_HTTP_SENTENCES = {
    404: "There is no page at this address.",
    405: "This address does not take that method.",
    413: "The request body is too large.",
}


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


def install(app: FastAPI) -> None:
    """Register the one set of handlers that turns every failure into an ApiError."""

    async def on_api_error(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, ApiError)
        return await _render(request, exc)

    async def on_validation(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, RequestValidationError)
        return await _render(request, from_validation(exc.errors()))

    async def on_http(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, StarletteHTTPException)
        sentence = _HTTP_SENTENCES.get(exc.status_code) or str(exc.detail)
        response = await _render(request, ApiError(exc.status_code, sentence))
        response.headers.update(exc.headers or {})
        if exc.status_code == 405:
            response.headers["allow"] = ", ".join(_allowed_methods(request))
        return response

    async def on_crash(request: Request, _exc: Exception) -> Response:
        logger.exception("unhandled error on %s", request.url.path)
        response = await _render(request, ApiError(500, "Something went wrong on our side."))
        # Starlette answers a crash outside every middleware, so the headers come from here.
        response.headers.update(security_headers(request.url.path))
        return response

    app.add_exception_handler(ApiError, on_api_error)
    app.add_exception_handler(RequestValidationError, on_validation)
    app.add_exception_handler(StarletteHTTPException, on_http)
    app.add_exception_handler(Exception, on_crash)
