"""JSON API for whole meshes: the report, the normals and the fixed file.

Every route takes the mesh file itself (the server keeps nothing between requests) and hands
the work to a worker process (:mod:`app.mesh.work`, admitted by :mod:`app.web.jobs`), so other
requests keep being served meanwhile.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Annotated, Any, Literal, TypeVar

from fastapi import APIRouter, Path, Query, Request
from fastapi.responses import Response, StreamingResponse

from app.mesh.estimates import Task, estimate
from app.mesh.samples import SAMPLES, computed, sample
from app.mesh.uploads import (
    UPLOAD_BODY,
    UPLOAD_WELD_BODY,
    WELD_HELP,
    Upload,
    read_upload,
    upload_weld,
)
from app.web.errors import ERROR_RESPONSES
from app.web.jobs import Jobs
from app.web.jsonio import FastJSONResponse
from mesh_normal.choices import NormalsChoice, NormalsKind, Weighting, Winding
from mesh_normal.files.formats import FORMATS, WRITABLE
from mesh_normal.mesh.report.models import MeshReport
from mesh_normal.tolerances import WELD_LIMIT

# The jobs (app.mesh.work: the readers, the kernels, NumPy) are imported by the routes that run
# them, not here: the server answers its first page without loading them, and loads them in the
# background once it is up (app.main's lifespan), before the first upload comes.

Value = TypeVar("Value")

router = APIRouter(
    prefix="/api/mesh",
    tags=["meshes"],
    default_response_class=FastJSONResponse,
    responses={
        **ERROR_RESPONSES,
        415: {
            "description": "The file's format is unknown or not supported.",
            "content": ERROR_RESPONSES[415]["content"],
        },
    },
)

_NOT_FOUND = {"content": ERROR_RESPONSES[422]["content"]}

#: The optional weld tolerance as a query parameter (for a raw body; multipart sends the field).
WeldQuery = Annotated[
    float | None,
    Query(ge=0, le=WELD_LIMIT, allow_inf_nan=False, description=WELD_HELP),
]

#: The library's WRITABLE, spelled out because FastAPI and mypy need a Literal (a test pins it).
FixFormat = Literal["ply", "stl", "obj", "off", "glb"]
#: The download's media type: the normals' formats, then the mesh formats from the library's table.
MEDIA_TYPES = {
    "json": "application/json",
    "csv": "text/csv",
    "npy": "application/octet-stream",
    **{name: FORMATS[name].media_type for name in WRITABLE},
}


async def run_job(
    request: Request, task: Task, upload: Upload, function: Callable[..., Value], *args: Any
) -> Value:
    """``function(upload, *args)`` as a heavy job, charged the upload's estimate for ``task``."""
    jobs: Jobs = request.app.state.jobs
    return await jobs.run(request, estimate(upload, task), function, upload, *args)


def stem(filename: str | None) -> str:
    """A safe download name from the upload's name: letters, digits, ``-`` and ``_``."""
    base = (filename or "mesh").rsplit("/", 1)[-1].rsplit("\\", 1)[-1].rsplit(".", 1)[0]
    return re.sub(r"[^A-Za-z0-9_-]+", "-", base).strip("-")[:60] or "mesh"


def attachment(name: str) -> dict[str, str]:
    return {"content-disposition": f'attachment; filename="{name}"'}


@router.post(
    "",
    summary="Report on a mesh file",
    openapi_extra=UPLOAD_WELD_BODY,
    response_model=MeshReport,
)
async def post_mesh(request: Request, weld: WeldQuery = None) -> FastJSONResponse:
    """Report on a mesh file: counts, area, volume, winding, orientation and problems."""
    from app.mesh import work

    upload = await read_upload(request)
    tolerance = upload_weld(upload, weld)
    # The model is rendered once, by pydantic-core, with non-finite floats as null; returning
    # a response skips FastAPI's second validation and encoding of the same model.
    return FastJSONResponse(await run_job(request, "report", upload, work.report, tolerance))


#: The sample's name in the address: the schema lists the names, any other is a 404.
SampleName = Annotated[
    str,
    Path(
        description="one of the page's sample meshes",
        json_schema_extra={"enum": list(SAMPLES)},
    ),
]


@router.get(
    "/sample/{name}",
    summary="Report on a sample mesh",
    response_model=MeshReport,
    responses={404: {"description": "There is no sample of that name.", **_NOT_FOUND}},
)
async def get_mesh_sample(request: Request, name: SampleName) -> FastJSONResponse:
    """The report on one of the mesh page's samples: what POST /api/mesh answers for its file
    (computed once, then served from memory)."""
    from app.mesh import work

    upload = sample(name).upload()
    report = await computed(request).get(
        ("report", name), lambda: run_job(request, "report", upload, work.report, None)
    )
    return FastJSONResponse(report)


