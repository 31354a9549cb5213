"""The heavy point-cloud work, everything after the upload is read: what a worker runs.

Each function takes the file's bytes, its name and the checked :class:`Options`, and returns
plain values (a model, bytes), so that it can run in a worker process (:mod:`app.web.jobs`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from app.points.figures import histogram_figure, view_figure
from app.web.errors import ApiError
from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.analysis import PointAnalysis, analyse_points
from mesh_normal.points.io.read import PointCloud, read_points
from mesh_normal.points.io.write import write_points
from mesh_normal.points.orient import OrientMode
from mesh_normal.points.report import PointReport
from mesh_normal.types import BoolArray, FloatArray


@dataclass(frozen=True, slots=True)
class Options:
    """The neighbourhood and orientation asked for, checked at the edge."""

    k: int | None
    radius: float | None
    orient: OrientMode
    viewpoint: tuple[float, float, float] | None
    direction: tuple[float, float, float] | None


def load(data: bytes, filename: str | None) -> PointCloud:
    """Read the uploaded file; a broken or unknown file becomes a 4xx naming the problem, one
    that expands past its budget (compressed points; ``read_points`` opens it) a 413."""
    try:
        return read_points(data, filename)
    except MeshFileError as error:
        raise ApiError(error.status_code, str(error), "file") from None


def analyse(data: bytes, filename: str | None, options: Options) -> PointAnalysis:
    cloud = load(data, filename)
    if options.orient == "viewpoint" and options.viewpoint is None and cloud.viewpoint is None:
        raise ApiError(
            422, "viewpoint is needed with orient=viewpoint: the file has none to use.", "viewpoint"
        )
    if options.orient == "file" and cloud.normals is None:
        raise ApiError(422, "orient=file needs normals stored in the file; it has none.", "orient")
    try:
        return analyse_points(
            cloud,
            k=options.k,
            radius=options.radius,
            orient=options.orient,
            viewpoint=options.viewpoint,
            direction=options.direction,
            name=filename,
            size=len(data),
        )
    except ValueError as error:  # checked at the edge; a sentence if one slips through
        raise ApiError(422, str(error).rstrip(".") + ".") from None


def report(data: bytes, filename: str | None, options: Options) -> PointReport:
    """The report of ``POST /api/points``."""
    return analyse(data, filename, options).report


def normals(
    data: bytes, filename: str | None, options: Options, file_format: str
) -> tuple[bytes | None, FloatArray, BoolArray]:
    """The file of points and normals for ``ply`` and ``xyz`` (else None), the normals in file
    order (zero rows where there is none) and the mask of those rows; the server writes the
    other formats from the arrays, in blocks."""
    result = analyse(data, filename, options)
    cloud, vectors, missing = result.cloud, result.normals.normals, ~result.normals.valid
    if file_format in ("ply", "xyz"):
        return write_points(cloud.points, vectors, file_format), vectors[:0], missing
    if cloud.file_points != len(cloud.points):
        # A row for each of the file's rows, as the command line writes them: those the reader
        # left out (a PCD's NaN points) are zero rows without a normal, so row i is point i.
        import numpy as np

        rows, gone = np.zeros((cloud.file_points, 3)), np.ones(cloud.file_points, dtype=bool)
        rows[cloud.kept], gone[cloud.kept] = vectors, missing
        vectors, missing = rows, gone
    return None, vectors, missing


def warm() -> None:
    """Run each point job once on a small cloud (a worker as it starts): scipy's k-d tree and
    spanning tree, the point kernels and the readers are loaded before the first upload."""
    import numpy as np

    angles = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
    ring = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    points = np.concatenate([ring * radius + [0, 0, radius] for radius in (1.0, 1.5, 2.0)])
    options = Options(k=12, radius=None, orient="mst", viewpoint=None, direction=None)
    for name, fmt in (("warm.ply", "ply"), ("warm.xyz", "xyz")):
        data = write_points(points, None, fmt)
        report(data, name, options)
        normals(data, name, options, fmt)
        page(data, name, options)  # the figures (plotly) too


def page(data: bytes, filename: str | None, options: Options) -> dict[str, Any]:
    """The point-cloud page's context for an upload: the report, its JSON twin and figures."""
    result = analyse(data, filename, options)
    return {
        "report": result.report,
        # The API's own JSON (non-finite floats already null), parsed back so that the
        # template's json_script escapes it for a <script> block.
        "report_json": json.loads(result.report.to_json()),
        "view": view_figure(result),
        "histogram": histogram_figure(result),
    }
