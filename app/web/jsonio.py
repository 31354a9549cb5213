"""JSON in and out of the API, both done by pydantic-core in Rust.

Bodies are read as raw bytes and validated straight from JSON (no ``json.loads`` pass and no
Python-side copy); responses are rendered with ``pydantic_core.to_json``. For a full batch of
100,000 triangles this is several times faster than the standard library.

NaN and ±Infinity have no JSON spelling: ``to_json`` would write them as bare words, which
``JSON.parse`` and Python's strict parsers refuse, and Starlette's ``JSONResponse`` raises on
them. Every JSON text the app writes goes through :func:`json_bytes`, which writes them as
``null``: the product's rule for any value it cannot give as a double ("out of range is
null", with a message where a sentence is due). A NaN reaching a response is still a bug, and
the tests that parse responses strictly are where it shows; a user never gets invalid JSON.
"""

from __future__ import annotations

from typing import Any, TypeVar

from fastapi import Request
from fastapi.responses import JSONResponse
from pydantic import BaseModel, ValidationError
from pydantic_core import to_json

from app.web.errors import ApiError, from_validation

Model = TypeVar("Model", bound=BaseModel)


def json_bytes(content: Any) -> bytes:
    """Compact UTF-8 JSON, with NaN and ±Infinity written as ``null`` (never bare words)."""
    return to_json(content, inf_nan_mode="null")


class FastJSONResponse(JSONResponse):
    """The app's one JSON response: pydantic-core's speed, never invalid JSON."""

    def render(self, content: Any) -> bytes:
        return json_bytes(content)


def request_body_spec(model: type[BaseModel]) -> dict[str, Any]:
    """The OpenAPI ``requestBody`` of a route that reads ``model`` itself."""
    schema = model.model_json_schema(ref_template="#/components/schemas/{model}")
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": schema}}}}


async def raw_json_body(request: Request) -> bytes:
    """The body of a JSON request; refuses other content types and an empty body."""
    content_type = request.headers.get("content-type", "")
    media_type = content_type.split(";", 1)[0].strip().lower()
    if media_type != "application/json" and not media_type.endswith("+json"):
        raise ApiError(
            415, "The request body must be JSON sent with Content-Type: application/json."
        )
    raw = await request.body()
    if not raw.strip():
        raise ApiError(422, "The request body is empty; send a JSON object.")
    return raw


async def read_body(request: Request, model: type[Model]) -> Model:
    """Validate the request body as ``model``; every failure becomes one ApiError."""
    return parse_body(await raw_json_body(request), model)


def parse_body(raw: bytes, model: type[Model]) -> Model:
    try:
        return model.model_validate_json(raw)
    except ValidationError as error:
        errors = [
            {**item, "loc": ("body", *item["loc"])} for item in error.errors(include_url=False)
        ]
        raise from_validation(errors) from None
