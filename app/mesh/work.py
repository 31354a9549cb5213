"""The heavy mesh work, everything after the upload is read: what a worker process runs.

Each function takes the upload and plain arguments and returns plain values (arrays, models,
dicts), so that it can run in a worker process (:mod:`app.web.jobs`): the routes name them
as ``work.report`` and so on, looked up when called.
"""

from __future__ import annotations

import json
import posixpath
import shlex
from typing import Any, get_args

import numpy as np
from numpy.typing import NDArray

from app.mesh.classes import CLASSES
from app.mesh.figures import mesh_figures
from app.mesh.uploads import Upload
from app.web.errors import ApiError
from mesh_normal import allocator
from mesh_normal.files import LoadedMesh, MeshFileError, read_mesh, read_mesh_files, stl
from mesh_normal.files.formats import FORMATS as MESH_FORMATS
from mesh_normal.files.formats import WRITABLE
from mesh_normal.files.normals import FORMATS, KINDS, Normals, NormalsKind, normals_to_write
from mesh_normal.files.read import read_mapped, reads_as_binary_stl
from mesh_normal.files.rewrite import NormalsChoice, Winding, export_mesh, file_normals
from mesh_normal.files.write import unkept
from mesh_normal.mesh.report.analysis import analyse_mesh, build_report, flips_by_component
from mesh_normal.mesh.report.models import MeshReport
from mesh_normal.mesh.vertices import Weighting

#: The formats the fixed mesh can be downloaded in: the library's writable ones.
FIX_FORMATS = WRITABLE
#: The page's "Download with normals": the formats that hold normals and the kinds offered.
EXPORT_FORMATS = ("obj", "ply", "glb")
EXPORT_NORMALS: tuple[NormalsKind, ...] = ("vertex", "face", "corner")
#: Problems that the fixed mesh (orient()) repairs: their card gets the download button.
FIXED_BY_ORIENT = frozenset({"winding", "inward", "mixed"})


#: A binary STL of this many bytes or more keeps the memory its job frees for the job's next
#: arrays, and has its arrays' memory faulted in ahead, on another thread (see
#: ``mesh_normal.allocator``). Below it that costs more than it saves: the kept memory raises
#: the job's peak (a 43 MB upload's from 259 to 306 MB, for no time gained), and the thread
#: takes a core from the parallel kernels. Only binary STL: the text formats' jobs take more
#: memory with freed blocks kept in the heap.
FAULT_AHEAD_FROM = 256 * 2**20


def ahead(size: int) -> None:
    """In a job worker, before a binary STL of ``size`` bytes is read: from
    ``FAULT_AHEAD_FROM`` bytes, keep freed memory for this job and fault its arrays' memory in
    on another thread (the worker undoes both when the job ends). Nothing outside a worker."""
    if size >= FAULT_AHEAD_FROM:
        allocator.start_job(allocator.ARRAYS_PER_STL_BYTE * size)


def load(upload: Upload) -> LoadedMesh:
    """Read the uploaded file (or files); a broken or unknown file becomes a 4xx naming the
    problem. A file that came in shared memory (``upload.mapped``) is read from the map where
    it is a binary STL (the reader copies only what it keeps), else from a copy of its bytes.
    What the file expands into is charged to its one budget (``read_mesh`` and
    ``read_mesh_files`` open it): a 413 beyond it."""
    try:
        if upload.parts:
            return read_mesh_files(upload.parts)
        if upload.mapped is not None:
            mapped = upload.mapped
            if reads_as_binary_stl(mapped[:4096], len(mapped)):
                ahead(len(mapped))
                return read_mapped(mapped, upload.filename or "")
            return read_mesh(bytes(mapped), upload.filename)
        if stl.is_binary(upload.data):
            ahead(len(upload.data))
        return read_mesh(upload.data, upload.filename)
    except MeshFileError as error:
        raise ApiError(error.status_code, str(error), "file") from None


def report(upload: Upload, weld: float | None) -> MeshReport:
    """The report of ``POST /api/mesh``."""
    return build_report(analyse_mesh(load(upload), upload.filename, upload.size, weld=weld))


