"""The mesh page: upload a file, read its diagnosis, see it in 3D, download normals and a fix.

``GET /mesh`` shows the form; ``POST /mesh`` (multipart field ``file``, once or once per file
of one mesh) answers with the whole page and its report, so it works without JavaScript.
``POST /mesh?part=report`` answers with the report alone, which the page's script swaps in.
``GET /mesh/sample/{name}`` is the page for one of :mod:`app.mesh.samples`, as if uploaded;
``GET /mesh/sample/{name}/file`` is that sample's file. What the jobs make of a sample is
computed once and then served from memory (:class:`app.mesh.samples.Computed`).
The server keeps nothing: the page's downloads send the files again to the JSON API.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request
from fastapi.responses import HTMLResponse, Response

from app.mesh.api import MEDIA_TYPES, FixFormat, attachment, run_job, stem
from app.mesh.samples import SAMPLES, computed, sample
from app.mesh.uploads import read_upload
from app.web.errors import ApiError
from app.web.links import public_url
from app.web.middleware import size_text
from app.web.templating import templates
from mesh_normal.choices import NormalsChoice
from mesh_normal.files.formats import ACCEPTED_SUFFIXES, COMPANION_SUFFIXES
from mesh_normal.files.formats import WRITABLE as FIX_FORMATS  # app.mesh.work's
from mesh_normal.tolerances import WELD_LIMIT

__all__ = ["FIX_FORMATS", "router"]

# The jobs (app.mesh.work) are imported by the routes that run them: see app.mesh.api.

router = APIRouter(include_in_schema=False)


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
        "samples": SAMPLES.values(),
        "sample": None,
    }


@router.get("/mesh", response_class=HTMLResponse)
def mesh_form(request: Request) -> HTMLResponse:
    return templates.TemplateResponse(request, "mesh.html", _form_context(request))


@router.post("/mesh", response_class=HTMLResponse)
async def mesh_upload(request: Request) -> HTMLResponse:
    """The report on an uploaded mesh: the whole page, or with ``?part=report`` the report."""
    fragment = request.query_params.get("part") == "report"
    context = _form_context(request)
    from app.mesh import work

    try:
        upload = await read_upload(request)
        context.update(
            await run_job(
                request, "page", upload, work.page, stem(upload.filename), public_url("/")
            )
        )
    except ApiError as error:
        context["error"] = error
        name = "_mesh_error.html" if fragment else "mesh.html"
        return templates.TemplateResponse(
            request, name, context, status_code=error.status_code, headers=error.headers
        )
    name = "_mesh_report.html" if fragment else "mesh.html"
    return templates.TemplateResponse(request, name, context)


@router.get("/mesh/sample/{name}", response_class=HTMLResponse)
async def mesh_sample(request: Request, name: str) -> HTMLResponse:
    """The page with the report on a sample, as the upload of its file would show it."""
    from app.mesh import work

    chosen = sample(name)
    upload = chosen.upload()
    context = _form_context(request)
    base_url = public_url("/")
    context.update(
        await computed(request).get(
            ("page", chosen.name, base_url),
            lambda: run_job(request, "page", upload, work.page, stem(upload.filename), base_url),
        )
    )
    context["sample"] = chosen
    fragment = request.query_params.get("part") == "report"
    response = templates.TemplateResponse(
        request, "_mesh_report.html" if fragment else "mesh.html", context
    )
    response.headers["link"] = (
        f'</api/mesh/sample/{chosen.name}>; rel="alternate"; type="application/json"'
    )
    return response


@router.get("/mesh/sample/{name}/file")
async def mesh_sample_file(
    request: Request,
    name: str,
    file_format: Annotated[FixFormat | None, Query(alias="format")] = None,
    normals: NormalsChoice | None = None,
    flip: bool = False,
    fix: bool = False,
) -> Response:
    """The sample's file itself; with ``format``, ``normals``, ``flip`` or ``fix``, written
    again as ``POST /api/mesh/export`` would (a plain link or GET form, so it works without
    JavaScript: the server holds the sample's file, not the visitor)."""
    chosen = sample(name)
    if file_format is None and normals is None and not flip and not fix:
        return Response(
            chosen.data(),
            media_type=MEDIA_TYPES[chosen.format],
            headers=attachment(chosen.filename),
        )
    if flip and fix:
        raise ApiError(422, "flip and fix cannot both be asked for: choose one.", "flip")
    winding = "flip" if flip else "fix" if fix else "keep"
    from app.mesh import work

    args = (file_format, normals or "auto", "angle", 30.0, winding, None)
    body, written, said = await computed(request).get(
        ("export", chosen.name, *args),
        lambda: run_job(request, "fix", chosen.upload(), work.export, *args),
    )
    headers = {**said, **attachment(f"{chosen.name}-{'fixed' if fix else 'export'}.{written}")}
    return Response(body.data, media_type=MEDIA_TYPES[written], headers=headers)
