"""A route class for endpoints that read the request themselves and return a response.

FastAPI's own handler solves the endpoint's dependencies on every request, even when the only
parameter is the :class:`~starlette.requests.Request` and the endpoint builds its response
itself, as every JSON route of the calculator does (the body is validated by
:func:`app.web.jsonio.read_body`, the response rendered by ``FastJSONResponse``). For
``POST /api/normal`` that step takes about a third of the request's time in the app.
:class:`RequestRoute` calls such an endpoint with the request directly. Everything else stays
FastAPI's: the routing, the OpenAPI schema (``openapi_extra``, ``response_model``), the
exception handlers (``request_response`` still wraps the handler) and the middleware.

An endpoint with any other signature gets FastAPI's handler unchanged, so the class is safe on
any router.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Coroutine
from typing import Any

from fastapi import Request
from fastapi.routing import APIRoute
from starlette.responses import Response

Handler = Callable[[Request], Coroutine[Any, Any, Response]]


def takes_only_the_request(endpoint: Callable[..., Any]) -> bool:
    """Whether ``endpoint`` is a coroutine function of one parameter annotated ``Request``."""
    if not inspect.iscoroutinefunction(endpoint):
        return False
    parameters = list(inspect.signature(endpoint, eval_str=True).parameters.values())
    return (
        len(parameters) == 1
        and parameters[0].annotation is Request
        and parameters[0].kind
        in (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
        and parameters[0].default is inspect.Parameter.empty
    )


class RequestRoute(APIRoute):
    """An API route whose ``async def endpoint(request: Request) -> Response`` is called
    directly (no dependency solving); any other endpoint is handled as FastAPI does."""

    def get_route_handler(self) -> Handler:
        if not takes_only_the_request(self.endpoint):
            return super().get_route_handler()
        endpoint = self.endpoint

        async def handler(request: Request) -> Response:
            response = await endpoint(request)
            if not isinstance(response, Response):  # a bug in the endpoint, not the request
                raise TypeError(
                    f"{endpoint.__qualname__} returned {type(response).__name__}, not a Response"
                )
            return response

        return handler
