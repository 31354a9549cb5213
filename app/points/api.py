"""JSON API for point clouds: the report and the normals.

Every route takes the point-cloud file itself (the server keeps nothing between requests) and
hands the work to a worker process (:mod:`app.points.work`, admitted by :mod:`app.web.jobs`).
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Annotated, Any, Literal

from fastapi import APIRouter, Query, Request
from fastapi.responses import Response, StreamingResponse

from app.points.estimates import estimate
from app.web.errors import ERROR_RESPONSES, ApiError, clip
from app.web.jobs import Jobs
from app.web.jsonio import FastJSONResponse
from app.web.uploads import read_files
from mesh_normal.choices import OrientMode
from mesh_normal.files.formats import SUFFIXES as MESH_SUFFIXES
from mesh_normal.points.io.formats import POINT_SUFFIXES
from mesh_normal.points.report import PointReport

if TYPE_CHECKING:
    from app.points import work

# The jobs (app.points.work: the readers, the k-d tree, NumPy) are imported by the routes that
# run them, not here: see app.mesh.api.

#: Every file suffix the routes take: the point formats' and the mesh formats' (as vertices).
POINT_FILE_SUFFIXES: tuple[str, ...] = tuple(sorted({*POINT_SUFFIXES, *MESH_SUFFIXES}))
#: The largest k: the neighbour lists of a chunk of queries grow with it.
K_LIMIT = 1000

#: Four points of a plane as XYZ text: the example upload in the API documentation.
EXAMPLE_FILE = "0 0 0\n1 0 0\n0 1 0\n1 1 0\n"

#: The OpenAPI ``requestBody`` of every route that takes a point-cloud file.
POINTS_BODY: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "content": {
            "multipart/form-data": {
                "schema": {
                    "type": "object",
                    "properties": {
                        "file": {
                            "type": "string",
                            "format": "binary",
                            "description": "The point-cloud file: "
                            + ", ".join(POINT_FILE_SUFFIXES)
                            + " (a mesh file is read as its vertices).",
                            "example": EXAMPLE_FILE,
                        }
                    },
                    "required": ["file"],
                }
            },
            "application/octet-stream": {
                "schema": {
                    "type": "string",
                    "format": "binary",
                    "description": "The file's bytes as they are (name it with ?filename=).",
                    "example": EXAMPLE_FILE,
                }
            },
        },
    }
}

router = APIRouter(
    prefix="/api/points",
    tags=["point clouds"],
    default_response_class=FastJSONResponse,
    responses={
        **ERROR_RESPONSES,
        415: {
            "description": "The file's format is unknown or not supported.",
            "content": ERROR_RESPONSES[415]["content"],
        },
    },
)

KQuery = Annotated[
    int | None,
    Query(
        ge=3,
        le=K_LIMIT,
        description="Neighbours in each fit, the point itself included; none given (with no "
        "radius): each point's own scale, from 12 to 96, chosen from the noise and curvature.",
    ),
]
RadiusQuery = Annotated[
    float | None,
    Query(
        gt=0,
        allow_inf_nan=False,
        description="Only neighbours within this distance (at most k of them), in file units.",
    ),
]
OrientQuery = Annotated[
    OrientMode,
    Query(
        description="mst (closed shapes out, terrain up), riemannian (thin walls), viewpoint "
        "(facing the viewpoint, or a PCD file's VIEWPOINT), direction, file (agreeing with "
        "the file's normals) or none."
    ),
]
VectorQuery = Annotated[str | None, Query(description="Three numbers x,y,z apart by commas.")]

#: The normals' download formats and their media types.
NormalsFormat = Literal["json", "csv", "npy", "ply", "xyz"]
MEDIA_TYPES: dict[str, str] = {
    "json": "application/json",
    "csv": "text/csv",
    "npy": "application/octet-stream",
    "ply": "application/octet-stream",
    "xyz": "text/plain",
}

_NUMBER = r"\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*"
_VECTOR = re.compile(rf"{_NUMBER},{_NUMBER},{_NUMBER}")


def parse_vector(text: str | None, name: str) -> tuple[float, float, float] | None:
    """``"x,y,z"`` as three finite numbers, or a 422 naming ``name``."""
    if text is None:
        return None
    values = tuple(float(part) for part in text.split(",")) if _VECTOR.fullmatch(text) else ()
    if len(values) != 3 or not all(math.isfinite(value) for value in values):
        raise ApiError(
            422, f"{name} must be three finite numbers x,y,z, e.g. 0,0,1, not {clip(text)!r}.", name
        )
    return values[0], values[1], values[2]


def options(
    k: int | None,
    radius: float | None,
    orient: OrientMode,
    viewpoint: str | None,
    direction: str | None,
) -> work.Options:
    """The query's options, checked together: each reference only with its mode."""
    sensor, along = parse_vector(viewpoint, "viewpoint"), parse_vector(direction, "direction")
    if sensor is not None and orient != "viewpoint":
        raise ApiError(422, "viewpoint is only used with orient=viewpoint.", "viewpoint")
    if along is not None and orient != "direction":
        raise ApiError(422, "direction is only used with orient=direction.", "direction")
    if orient == "direction" and (along is None or not any(along)):
        given = "must not be zero" if along is not None else "is needed with orient=direction"
        raise ApiError(422, f"direction {given}, e.g. direction=0,0,1.", "direction")
    from app.points import work

    return work.Options(k, radius, orient, sensor, along)


