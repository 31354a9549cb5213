"""Pure ASGI middleware: security headers, gzip for pages, and the request body limit."""

from __future__ import annotations

import json

from starlette.middleware.gzip import GZipMiddleware
from starlette.types import ASGIApp, Message, Receive, Scope, Send

import app.config as config
from app.web.errors import ApiError
from app.web.headers import FRAMEABLE, FRAMED, UNFRAMED


class SecurityHeaders:
    """Adds CSP (no inline scripts), nosniff, a referrer policy and the framing rules."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        extra = FRAMED if scope["path"] in FRAMEABLE else UNFRAMED

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                message["headers"] = [*message.get("headers", []), *extra]
            await send(message)

        await self.app(scope, receive, send_with_headers)


class HeadAsGet:
    """HEAD is answered as GET without the body (RFC 9110: same status and headers).

    FastAPI's routes take only the methods they name, so without this ``HEAD /`` is a 405.
    The request goes on as a GET; every body message is sent empty (the headers, with the
    Content-Length of the GET's body, are kept).
    """

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] != "HEAD":
            await self.app(scope, receive, send)
            return

        async def without_body(message: Message) -> None:
            if message["type"] == "http.response.body":
                message = {**message, "body": b""}
            await send(message)

        await self.app({**scope, "method": "GET"}, receive, without_body)


class PageCompression:
    """Gzip for HTML pages, whose size grows with a mesh report's 3D view data.

    API responses are left as they are (their overhead is what the benchmarks measure, and
    downloads such as .npy are for scripts), and static files come pre-compressed.
    """

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        path = scope.get("path", "")
        if scope["type"] != "http" or path.startswith(("/api/", "/static/")):
            await self.app(scope, receive, send)
            return

        async def app(scope: Scope, receive: Receive, gzip_send: Send) -> None:
            async def route(message: Message) -> None:
                # GZipMiddleware drops the template debug message that the TestClient reads.
                await (send if message["type"] == "http.response.debug" else gzip_send)(message)

            await self.app(scope, receive, route)

        await GZipMiddleware(app, minimum_size=1024, compresslevel=6)(scope, receive, send)


class BodyLimit:
    """Answers 413 beyond the path's body limit; nothing is parsed or half-processed then.

    Small JSON bodies are read whole up front, so the app is never called for one that is too
    large. Mesh uploads (``MESH_PATHS``) are streamed instead: a ``Content-Length`` beyond the
    limit is refused at once, and a body that grows past it mid-way raises ``ApiError(413)``
    inside the route, which stops parsing and drops what was read.
    """

    def __init__(self, app: ASGIApp, upload_limit: int | None = None) -> None:
        self.app = app
        self.upload_limit = config.upload_limit() if upload_limit is None else upload_limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] in ("GET", "HEAD", "OPTIONS"):
            await self.app(scope, receive, send)
            return
        streamed = scope["path"].rstrip("/") in config.MESH_PATHS  # "/api/mesh/" redirects
        limit = (
            self.upload_limit
            if streamed
            else config.BODY_LIMITS.get(scope["path"], config.DEFAULT_BODY_LIMIT)
        )
        declared = _content_length(scope)
        if streamed:
            # Refused inside the route, where the one error handler answers: JSON for the API,
            # the HTML page for /mesh. A declared length beyond the limit fails at once.
            await self.app(scope, _counted(receive, limit, declared or 0), send)
            return
        if declared is not None and declared > limit:
            await _too_large(send, limit)
            return
        chunks: list[bytes] = []
        size = 0
        more = True
        while more:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > limit:
                await _too_large(send, limit)
                return
            chunks.append(chunk)
            more = message.get("more_body", False)
        body = b"".join(chunks)
        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)


def _counted(receive: Receive, limit: int, declared: int) -> Receive:
    size = 0

    async def counted() -> Message:
        nonlocal size
        if declared > limit:
            raise ApiError(413, too_large_sentence(limit))
        message = await receive()
        size += len(message.get("body", b""))
        if size > limit:
            raise ApiError(413, too_large_sentence(limit))
        return message

    return counted


def _content_length(scope: Scope) -> int | None:
    for key, value in scope["headers"]:
        if key == b"content-length":
            try:
                return int(value)
            except ValueError:
                return None
    return None


def size_text(size: int) -> str:
    if size >= 1024 * 1024:
        return f"{size / (1024 * 1024):.4g} MB"
    return f"{size / 1024:.4g} KB"


def too_large_sentence(limit: int) -> str:
    return f"The request body is larger than {size_text(limit)}, the limit for this address."


async def _too_large(send: Send, limit: int) -> None:
    body = json.dumps(ApiError(413, too_large_sentence(limit)).body()).encode()
    await send(
        {
            "type": "http.response.start",
            "status": 413,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
                (b"connection", b"close"),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})
