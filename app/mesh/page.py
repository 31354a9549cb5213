"""The mesh page: upload a file, read its diagnosis, see it in 3D, download normals and a fix.

``GET /mesh`` shows the form; ``POST /mesh`` (multipart field ``file``) answers with the whole
page and its report, so it works without JavaScript. ``POST /mesh?part=report`` answers with
the report alone, which the page's script swaps in. The server keeps nothing: the page's
downloads send the file again to the JSON API.
"""

from __future__ import annotations

import json
import shlex
from typing import Any, get_args

from fastapi import APIRouter, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import HTMLResponse

from app.mesh.api import load, stem
from app.mesh.classes import CLASSES
from app.mesh.figures import mesh_figures
from app.mesh.uploads import Upload, read_upload
from app.web.errors import ApiError
from app.web.middleware import size_text
from app.web.templating import templates
from mesh_normal.analysis import analyse_mesh, build_report
from mesh_normal.exports import FORMATS, KINDS
from mesh_normal.files import WRITABLE
from mesh_normal.files.formats import ACCEPTED_SUFFIXES
from mesh_normal.tolerances import WELD_LIMIT
from mesh_normal.vertices import Weighting

router = APIRouter(include_in_schema=False)

#: The formats the fixed mesh can be downloaded in: the library's writable ones.
FIX_FORMATS = WRITABLE
#: Problems that the fixed mesh (orient()) repairs: their card gets the download button.
FIXED_BY_ORIENT = frozenset({"winding", "inward", "mixed"})


def _form_context(request: Request) -> dict[str, Any]:
    """What the upload form needs: the accepted suffixes and the app's size limit."""
    limit: int = request.app.state.upload_limit
    return {
        "suffixes": [suffix.lstrip(".") for suffix in ACCEPTED_SUFFIXES],
        "limit": limit,
        "limit_text": size_text(limit),
        "weld_limit": WELD_LIMIT,
        "report": None,
        "error": None,
    }


def _report_context(upload: Upload, base_url: str) -> dict[str, Any]:
    """Analyse the upload (in a worker thread): the report, its figures and the downloads."""
    analysis = analyse_mesh(load(upload), upload.filename, len(upload.data), weld=upload.weld)
    report = build_report(analysis)
    name = upload.filename or "mesh"
    weld = "" if upload.weld is None else f" -F weld={upload.weld!r}"
    return {
        "report": report,
        # The JSON twin is the API's own JSON (non-finite floats already null), parsed back
        # so that the template's json_script escapes it for a <script> block.
        "report_json": json.loads(report.model_dump_json()),
        "figures": mesh_figures(analysis),
        "classes": CLASSES,
        "stem": stem(upload.filename),
        "curl": f"curl -F {shlex.quote('file=@' + name)}{weld} {base_url}api/mesh",
        "kinds": KINDS,
        "weightings": get_args(Weighting),
        "formats": FORMATS,
        "fix_formats": FIX_FORMATS,
        "fixed_by_orient": FIXED_BY_ORIENT,
    }


@router.get("/mesh", response_class=HTMLResponse)
def mesh_form(request: Request) -> HTMLResponse:
    return templates.TemplateResponse(request, "mesh.html", _form_context(request))


@router.post("/mesh", response_class=HTMLResponse)
async def mesh_upload(request: Request) -> HTMLResponse:
    """The report on an uploaded mesh: the whole page, or with ``?part=report`` the report."""
    fragment = request.query_params.get("part") == "report"
    context = _form_context(request)
    try:
        upload = await read_upload(request)
        context.update(await run_in_threadpool(_report_context, upload, str(request.base_url)))
    except ApiError as error:
        context["error"] = error
        name = "_mesh_error.html" if fragment else "mesh.html"
        return templates.TemplateResponse(request, name, context, status_code=error.status_code)
    name = "_mesh_report.html" if fragment else "mesh.html"
    return templates.TemplateResponse(request, name, context)
