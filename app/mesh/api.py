"""JSON API for whole meshes: the report, the normals and the fixed file.

Every route takes the mesh file itself (the server keeps nothing between requests) and does
its work in a worker thread, so other requests keep being served meanwhile.
"""

from __future__ import annotations

import re
from typing import Annotated, Literal

import numpy as np
from fastapi import APIRouter, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import Response

from app.mesh.uploads import (
    UPLOAD_BODY,
    UPLOAD_WELD_BODY,
    WELD_HELP,
    Upload,
    read_upload,
    upload_weld,
)
from app.web.errors import ERROR_RESPONSES, ApiError
from app.web.jsonio import FastJSONResponse
from mesh_normal.analysis import analyse_mesh, build_report, flips_by_component
from mesh_normal.exports import NormalsKind, export_normals
from mesh_normal.files import LoadedMesh, MeshFileError, read_mesh, read_mesh_files, write_mesh
from mesh_normal.files.formats import FORMATS, WRITABLE
from mesh_normal.files.write import unkept
from mesh_normal.orientation import orient
from mesh_normal.report import MeshReport
from mesh_normal.tolerances import WELD_LIMIT
from mesh_normal.vertices import Weighting

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

#: The optional weld tolerance as a query parameter (for a raw body; multipart sends the field).
WeldQuery = Annotated[
    float | None,
    Query(ge=0, le=WELD_LIMIT, allow_inf_nan=False, description=WELD_HELP),
]

#: The library's WRITABLE, spelled out because FastAPI and mypy need a Literal (a test pins it).
FixFormat = Literal["ply", "stl", "obj"]
#: The download's media type: the normals' formats, then the mesh formats from the library's table.
MEDIA_TYPES = {
    "json": "application/json",
    "csv": "text/csv",
    "npy": "application/octet-stream",
    **{name: FORMATS[name].media_type for name in WRITABLE},
}


def load(upload: Upload) -> LoadedMesh:
    """Read the uploaded file (or files); a broken or unknown file becomes a 4xx naming the
    problem."""
    try:
        if upload.parts:
            return read_mesh_files(upload.parts)
        return read_mesh(upload.data, upload.filename)
    except MeshFileError as error:
        raise ApiError(error.status_code, str(error), "file") from None


def stem(filename: str | None) -> str:
    """A safe download name from the upload's name: letters, digits, ``-`` and ``_``."""
    base = (filename or "mesh").rsplit("/", 1)[-1].rsplit("\\", 1)[-1].rsplit(".", 1)[0]
    return re.sub(r"[^A-Za-z0-9_-]+", "-", base).strip("-")[:60] or "mesh"


def attachment(name: str) -> dict[str, str]:
    return {"content-disposition": f'attachment; filename="{name}"'}


@router.post("", openapi_extra=UPLOAD_WELD_BODY, response_model=MeshReport)
async def post_mesh(request: Request, weld: WeldQuery = None) -> FastJSONResponse:
    """Report on a mesh file: counts, area, volume, winding, orientation and problems."""
    upload = await read_upload(request)
    tolerance = upload_weld(upload, weld)
    # The model is rendered once, by pydantic-core, with non-finite floats as null; returning
    # a response skips FastAPI's second validation and encoding of the same model.
    return FastJSONResponse(await run_in_threadpool(_report, upload, tolerance))


def _report(upload: Upload, weld: float | None) -> MeshReport:
    return build_report(analyse_mesh(load(upload), upload.filename, upload.size, weld=weld))


@router.post(
    "/normals",
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
    upload = await read_upload(request)

    def work() -> bytes:
        mesh = load(upload)
        return export_normals(mesh, kind, weighting, crease_angle, file_format)

    body = await run_in_threadpool(work)
    name = f"{stem(upload.filename)}-{kind}-normals.{file_format}"
    return Response(body, media_type=MEDIA_TYPES[file_format], headers=attachment(name))


@router.post(
    "/fix",
    openapi_extra=UPLOAD_WELD_BODY,
    response_class=Response,
    responses={
        200: {
            "description": "The mesh with consistent, outward winding; vertices untouched. "
            "X-Faces-Flipped (a count), X-Component-Faces-Flipped (component:faces "
            "for the first 100 components changed) and X-Orientation-Before say "
            "what changed; X-Weld (the tolerance, present only when a weld was asked for) "
            "says how the parts were judged, as in the report. Vertex colours are kept "
            "where the format holds them (PLY in their own type, OBJ as v x y z r g b), face "
            "colours in PLY; X-Dropped, present only when something was left out, names what "
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
    upload = await read_upload(request)
    tolerance = upload_weld(upload, weld)

    def work() -> tuple[bytes, str, dict[str, str]]:
        mesh = load(upload)
        chosen = file_format or (mesh.format if mesh.format in WRITABLE else WRITABLE[0])
        # The same weld as the report's, so that the file is the fix the report described.
        fixed = orient(mesh.checked(), weld=tolerance)
        headers = {
            "x-faces-flipped": str(int(np.count_nonzero(fixed.flipped))),
            "x-component-faces-flipped": flips_by_component(fixed),
            "x-orientation-before": fixed.orientation,
        }
        if tolerance is not None:
            headers["x-weld"] = repr(tolerance)
        objects = len(mesh.group_names or ())
        dropped = unkept(chosen, mesh.vertex_colors, mesh.face_colors, objects=objects)
        if dropped:  # do no harm: never leave data out without saying so
            headers["x-dropped"] = "; ".join(dropped)
        try:
            data = write_mesh(
                mesh.vertices,
                fixed.faces,
                chosen,
                vertex_colors=mesh.vertex_colors,
                face_colors=mesh.face_colors,
            )
            return data, chosen, headers
        except MeshFileError as error:  # e.g. coordinates beyond what STL's floats hold
            raise ApiError(error.status_code, str(error), "format") from None

    body, chosen, headers = await run_in_threadpool(work)
    headers.update(attachment(f"{stem(upload.filename)}-fixed.{chosen}"))
    return Response(body, media_type=MEDIA_TYPES[chosen], headers=headers)
