"""One error shape for every bad request: ``{"error": "<one sentence>", "field": ...}``.

Every failure, whatever raised it (our own checks, pydantic, Starlette's routing, the body
limit), becomes an :class:`ApiError`. This module only says what went wrong, in one
sentence; :mod:`app.web.handlers` renders it (JSON for API paths, an HTML page elsewhere), so
the exception knows nothing of pages.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from app.config import BATCH_LIMIT


class ApiError(Exception):
    """A request the service refuses, with the status, a sentence and the field to blame."""

    def __init__(
        self,
        status_code: int,
        error: str,
        field: str | None = None,
        headers: dict[str, str] | None = None,
    ) -> None:
        super().__init__(error)
        self.status_code = status_code
        self.error = error
        self.field = field
        self.headers = headers or {}  # e.g. Retry-After with a 503

    def __reduce__(self) -> tuple[type[ApiError], tuple[Any, ...]]:
        """Pickled whole: a refusal raised in a worker process is raised again in the server."""
        return ApiError, (self.status_code, self.error, self.field, self.headers)

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
        (
            422,
            "An input is missing or not a finite number, a vector has the wrong length, "
            "or a key is given twice.",
        ),
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
        reason = str(context.get("error", "it cannot be parsed"))
        if reason.startswith("number out of range"):
            # An integer literal of more than 4,300 digits: out of range like 1e400, so a 422.
            place = reason.removeprefix("number out of range").strip()
            return ApiError(
                422,
                "A number in the request body"
                + (f", {place}," if place else "")
                + " is beyond the double range (about ±1.8e308); NaN, Infinity and larger "
                "numbers are not accepted.",
            )
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
