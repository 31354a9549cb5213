"""One file's job: read it through fsspec, report on it, write its outputs, return its row.

:func:`run_file` is what every engine runs (a local worker process, a Dask worker); it never
raises for the file's fault: a file that cannot be read or is not a mesh is an ``unreadable``
row with the reason in one sentence, one that exhausts memory a ``too_large`` row.
"""

from __future__ import annotations

import hashlib
import os
import time
import uuid
from typing import TYPE_CHECKING, Any

import fsspec

from mesh_normal.datasets.schema import empty_row, failed_row
from mesh_normal.datasets.tasks import BatchOptions, FileTask

if TYPE_CHECKING:
    from mesh_normal.mesh.report.analysis import MeshAnalysis
    from mesh_normal.points.analysis import PointAnalysis

#: Bytes of the digest in the ``hash`` column (BLAKE2b, 128 bits: 32 hex digits).
DIGEST_BYTES = 16


def file_hash(data: bytes) -> str:
    """The ``hash`` column: BLAKE2b of the bytes, 128 bits, in hex."""
    return hashlib.blake2b(data, digest_size=DIGEST_BYTES).hexdigest()


def run_file(task: FileTask, options: BatchOptions) -> dict[str, Any]:
    """The row of one file (see :data:`~mesh_normal.datasets.schema.SCHEMA`), its outputs
    written under ``options.out``."""
    start = time.perf_counter()
    kind = "points" if options.points else "mesh"
    try:
        row = _run(task, options, kind)
    except MemoryError:
        row = failed_row(
            task, "too_large", "It needs more memory than the limit allows.", kind=kind
        )
    row["wall_seconds"] = time.perf_counter() - start
    return row


def _run(task: FileTask, options: BatchOptions, kind: str) -> dict[str, Any]:
    limit = options.max_file_mb
    if limit is not None and task.size > limit * 1e6:
        return failed_row(task, "too_large", too_large_sentence(task.size, limit), kind=kind)
    try:
        with fsspec.open(task.url, "rb") as file:
            data = file.read()
    except (OSError, ValueError) as error:
        return failed_row(task, "unreadable", f"It cannot be read: {_words(error)}.", kind=kind)
    row = empty_row(task, kind)
    row.update(size=len(data), hash=file_hash(data))
    if limit is not None and len(data) > limit * 1e6:  # the listing was out of date
        row.update(status="too_large", error=too_large_sentence(len(data), limit))
        return row
    try:
        if options.points:
            _points(task, options, data, row)
        else:
            _mesh(task, options, data, row)
    except MemoryError:
        raise
    except Exception as error:
        row.update(status="unreadable", error=_sentence(error))
    return row


def too_large_sentence(size: int, limit_mb: float) -> str:
    """Why a file over ``--max-file-mb`` has no report."""
    return f"It is {size / 1e6:,.1f} MB, over the limit of {limit_mb:g} MB (--max-file-mb)."


def _words(error: BaseException) -> str:
    text = getattr(error, "strerror", None) or str(error) or type(error).__name__
    return str(text).rstrip(".")


def _sentence(error: BaseException) -> str:
    text = _words(error)
    return text[:1].upper() + text[1:] + "."


def _name(task: FileTask) -> str:
    return task.path.rsplit("/", 1)[-1]


def _mesh(task: FileTask, options: BatchOptions, data: bytes, row: dict[str, Any]) -> None:
    from mesh_normal.files import read_mesh
    from mesh_normal.mesh.report.analysis import analyse_mesh, build_report

    name = _name(task)
    if name.lower().endswith(".gltf") and os.path.exists(task.url):
        mesh = read_mesh(task.url, name)  # a local .gltf finds its .bin beside it
    else:
        mesh = read_mesh(data, name)
    analysis = analyse_mesh(mesh, name, len(data), weld=options.weld)
    report = build_report(analysis)
    stored = report.file_normals
    codes = [problem.code for problem in report.problems]
    serious = any(problem.severity != "info" for problem in report.problems)
    row.update(
        format=mesh.format,
        status="problems" if serious else "ok",
        vertices=report.vertices,
        faces=report.faces,
        components=report.components,
        area=report.area,
        volume=report.volume,
        watertight=report.watertight,
        winding_consistent=report.winding_consistent,
        orientation=report.orientation,
        degenerate_faces=report.degenerate_faces,
        boundary_edges=report.boundary_edges,
        nonmanifold_edges=report.nonmanifold_edges,
        unused_vertices=report.unused_vertices,
        faces_flipped=report.fix.faces_flipped,
        problems_found=codes,
    )
    if stored is not None:
        row.update(
            stored_normals=stored.kind,
            stored_compared=stored.compared,
            stored_agreeing=stored.agreeing,
            stored_opposite=stored.opposite,
            stored_median_degrees=stored.median_angle_degrees,
        )
    outputs = row["outputs"]
    if options.normals is not None:
        outputs.append(
            write_output(options.out, output_name(task, options), _normals(analysis, options))
        )
    if options.fix and report.fix.faces_flipped:
        from mesh_normal.files.rewrite import default_format, export_mesh

        chosen = default_format(mesh)
        fixed = export_mesh(mesh, chosen, winding="fix", weld=options.weld)
        outputs.append(write_output(options.out, fixed_name(task, chosen), fixed.data))


