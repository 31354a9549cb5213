"""RequestRoute calls an endpoint of one Request directly; every other endpoint as FastAPI does."""

from __future__ import annotations

from fastapi import APIRouter, FastAPI, Request
from fastapi.testclient import TestClient
from starlette.responses import JSONResponse, Response

from app.web.routes import RequestRoute, takes_only_the_request


async def only_the_request(request: Request) -> Response:
    return JSONResponse({"path": request.url.path})


async def with_a_query(_request: Request, n: int) -> Response:
    return JSONResponse({"n": n})


def plain(_request: Request) -> Response:
    return JSONResponse({})


async def keyword_only(*, _request: Request) -> Response:
    return JSONResponse({})


async def with_a_default(_request: Request = None) -> Response:  # type: ignore[assignment]
    return JSONResponse({})


async def returns_a_dict(_request: Request) -> dict[str, int]:
    return {"n": 1}


def test_only_an_async_endpoint_of_one_request_is_called_directly() -> None:
    assert takes_only_the_request(only_the_request)
    for endpoint in (with_a_query, plain, keyword_only, with_a_default):
        assert not takes_only_the_request(endpoint), endpoint.__name__


def app_with(*endpoints) -> TestClient:  # type: ignore[no-untyped-def]
    router = APIRouter(route_class=RequestRoute)
    for endpoint in endpoints:
        router.add_api_route(f"/{endpoint.__name__}", endpoint, methods=["GET"])
    app = FastAPI()
    app.include_router(router)
    return TestClient(app, raise_server_exceptions=False)


def test_the_direct_handler_answers_and_other_endpoints_keep_fastapis() -> None:
    client = app_with(only_the_request, with_a_query, plain)
    assert client.get("/only_the_request").json() == {"path": "/only_the_request"}
    assert client.get("/with_a_query", params={"n": "7"}).json() == {"n": 7}
    assert client.get("/with_a_query", params={"n": "x"}).status_code == 422  # FastAPI's
    assert client.get("/plain").json() == {}


def test_a_direct_endpoint_that_returns_no_response_is_a_server_error() -> None:
    client = app_with(returns_a_dict)
    assert client.get("/returns_a_dict").status_code == 500


def test_the_schema_still_lists_a_direct_route() -> None:
    client = app_with(only_the_request)
    assert "/only_the_request" in client.get("/openapi.json").json()["paths"]
