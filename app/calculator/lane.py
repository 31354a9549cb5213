"""``POST /api/normal`` answered in one step where the fast path is sure: the fast lane.

The route itself (:func:`app.calculator.api.post_normal`) passes every request through the
middleware, the router, an included router and the route's exception wrappers: that stack
takes about two thirds of the request's time in the app, for the one
endpoint that people call in loops. This middleware sits outside the app's own middleware
(FastAPI's error and telemetry layers still wrap it) and answers a request there only when it
can write exactly what the whole stack would write:

- ``POST /api/normal`` with no ``root_path``, ``Content-Type: application/json`` exactly and a
  ``Content-Length`` within the path's body limit that the body matches;
- a body that :class:`~app.calculator.schemas.NormalRequest` accepts, with no key given twice;
- a triangle that :func:`app.calculator.fast.fast_payload` answers (not ``None``).

The answer is the same bytes with the same headers, in the same order: ``content-length`` and
``content-type`` as ``FastJSONResponse`` writes them, then the security headers. Anything else
(any doubt at all) goes down the whole stack with the body replayed, which then writes the
error or the exact path's answer. ``tests/app/calculator/test_lane.py`` sends the same requests
with and without the lane and compares status, headers and body.
"""

from __future__ import annotations

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app import config
from app.calculator.fast import fast_payload
from app.calculator.schemas import NormalRequest
from app.web.errors import ApiError
from app.web.headers import FRAMEABLE, FRAMED, UNFRAMED
from app.web.jsonio import json_bytes, refuse_duplicate_keys

PATH = "/api/normal"
_LIMIT = config.BODY_LIMITS.get(PATH, config.DEFAULT_BODY_LIMIT)
_SECURITY = FRAMED if PATH in FRAMEABLE else UNFRAMED
_CONTENT_TYPE = (b"content-type", b"application/json")
_validate_json = NormalRequest.model_validate_json


class NormalFastLane:
    """Answers the common ``POST /api/normal`` at once; passes everything else on."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if (
            scope["type"] != "http"
            or scope["path"] != PATH
            or scope["method"] != "POST"
            or scope.get("root_path")
        ):
            await self.app(scope, receive, send)
            return
        declared = _declared_json_length(scope["headers"])
        if declared is None:
            await self.app(scope, receive, send)
            return
        chunks: list[bytes] = []
        size = 0
        more = True
        while more:
            message = await receive()
            if message["type"] != "http.request":  # a disconnect: the stack sees it too
                await self.app(scope, _replay(chunks, receive, message), send)
                return
            chunk = message.get("body", b"")
            chunks.append(chunk)
            size += len(chunk)
            more = size <= declared and message.get("more_body", False)
        raw = chunks[0] if len(chunks) == 1 else b"".join(chunks)
        body = _answer(raw) if size == declared else None
        if body is None:
            stream_goes_on = bool(message.get("more_body", False))  # a body beyond its length
            await self.app(scope, _replay(chunks, receive, None, more=stream_goes_on), send)
            return
        await send(
            {
                "type": "http.response.start",
                "status": 200,
                "headers": [
                    (b"content-length", str(len(body)).encode()),
                    _CONTENT_TYPE,
                    *_SECURITY,
                ],
            }
        )
        await send({"type": "http.response.body", "body": body})


def _declared_json_length(headers: list[tuple[bytes, bytes]]) -> int | None:
    """The Content-Length of a JSON body within the limit, or ``None`` (then the stack)."""
    content_type = length = None
    for key, value in headers:
        if key == b"content-type":
            if content_type is not None:
                return None
            content_type = value
        elif key == b"content-length":
            if length is not None:
                return None
            length = value
    if content_type != b"application/json" or length is None or not length.isdigit():
        return None
    declared = int(length)
    return declared if 0 < declared <= _LIMIT else None


def _answer(raw: bytes) -> bytes | None:
    """The response body for ``raw``, or ``None`` where the stack must decide."""
    try:
        request = _validate_json(raw)
        refuse_duplicate_keys(raw)
    except (ValueError, ApiError):  # pydantic's ValidationError is a ValueError
        return None
    payload = fast_payload(request.a, request.b, request.c, request.swap_winding)
    return None if payload is None else json_bytes(payload)


def _replay(
    chunks: list[bytes], receive: Receive, last: Message | None, more: bool = False
) -> Receive:
    """A ``receive`` that gives the chunks already read, then ``last``, then the rest."""
    pending: list[Message] = [
        {"type": "http.request", "body": chunk, "more_body": True} for chunk in chunks
    ]
    if last is not None:
        pending.append(last)
    elif pending:
        pending[-1]["more_body"] = more
    else:
        pending.append({"type": "http.request", "body": b"", "more_body": more})

    async def replay() -> Message:
        if pending:
            return pending.pop(0)
        return await receive()

    return replay
