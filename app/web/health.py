"""``GET /healthz``: whether this worker serves, for a load balancer or a container's
HEALTHCHECK: a few bytes of JSON, no template, no file, no heavy job.

It answers 200 while the event loop serves (pages and the calculator work even while the heavy
mesh jobs are all busy: those answer 503 with Retry-After on their own, which is load, not ill
health), with this worker's heavy jobs for whoever watches: how many run, how many wait, and the
bound on them. It is left out of the OpenAPI document: it is for the operator, not the API's
users.
"""

from __future__ import annotations

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse

import mesh_normal

router = APIRouter()


@router.get("/healthz", include_in_schema=False)
def healthz(request: Request) -> JSONResponse:
    admission = request.app.state.jobs.admission
    body = {
        "status": "ok",
        "version": mesh_normal.__version__,
        "jobs": {
            "running": admission.running,
            "waiting": admission.waiting,
            "slots": admission.slots,
        },
    }
    return JSONResponse(body, headers={"cache-control": "no-store"})
