"""The point-cloud page: upload a cloud, read its diagnosis, see it in 3D, download normals.

``GET /points`` shows the form; ``POST /points`` (multipart: the field ``file`` and the options
k, radius, orient, viewpoint and direction as text fields) answers with the whole page and its
report, so it works without JavaScript. ``POST /points?part=report`` answers with the report
alone, which the page's script swaps in. The server keeps nothing: the downloads send the file
again to ``POST /api/points/normals``.
"""

from __future__ import annotations

import math
import shlex
from typing import TYPE_CHECKING, Any, get_args
from urllib.parse import urlencode

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse

from app.points.api import K_LIMIT, POINT_FILE_SUFFIXES, options, read_point_upload
from app.points.estimates import estimate
from app.web.errors import ApiError, clip
from app.web.jobs import Jobs
from app.web.links import public_url
from app.web.middleware import size_text
from app.web.templating import templates
from mesh_normal.choices import OrientMode
from mesh_normal.points.report import ALL_CLEAR, PointReport

if TYPE_CHECKING:
    from app.points import work  # imported by the route that runs it (see app.mesh.api)

router = APIRouter(include_in_schema=False)

FIELDS = ("k", "radius", "orient", "viewpoint", "direction")
ORIENT_MODES: tuple[str, ...] = get_args(OrientMode)
#: The normals' download formats, in the order the page offers them.
DOWNLOAD_FORMATS = ("ply", "xyz", "csv", "npy", "json")
#: What each orient mode does, for the form's help.
ORIENT_HELP = {
    "mst": "spanning tree: closed shapes out, terrain up",
    "riemannian": "for thin walls",
    "viewpoint": "facing the viewpoint (or a PCD's VIEWPOINT)",
    "direction": "along a direction",
    "file": "agreeing with the file's normals",
    "none": "not oriented",
}


def verdict(report: PointReport) -> str:
    """How the diagnosis reads, as the page's message classes: "error" when more than a tenth
    of the points have no normal; "ok" only when nothing was found and no point lies near a
    sharp edge (its normal is one side's, worth a look); else "warn"."""
    missing = report.points - report.with_normal
    if missing * 10 > report.points:
        return "error"
    if report.diagnosis == [ALL_CLEAR] and not missing and not report.counts.sharp:
        return "ok"
    return "warn"


def _form_context(request: Request) -> dict[str, Any]:
    limit: int = request.app.state.upload_limit
    return {
        "suffixes": [suffix.lstrip(".") for suffix in POINT_FILE_SUFFIXES],
        "accept": ",".join(POINT_FILE_SUFFIXES),
        "limit": limit,
        "limit_text": size_text(limit),
        "k_limit": K_LIMIT,
        "orient_modes": ORIENT_MODES,
        "orient_help": ORIENT_HELP,
        "formats": DOWNLOAD_FORMATS,
        "values": {"k": "", "radius": "", "orient": "mst", "viewpoint": "", "direction": ""},
        "report": None,
        "error": None,
    }


def _number(text: str, name: str, whole: bool) -> float:
    try:
        value = int(text) if whole else float(text)
    except ValueError:
        value = math.nan
    if whole and not 3 <= value <= K_LIMIT:
        raise ApiError(
            422, f"k must be a whole number from 3 to {K_LIMIT}, not {clip(text)!r}.", name
        )
    if not whole and not (math.isfinite(value) and value > 0):
        raise ApiError(422, f"radius must be a positive number or empty, not {clip(text)!r}.", name)
    return value


def form_options(values: dict[str, str]) -> work.Options:
    """The form's fields as checked options; empty fields take the API's defaults, and the
    reference a mode does not use (the form has both inputs) is ignored."""
    k = int(_number(values["k"], "k", True)) if values["k"] else None
    radius = _number(values["radius"], "radius", False) if values["radius"] else None
    orient = values["orient"] or "mst"
    if orient not in ORIENT_MODES:
        raise ApiError(
            422, f"orient must be one of {', '.join(ORIENT_MODES)}, not {clip(orient)!r}.", "orient"
        )
    viewpoint = (values["viewpoint"] or None) if orient == "viewpoint" else None
    direction = (values["direction"] or None) if orient == "direction" else None
    return options(k, radius, orient, viewpoint, direction)  # type: ignore[arg-type]


def _query(checked: work.Options) -> str:
    """The options as the API's query string, defaults left out."""
    query: dict[str, str] = {}
    if checked.k is not None:
        query["k"] = str(checked.k)
    if checked.radius is not None:
        query["radius"] = repr(checked.radius)
    if checked.orient != "mst":
        query["orient"] = checked.orient
    for name in ("viewpoint", "direction"):
        vector = getattr(checked, name)
        if vector is not None:
            query[name] = ",".join(f"{x:g}" for x in vector)
    return urlencode(query)


@router.get("/points", response_class=HTMLResponse)
def points_form(request: Request) -> HTMLResponse:
    return templates.TemplateResponse(request, "points.html", _form_context(request))


@router.post("/points", response_class=HTMLResponse)
async def points_upload(request: Request) -> HTMLResponse:
    """The report on an uploaded cloud: the whole page, or with ``?part=report`` the report."""
    from app.points import work

    fragment = request.query_params.get("part") == "report"
    context = _form_context(request)
    try:
        data, filename, fields = await read_point_upload(request, FIELDS)
        values = {name: fields.get(name, "").strip() for name in FIELDS}
        context["values"] = {**context["values"], **{k: v for k, v in values.items() if v}}
        checked = form_options(values)
        jobs: Jobs = request.app.state.jobs
        context.update(
            await jobs.run(request, estimate(data, filename), work.page, data, filename, checked)
        )
        context["verdict"] = verdict(context["report"])
    except ApiError as error:
        context["error"] = error
        name = "_points_error.html" if fragment else "points.html"
        return templates.TemplateResponse(
            request, name, context, status_code=error.status_code, headers=error.headers
        )
    query = _query(checked)
    api = "/api/points" + (f"?{query}" if query else "")
    sent = shlex.quote("file=@" + (filename or "points.xyz"))
    context.update(
        api_url=api,
        api_query=query,
        curl=f"curl -F {sent} {shlex.quote(public_url(api))}",
    )
    name = "_points_report.html" if fragment else "points.html"
    headers = {"link": f'<{api}>; rel="alternate"; type="application/json"'}
    return templates.TemplateResponse(request, name, context, headers=headers)
