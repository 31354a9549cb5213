"""JSON API: one triangle, a batch, and the chart figure."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, FastAPI, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import Response

from app.calculator import batch
from app.calculator.calculation import calculation_payload, from_doubles, from_typed
from app.calculator.chart import bar_figure
from app.calculator.params import query_parameters_spec, read_triangle
from app.calculator.payloads import payload_csv
from app.calculator.schemas import BatchRequest, BatchResult, Figure, NormalRequest, NormalResult
from app.web.errors import ERROR_RESPONSES
from app.web.jobs import Jobs
from app.web.jsonio import (
    FastJSONResponse,
    raw_json_body,
    read_body,
    request_body_spec,
)

router = APIRouter(
    prefix="/api",
    tags=["normals"],
    responses=ERROR_RESPONSES,
    default_response_class=FastJSONResponse,
)


def query_payload(request: Request) -> dict[str, Any]:
    """The result for the page's query parameters, or the first error as an ApiError."""
    parsed = read_triangle(request.query_params)
    if not parsed.valid:
        raise parsed.first_error()
    return calculation_payload(from_typed(parsed))


async def post_normal(request: Request) -> FastJSONResponse:
    """The normal of one triangle given as JSON."""
    body = await read_body(request, NormalRequest)
    calc = from_doubles(body.a, body.b, body.c, swap_winding=body.swap_winding)
    return FastJSONResponse(calculation_payload(calc))


def add_post_normal(app: FastAPI) -> None:
    """``POST /api/normal`` as a route of the app itself, before the routers are included.

    It is the endpoint people call in loops, and FastAPI matches a route of an included router
    twice a request (once to find the router, once inside it), about 13 µs of the 200 or so
    that a request costs the server; a route of the app is matched once.
    """
    app.add_api_route(
        "/api/normal",
        post_normal,
        methods=["POST"],
        summary="Normal of one triangle",
        response_model=NormalResult,
        openapi_extra=request_body_spec(NormalRequest),
        tags=["normals"],
        responses=ERROR_RESPONSES,
        response_class=FastJSONResponse,
    )


@router.get(
    "/normal",
    summary="Normal of one triangle, from query parameters",
    response_model=NormalResult,
    openapi_extra=query_parameters_spec(),
)
async def get_normal(
    request: Request,
) -> FastJSONResponse:
    """The normal for the calculator page's query parameters: the JSON twin of a result page."""
    return FastJSONResponse(query_payload(request))


@router.get(
    "/normal.csv",
    summary="Normal of one triangle as CSV",
    response_class=Response,
    openapi_extra=query_parameters_spec(),
    responses={
        200: {
            "description": "One header row and one result row.",
            "content": {"text/csv": {"schema": {"type": "string"}}},
        }
    },
)
async def get_normal_csv(
    request: Request,
) -> Response:
    """The same result as CSV, for spreadsheets (a download)."""
    return Response(
        payload_csv(query_payload(request)),
        media_type="text/csv",
        headers={"content-disposition": 'attachment; filename="triangle-normal.csv"'},
    )


@router.post(
    "/normals",
    summary="Normals of many triangles",
    response_model=BatchResult,
    openapi_extra=request_body_spec(BatchRequest),
)
async def post_normals(request: Request) -> Response:
    """Normals of up to 100,000 triangles, in input order."""
    raw = await raw_json_body(request)
    if len(raw) <= batch.INLINE_BYTES:
        return FastJSONResponse(await run_in_threadpool(batch.payload, raw))
    jobs: Jobs = request.app.state.jobs
    estimate = batch.estimate(raw)
    batch.refuse_beyond_budget(estimate, jobs.admission.budget)
    text = await jobs.run(request, estimate, batch.job, raw)
    return Response(text, media_type="application/json")


@router.get(
    "/chart",
    summary="Bar chart of a triangle's normal",
    response_model=Figure,
    openapi_extra=query_parameters_spec(),
)
async def get_chart(
    request: Request,
) -> FastJSONResponse:
    """The Plotly figure of the bar chart for the page's query parameters."""
    return FastJSONResponse(bar_figure(query_payload(request)))