def _normals(analysis: MeshAnalysis, options: BatchOptions) -> bytes:
    from mesh_normal.files.normals import compute_normals, normals_file, normals_ply

    kind = options.normals or "face"
    mesh = analysis.mesh
    if kind == "face":  # the analysis has them
        normals, missing = analysis.faces.normals, analysis.geometry.degenerate
    else:
        normals, missing = compute_normals(mesh, kind, "angle", options.crease_angle)
    if options.normals_format == "ply":
        return normals_ply(mesh, normals, kind)
    return normals_file(normals, missing, kind, "angle", options.crease_angle, "npy")


def _points(task: FileTask, options: BatchOptions, data: bytes, row: dict[str, Any]) -> None:
    from mesh_normal.points.analysis import analyse_points
    from mesh_normal.points.io.read import read_points

    name = _name(task)
    cloud = read_points(data, name)
    found = analyse_points(cloud, k=options.k, name=name, size=len(data))
    report = found.report
    codes = point_codes(found)
    row.update(
        format=cloud.format,
        status="problems" if codes else "ok",
        vertices=report.points,
        points=report.points,
        points_with_normal=report.with_normal,
        points_unoriented=report.orientation.unoriented,
        spacing_median=None if report.spacing is None else report.spacing.median,
        problems_found=codes,
    )
    stored = report.stored_normals
    if stored is not None:
        row.update(
            stored_normals="vertex",
            stored_compared=stored.compared,
            stored_agreeing=stored.agreeing,
            stored_median_degrees=stored.median_angle_degrees,
        )
    if options.normals is not None:
        from mesh_normal.files.normals import npy_bytes
        from mesh_normal.points.io.write import write_points

        normals = found.normals.normals
        if options.normals_format == "ply":
            content = write_points(cloud.points, normals, "ply")
        else:
            content = npy_bytes(normals)
        row["outputs"].append(write_output(options.out, output_name(task, options), content))


def point_codes(found: PointAnalysis) -> list[str]:
    """The problem codes of a point cloud's row: points without a normal, normals whose side
    was not decided, stored normals that mostly disagree with ours."""
    report = found.report
    codes = []
    if report.with_normal < report.points:
        codes.append("without_normal")
    if report.orientation.unoriented:
        codes.append("unoriented")
    stored = report.stored_normals
    if stored is not None and stored.compared and stored.agreeing * 2 < stored.compared:
        codes.append("file_normals")
    return codes


# --- outputs ------------------------------------------------------------------------------


def relative_key(path: str) -> str:
    """Where a file's outputs go under ``--out``: its path without a scheme, a leading slash
    or ``..`` parts (``memory://a/b.stl`` -> ``a/b.stl``, ``/data/b.stl`` -> ``data/b.stl``)."""
    _, _, rest = path.rpartition("://")
    parts = [part for part in rest.replace("\\", "/").split("/") if part not in ("", ".", "..")]
    return "/".join(parts)


def output_name(task: FileTask, options: BatchOptions) -> str:
    """The normals file of ``task`` under ``--out``: ``normals/<path>.<kind>.<format>``."""
    kind = "points" if options.points else options.normals
    return f"normals/{relative_key(task.path)}.{kind}.{options.normals_format}"


def fixed_name(task: FileTask, file_format: str) -> str:
    """The fixed mesh under ``--out``: ``fixed/<path>``, its suffix the format written."""
    key = relative_key(task.path)
    stem = key.rsplit(".", 1)[0] if "." in key.rsplit("/", 1)[-1] else key
    return f"fixed/{stem}.{file_format}"


def join(base: str, name: str) -> str:
    """``base`` (a folder or a folder URL) and a relative ``name`` under it."""
    return base.rstrip("/") + "/" + name


def write_output(out: str, name: str, data: bytes) -> str:
    """Write ``data`` to ``out/name`` atomically (a temporary name beside it, then a rename),
    through fsspec; returns the URL written."""
    target = join(out, name)
    fs, path = fsspec.core.url_to_fs(target)
    parent = path.rsplit("/", 1)[0]
    fs.makedirs(parent, exist_ok=True)
    temporary = f"{parent}/.{path.rsplit('/', 1)[-1]}.{uuid.uuid4().hex[:12]}.tmp"
    with fs.open(temporary, "wb") as file:
        file.write(data)
    fs.mv(temporary, path)
    return target
