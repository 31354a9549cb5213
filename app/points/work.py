"""The heavy point-cloud work, everything after the upload is read: what a worker runs.

Each function takes the file's bytes, its name and the checked :class:`Options`, and returns
plain values (a model, bytes), so that it can run in a worker process (:mod:`app.web.jobs`).
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from app.web.errors import ApiError
from app.web.jsonio import json_bytes
from mesh_normal.exports import npy_bytes
from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.orient import OrientMode
from mesh_normal.points.read import PointCloud, read_points
from mesh_normal.points.report import PointAnalysis, PointReport, analyse_points
from mesh_normal.points.write import write_points
from mesh_normal.types import FloatArray

#: Rows of CSV text written at once.
CSV_BLOCK = 2**16


@dataclass(frozen=True, slots=True)
class Options:
    """The neighbourhood and orientation asked for, checked at the edge."""

    k: int
    radius: float | None
    orient: OrientMode
    viewpoint: tuple[float, float, float] | None
    direction: tuple[float, float, float] | None


def load(data: bytes, filename: str | None) -> PointCloud:
    """Read the uploaded file; a broken or unknown file becomes a 4xx naming the problem."""
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
) -> tuple[bytes, int]:
    """The normals in file order as ``file_format``, and how many points have none (their
    rows are zeros)."""
    result = analyse(data, filename, options)
    vectors, valid = result.normals.normals, result.normals.valid
    missing = np.flatnonzero(~valid)
    if file_format in ("ply", "xyz"):
        return write_points(result.cloud.points, vectors, file_format), len(missing)
    if file_format == "npy":
        return npy_bytes(vectors), len(missing)
    if file_format == "csv":
        return _csv(vectors), len(missing)
    head = {
        "orient": options.orient,
        "shape": list(vectors.shape),
        "missing": len(missing),
        "missing_indices": missing.tolist(),
    }
    return json_bytes({**head, "normals": vectors.tolist()}), len(missing)


def _csv(vectors: FloatArray) -> bytes:
    """``point,nx,ny,nz`` rows; 17 significant digits, so every value round-trips."""
    out = io.BytesIO()
    out.write(b"point,nx,ny,nz\n")
    for start in range(0, len(vectors), CSV_BLOCK):
        block = vectors[start : start + CSV_BLOCK]
        index = np.arange(start, start + len(block), dtype=np.float64)[:, None]
        np.savetxt(out, np.hstack([index, block]), fmt="%d,%.17g,%.17g,%.17g")
    return out.getvalue()