def normals(
    upload: Upload, kind: NormalsKind, weighting: Weighting, crease_angle: float
) -> tuple[Normals, NDArray[np.bool_]]:
    """The normals and the mask of rows without one (the answer is written from them in
    blocks, by the server): corner normals as what they are made of, a block of faces at a
    time as they are written, so that their 72 bytes a face are never whole in either
    process."""
    return normals_to_write(load(upload), kind, weighting, crease_angle)


def fix(
    upload: Upload, file_format: str | None, weld: float | None
) -> tuple[NDArray[np.uint8], str, dict[str, str]]:
    """The fixed file's bytes (as an array, so that they travel without a copy), its format
    and the headers saying what changed: :func:`export` with ``winding="fix"``, the normals
    the file had."""
    return export(upload, file_format, "auto", "angle", 30.0, "fix", weld)


def export(
    upload: Upload,
    file_format: str | None,
    normals: NormalsChoice,
    weighting: Weighting,
    crease_angle: float,
    winding: Winding,
    weld: float | None,
) -> tuple[NDArray[np.uint8], str, dict[str, str]]:
    """The file written again (:func:`~mesh_normal.files.rewrite.export_mesh`), its format and
    the headers saying what changed and what the format could not hold."""
    mesh = load(upload)
    try:
        # The same weld as the report's, so that the file is the fix the report described.
        result = export_mesh(
            mesh,
            file_format,
            normals=normals,
            winding=winding,
            weighting=weighting,
            crease_angle=crease_angle,
            weld=weld,
        )
    except MeshFileError as error:  # e.g. coordinates beyond what STL's floats hold
        raise ApiError(error.status_code, str(error), "format") from None
    headers = {
        "x-faces-flipped": str(result.faces_flipped),
        "x-normals": result.normals_kind or "none",
    }
    if result.orientation is not None:
        headers["x-component-faces-flipped"] = flips_by_component(result.orientation)
        headers["x-orientation-before"] = result.orientation.orientation
    if weld is not None:
        headers["x-weld"] = repr(weld)
    if result.kept:
        headers["x-kept"] = "; ".join(result.kept)
    if result.dropped:  # do no harm: never leave data out without saying so
        headers["x-dropped"] = "; ".join(result.dropped)
    return np.frombuffer(result.data, dtype=np.uint8), result.file_format, headers


def page(upload: Upload, stem: str, base_url: str) -> dict[str, Any]:
    """The mesh page's context for an upload: the report, its figures and the downloads."""
    mesh = load(upload)
    analysis = analyse_mesh(mesh, upload.filename, upload.size, weld=upload.weld)
    built = build_report(analysis)
    weld = "" if upload.weld is None else f" -F weld={upload.weld!r}"
    return {
        "files": files_read(upload, mesh.files),
        "fix_dropped": fix_dropped(mesh),
        "report": built,
        # The JSON twin is the API's own JSON (non-finite floats already null), parsed back
        # so that the template's json_script escapes it for a <script> block.
        "report_json": json.loads(built.to_json()),
        "figures": mesh_figures(analysis),
        "classes": CLASSES,
        "stem": stem,
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
        "export_formats": EXPORT_FORMATS,
        "export_normals": EXPORT_NORMALS,
        "fixed_by_orient": FIXED_BY_ORIENT,
    }


def fix_dropped(mesh: LoadedMesh) -> dict[str, str]:
    """For each format of the fixed mesh, the sentence saying what of this mesh it leaves out,
    in the words of the fix's ``X-Dropped`` header; empty when it keeps everything."""
    objects = len(mesh.group_names or ())
    had = file_normals(mesh)
    dropped = {
        name: [
            *unkept(name, mesh.vertex_colors, mesh.face_colors, objects=objects, normals_kind=had),
            *mesh.unkept,
        ]
        for name in FIX_FORMATS
    }
    keeping = [MESH_FORMATS[name].title for name, left_out in dropped.items() if not left_out]
    listed = (
        ", ".join(keeping[:-1]) + " and " + keeping[-1] if len(keeping) > 1 else "".join(keeping)
    )
    keeps = listed + (" keeps" if len(keeping) == 1 else " keep")
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
