"""The app itself with one more route: an echo of the JSON body, before every other route.

Beside the bare echo app it tells our stack's cost (the middleware, the routing, the error
handlers) apart from the calculator's own work in ``POST /api/normal``.
"""

from __future__ import annotations

from typing import Any

from fastapi import Request

from app.main import create_app
from app.web.jsonio import FastJSONResponse

app = create_app()


async def echo(request: Request) -> FastJSONResponse:
    """The body parsed and sent back, as the bare app's ``/echo-raw``."""
    body: Any = await request.json()
    return FastJSONResponse(body)


app.router.add_api_route("/api/echo", echo, methods=["POST"])
app.router.routes.insert(0, app.router.routes.pop())  # matched first, as /api/normal nearly is
