"""JSON in and out of the API, both done by pydantic-core in Rust.

Bodies are read as raw bytes and validated straight from JSON (no ``json.loads`` pass and no
Python-side copy); responses are rendered with ``pydantic_core.to_json``. For a full batch of
100,000 triangles this is several times faster than the standard library.
"""

from __future__ import annotations

from typing import Any, TypeVar

from fastapi import Request
from fastapi.responses import JSONResponse
from pydantic import BaseModel, ValidationError
from pydantic_core import to_json

from app.errors import ApiError, from_validation

Model = TypeVar("Model", bound=BaseModel)


class FastJSONResponse(JSONResponse):
    def render(self, content: Any) -> bytes:
        return to_json(content)


def request_body_spec(model: type[BaseModel]) -> dict[str, Any]:
    """The OpenAPI ``requestBody`` of a route that reads ``model`` itself."""
    schema = model.model_json_schema(ref_template="#/components/schemas/{model}")
    return {"requestBody": {"required": True,
                            "content": {"application/json": {"schema": schema}}}}


async def read_body(request: Request, model: type[Model]) -> Model:
    """Validate the request body as ``model``; every failure becomes one ApiError."""
    raw = await request.body()
    if not raw.strip():
        raise ApiError(422, "The request body is empty; send a JSON object.")
    return parse_body(raw, model)


def parse_body(raw: bytes, model: type[Model]) -> Model:
    try:
        return model.model_validate_json(raw)
    except ValidationError as error:
        raise from_validation(error.errors(include_url=False)) from None
