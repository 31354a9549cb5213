"""JSON API: one triangle, a batch, and the chart figure."""

from __future__ import annotations

import re
from typing import Any

from fastapi import APIRouter, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import Response

from app.calculator.calculation import calculation_payload, from_doubles, from_typed
from app.calculator.chart import bar_figure
from app.calculator.fast import fast_payload
from app.calculator.params import query_parameters_spec, read_triangle
from app.calculator.payloads import batch_payload, payload_csv
from app.calculator.schemas import BatchRequest, BatchResult, Figure, NormalRequest, NormalResult
from app.config import BATCH_LIMIT
from app.web.errors import ERROR_RESPONSES, ApiError
from app.web.jsonio import (
    FastJSONResponse,
    parse_body,
    raw_json_body,
    read_body,
    request_body_spec,
)
from app.web.routes import RequestRoute
from mesh_normal.triangle import triangle_normal

router = APIRouter(
    prefix="/api",
    tags=["normals"],
    responses=ERROR_RESPONSES,
    default_response_class=FastJSONResponse,
    route_class=RequestRoute,
)


def query_payload(request: Request) -> dict[str, Any]:
    """The result for the page's query parameters, or the first error as an ApiError."""
    parsed = read_triangle(request.query_params)
    if not parsed.valid:
        raise parsed.first_error()
    return calculation_payload(from_typed(parsed))


@router.post(
    "/normal",
    summary="Normal of one triangle",
    response_model=NormalResult,
    openapi_extra=request_body_spec(NormalRequest),
)
async def post_normal(request: Request) -> FastJSONResponse:
    """The normal of one triangle given as JSON."""
    body = await read_body(request, NormalRequest)
    payload = fast_payload(body.a, body.b, body.c, body.swap_winding)
    if payload is None:  # where the fast path cannot be sure of the same answer
        calc = from_doubles(body.a, body.b, body.c, swap_winding=body.swap_winding)
        payload = calculation_payload(calc)
    return FastJSONResponse(payload)


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
async def post_normals(request: Request) -> FastJSONResponse:
    """Normals of up to 100,000 triangles, in input order."""
    raw = await raw_json_body(request)
    # Parsing and computing a full batch takes a while: keep the event loop free meanwhile.
    content = await run_in_threadpool(_batch, raw)
    return FastJSONResponse(content)


def _batch(raw: bytes) -> dict[str, Any]:
    # Imported here, not at the top: NumPy is for batches only, and importing it would add
    # to every start-up of the server (the calculator page and /api/normal never need it).
    import numpy as np

    from mesh_normal.triangle_batch import triangle_normals

    refuse_oversized_batch(raw)
    body = parse_body(raw, BatchRequest)
    triangles = np.array(body.triangles, dtype=np.float64).reshape(-1, 3, 3)
    batch = triangle_normals(triangles, swap_winding=body.swap_winding)
    exact_rows = {
        int(row): triangle_normal(*triangles[row].tolist(), swap_winding=body.swap_winding)
        for row in np.flatnonzero(batch.out_of_range)
    }
    return batch_payload(batch, exact_rows)


#: A JSON string, escapes included (linear: each character matches one way).
_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"')


def refuse_oversized_batch(raw: bytes) -> None:
    """Refuse a batch of more than ``BATCH_LIMIT`` triangles before it is parsed.

    Parsing builds every number as an object (about 70 times the body's size for 1.9 million
    triangles); counting brackets reads the bytes once. A valid body holds exactly
    ``4 * n + 1`` of them for ``n`` triangles (keys are ``triangles`` and ``swap_winding``,
    with no bracket), so more than ``4 * BATCH_LIMIT + 1`` is over the limit or not a batch.
    """
    most = 4 * BATCH_LIMIT + 1
    brackets = raw.count(b"[")
    if brackets > most and b'"' in raw:  # brackets inside strings are no triangles
        brackets = _STRING.sub(b'""', raw).count(b"[")
    if brackets > most:
        raise ApiError(
            413,
            f"A batch holds at most {BATCH_LIMIT:,} triangles (about {(brackets - 1) // 4:,} "
            "were sent); split it into several requests.",
            "triangles",
        )


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