async def read_point_file(request: Request) -> tuple[bytes, str | None]:
    """The one file of the request, with its name; a name of another kind is a 415."""
    data, filename, _ = await read_point_upload(request)
    return data, filename


async def read_point_upload(
    request: Request, text_fields: tuple[str, ...] = ()
) -> tuple[bytes, str | None, dict[str, str]]:
    """The one file of the request, its name and the ``text_fields`` sent with it (the page's
    form sends its options as fields); a file name of another kind is a 415."""
    received = await read_files(request, "point cloud", text_fields)
    if len(received.parts) > 1:
        raise ApiError(422, "file is given more than once: send one point cloud.", "file")
    filename, data = received.parts[0]
    suffix = "." + filename.rsplit(".", 1)[-1].lower() if filename and "." in filename else ""
    if suffix and suffix not in POINT_FILE_SUFFIXES:
        raise ApiError(
            415,
            f"Files named {clip(suffix)} are not read: send one of "
            f"{', '.join(POINT_FILE_SUFFIXES)}.",
            "file",
        )
    return data, filename, received.fields


def download_name(filename: str | None, suffix: str) -> dict[str, str]:
    """The attachment header: the upload's stem (letters, digits, - and _) and ``suffix``."""
    base = (filename or "points").rsplit("/", 1)[-1].rsplit("\\", 1)[-1].rsplit(".", 1)[0]
    stem = re.sub(r"[^A-Za-z0-9_-]+", "-", base).strip("-")[:60] or "points"
    return {"content-disposition": f'attachment; filename="{stem}-{suffix}"'}


@router.post(
    "", summary="Report on a point cloud", openapi_extra=POINTS_BODY, response_model=PointReport
)
async def post_points(
    request: Request,
    k: KQuery = None,
    radius: RadiusQuery = None,
    orient: OrientQuery = "mst",
    viewpoint: VectorQuery = None,
    direction: VectorQuery = None,
) -> FastJSONResponse:
    """Report on a point cloud: spacing, normals by status, orientation and a diagnosis."""
    from app.points import work

    checked = options(k, radius, orient, viewpoint, direction)
    data, filename = await read_point_file(request)
    jobs: Jobs = request.app.state.jobs
    result = await jobs.run(request, estimate(data, filename), work.report, data, filename, checked)
    return FastJSONResponse(result)


@router.post(
    "/normals",
    summary="Normals of a point cloud",
    openapi_extra=POINTS_BODY,
    response_class=Response,
    responses={
        200: {
            "description": "The normals in file order: JSON, CSV, NumPy .npy (float64), or "
            "the points with their normals as binary PLY or XYZ text. Points without a normal "
            "have zeros; X-Points-Without-Normal counts them.",
            "content": {
                "application/json": {},
                "text/csv": {},
                "text/plain": {},
                "application/octet-stream": {},
            },
        }
    },
)
async def post_points_normals(
    request: Request,
    k: KQuery = None,
    radius: RadiusQuery = None,
    orient: OrientQuery = "mst",
    viewpoint: VectorQuery = None,
    direction: VectorQuery = None,
    file_format: Annotated[NormalsFormat, Query(alias="format")] = "json",
) -> Response:
    """The normals of a point cloud, in the file's order, or the points with their normals."""
    from app.points import work

    checked = options(k, radius, orient, viewpoint, direction)
    data, filename = await read_point_file(request)
    jobs: Jobs = request.app.state.jobs
    body, normals, missing = await jobs.run(
        request, estimate(data, filename), work.normals, data, filename, checked, file_format
    )
    headers = download_name(filename, f"normals.{file_format}")
    headers["x-points-without-normal"] = str(int(missing.sum()))
    media_type = MEDIA_TYPES[file_format]
    if body is not None:
        return Response(body, media_type=media_type, headers=headers)
    # Written in blocks as the client reads: the text of millions of normals is never whole.
    from app.points.downloads import normals_blocks

    blocks = normals_blocks(normals, missing, orient, file_format)
    return StreamingResponse(blocks, media_type=media_type, headers=headers)
