"""The baseline: bare FastAPI endpoints that echo the JSON body they are sent."""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse

app = FastAPI()


@app.post("/echo")
async def echo(body: dict[str, Any]) -> dict[str, Any]:
    """The FastAPI idiom: the body parsed into a dict and returned."""
    return body


@app.post("/echo-raw")
async def echo_raw(request: Request) -> JSONResponse:
    """The least FastAPI can do: parse the JSON and send it back."""
    return JSONResponse(await request.json())