@router.post(
    "/normals",
    summary="Normals of a mesh file",
    openapi_extra=UPLOAD_BODY,
    response_class=Response,
    responses={
        200: {
            "description": "The normals in file order: JSON, CSV or NumPy .npy (float64).",
            "content": {"application/json": {}, "text/csv": {}, "application/octet-stream": {}},
        }
    },
)
async def post_mesh_normals(
    request: Request,
    kind: Annotated[NormalsKind, Query(description="face, vertex or corner normals")] = "vertex",
    weighting: Annotated[
        Weighting, Query(description="how faces count at a vertex (vertex and corner kinds)")
    ] = "angle",
    crease_angle: Annotated[
        float,
        Query(
            ge=0,
            le=180,
            description="corner kind: edges with a larger dihedral angle stay sharp, in degrees",
        ),
    ] = 30.0,
    file_format: Annotated[Literal["json", "csv", "npy"], Query(alias="format")] = "json",
) -> Response:
    """The face, vertex or corner normals of a mesh file, in the file's order."""
    from app.mesh import work

    upload = await read_upload(request)
    normals, missing = await run_job(
        request, kind, upload, work.normals, kind, weighting, crease_angle
    )
    name = f"{stem(upload.filename)}-{kind}-normals.{file_format}"
    # Written in blocks as the client reads: the text of millions of normals is never whole.
    from mesh_normal.files.normals import normals_blocks

    blocks = normals_blocks(normals, missing, kind, weighting, crease_angle, file_format)
    return StreamingResponse(blocks, media_type=MEDIA_TYPES[file_format], headers=attachment(name))


@router.post(
    "/fix",
    summary="Mesh file with its winding fixed",
    openapi_extra=UPLOAD_WELD_BODY,
    response_class=Response,
    responses={
        200: {
            "description": "The mesh with consistent, outward winding; vertices untouched. "
            "X-Faces-Flipped (a count), X-Component-Faces-Flipped (component:faces "
            "for the first 100 components changed) and X-Orientation-Before say "
            "what changed; X-Weld (the tolerance, present only when a weld was asked for) "
            "says how the parts were judged, as in the report. Vertex colours are kept "
            "where the format holds them (PLY in their own type, OBJ as v x y z r g b, GLB "
            "COLOR_0, OFF), face colours in PLY and OFF, groups in OBJ, and the normals the "
            "file had, recomputed on the fixed faces (X-Normals names the kind, or none); "
            "X-Kept lists what was kept. X-Dropped, present only when something was left out, "
            "names what "
            'the chosen format could not hold, e.g. "vertex colours (STL holds none)" or "the '
            'division into 2 objects (the STL written is one mesh)" (several joined by "; ").',
            "content": {FORMATS[name].media_type: {} for name in WRITABLE},
        }
    },
)
async def post_mesh_fix(
    request: Request,
    file_format: Annotated[
        FixFormat | None,
        Query(
            alias="format",
            description=f"{', '.join(WRITABLE[:-1])} or {WRITABLE[-1]}; default: the "
            "upload's format where it is one of these, "
            f"else {WRITABLE[0]}",
        ),
    ] = None,
    weld: WeldQuery = None,
) -> Response:
    """The mesh file with consistent, outward winding (the vertices untouched)."""
    from app.mesh import work

    upload = await read_upload(request)
    tolerance = upload_weld(upload, weld)
    body, chosen, headers = await run_job(request, "fix", upload, work.fix, file_format, tolerance)
    headers.update(attachment(f"{stem(upload.filename)}-fixed.{chosen}"))
    return Response(body.data, media_type=MEDIA_TYPES[chosen], headers=headers)


@router.post(
    "/export",
    summary="Mesh file written again with its normals",
    openapi_extra=UPLOAD_WELD_BODY,
    response_class=Response,
    responses={
        200: {
            "description": "The mesh file written again, with its normals: OBJ vn, PLY "
            "nx ny nz (vertex or face), GLB NORMAL (vertices split for face and corner "
            "normals), OFF vertex normals, STL facet normals. X-Normals names the kind "
            "written (or none), X-Faces-Flipped counts the faces reversed (and, for "
            "winding=fix, X-Component-Faces-Flipped and X-Orientation-Before as in the fix), "
            "X-Kept lists what besides vertices and faces the file holds, X-Dropped (present "
            'only when something was left out) what the format could not hold, e.g. "corner '
            'normals (STL holds face normals only)" (several joined by "; ").',
            "content": {FORMATS[name].media_type: {} for name in WRITABLE},
        }
    },
)
async def post_mesh_export(
    request: Request,
    file_format: Annotated[
        FixFormat | None,
        Query(
            alias="format",
            description=f"{', '.join(WRITABLE)}; default: the upload's format where it is "
            f"one of these, else {WRITABLE[0]}",
        ),
    ] = None,
    normals: Annotated[
        NormalsChoice,
        Query(
            description="none, face, vertex or corner normals, computed on the faces written; "
            "auto (the default): the kind the file stored (vertex normals for per-vertex ones, "
            "corner for per-corner), none when it stored none (or is STL)"
        ),
    ] = "auto",
    weighting: Annotated[
        Weighting, Query(description="how faces count at a vertex (vertex and corner normals)")
    ] = "angle",
    crease_angle: Annotated[
        float,
        Query(
            ge=0,
            le=180,
            description="corner normals: edges with a larger dihedral angle stay sharp, degrees",
        ),
    ] = 30.0,
    winding: Annotated[
        Winding,
        Query(description="keep the faces, fix them (consistent and outward) or flip every one"),
    ] = "keep",
    weld: WeldQuery = None,
) -> Response:
    """The mesh file in any writable format, with face, vertex or corner normals."""
    from app.mesh import work

    upload = await read_upload(request)
    tolerance = upload_weld(upload, weld)
    body, chosen, headers = await run_job(
        request,
        "fix",
        upload,
        work.export,
        file_format,
        normals,
        weighting,
        crease_angle,
        winding,
        tolerance,
    )
    headers.update(attachment(f"{stem(upload.filename)}-export.{chosen}"))
    return Response(body.data, media_type=MEDIA_TYPES[chosen], headers=headers)
