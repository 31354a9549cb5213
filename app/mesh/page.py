"""The mesh page: upload a file, read its diagnosis, see it in 3D, download normals and a fix.

``GET /mesh`` shows the form; ``POST /mesh`` (multipart field ``file``, once or once per file
of one mesh) answers with the whole page and its report, so it works without JavaScript.
``POST /mesh?part=report`` answers with the report alone, which the page's script swaps in.
The server keeps nothing: the page's downloads send the files again to the JSON API.
"""

from __future__ import annotations

import json
import posixpath
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
from app.web.links import public_url
from app.web.middleware import size_text
from app.web.templating import templates
from mesh_normal.analysis import analyse_mesh, build_report
from mesh_normal.exports import FORMATS, KINDS
from mesh_normal.files import WRITABLE, LoadedMesh
from mesh_normal.files.formats import ACCEPTED_SUFFIXES, COMPANION_SUFFIXES
from mesh_normal.files.formats import FORMATS as MESH_FORMATS
from mesh_normal.files.write import unkept
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
        # The file chooser offers the files that come with a mesh file too (a .gltf's .bin).
        "accept": ",".join((*ACCEPTED_SUFFIXES, *COMPANION_SUFFIXES)),
        "limit": limit,
        "limit_text": size_text(limit),
        "weld_limit": WELD_LIMIT,
        "report": None,
        "error": None,
    }


def _report_context(upload: Upload, base_url: str) -> dict[str, Any]:
    """Analyse the upload (in a worker thread): the report, its figures and the downloads."""
    mesh = load(upload)
    analysis = analyse_mesh(mesh, upload.filename, upload.size, weld=upload.weld)
    report = build_report(analysis)
    weld = "" if upload.weld is None else f" -F weld={upload.weld!r}"
    return {
        "files": files_read(upload, mesh.files),
        "fix_dropped": fix_dropped(mesh),
        "report": report,
        # The JSON twin is the API's own JSON (non-finite floats already null), parsed back
        # so that the template's json_script escapes it for a <script> block.
        "report_json": json.loads(report.model_dump_json()),
        "figures": mesh_figures(analysis),
        "classes": CLASSES,
        "stem": stem(upload.filename),
        "curl": "curl "
        + "".join(f"-F {shlex.quote('file=@' + sent)} " for sent in upload.names)
        + weld.lstrip()
        + (" " if weld else "")
        + f"{base_url}api/mesh",
        "sent": upload.names,
        "kinds": KINDS,
        "weightings": get_args(Weighting),
        "formats": FORMATS,
        "fix_formats": FIX_FORMATS,
        "fixed_by_orient": FIXED_BY_ORIENT,
    }


def fix_dropped(mesh: LoadedMesh) -> dict[str, str]:
    """For each format of the fixed mesh, the sentence saying what of this mesh it leaves out,
    in the words of the fix's ``X-Dropped`` header; empty when it keeps everything."""
    objects = len(mesh.group_names or ())
    dropped = {
        name: unkept(name, mesh.vertex_colors, mesh.face_colors, objects=objects)
        for name in FIX_FORMATS
    }
    keeping = [MESH_FORMATS[name].title for name, left_out in dropped.items() if not left_out]
    keeps = " and ".join(keeping) + (" keeps" if len(keeping) == 1 else " keep")
    return {
        name: f"{MESH_FORMATS[name].title} leaves out {'; '.join(left_out)}"
        + (f"; {keeps} everything." if keeping else ".")
        if left_out
        else ""
        for name, left_out in dropped.items()
    }


def files_read(upload: Upload, read: tuple[str, ...]) -> list[tuple[str, bool]]:
    """Each file sent with whether it was read; for a .zip, the members read. Empty for one
    file read alone."""
    if not upload.parts:
        return [(name, True) for name in read]
    return [(name, posixpath.normpath(name.replace("\\", "/")) in read) for name in upload.names]


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
        context.update(await run_in_threadpool(_report_context, upload, public_url("/")))
    except ApiError as error:
        context["error"] = error
        name = "_mesh_error.html" if fragment else "mesh.html"
        return templates.TemplateResponse(request, name, context, status_code=error.status_code)
    name = "_mesh_report.html" if fragment else "mesh.html"
    return templates.TemplateResponse(request, name, context)
