"""A mesh's normals as a file: JSON, CSV or NumPy ``.npy``, in the file's own order."""

from __future__ import annotations

import io
from collections.abc import Iterator
from typing import Literal, TypeAlias, get_args

import numpy as np
from numpy.typing import NDArray
from pydantic_core import to_json

from mesh_normal.choices import NormalsKind as NormalsKind
from mesh_normal.files import LoadedMesh
from mesh_normal.files.ply import ply_bytes
from mesh_normal.mesh.corners import CornerBlocks, corner_blocks
from mesh_normal.mesh.faces import face_geometry
from mesh_normal.mesh.vertices import Weighting, vertex_normals

NormalsFormat = Literal["json", "csv", "npy"]
KINDS: tuple[NormalsKind, ...] = get_args(NormalsKind)
FORMATS: tuple[NormalsFormat, ...] = ("json", "csv", "npy")
#: Normals a block of a streamed file holds (faces for corner normals): each block is a
#: short step, a few milliseconds.
BLOCK_ROWS = 4096
#: Normals to write: an array, or corner normals made a block at a time as they are written.
Normals: TypeAlias = NDArray[np.float64] | CornerBlocks


def compute_normals(
    mesh: LoadedMesh, kind: NormalsKind, weighting: Weighting = "angle", crease_angle: float = 30.0
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The normals of one kind and the mask of rows without one (zero rows, never NaN).

    Returns
    -------
    normals : (m, 3), (n, 3) or (m, 3, 3) float64
        Face, vertex or corner normals.
    missing : (m,), (n,) or (m, 3) bool
        Degenerate faces, vertices in no usable face, corners whose sum cancels.
    """
    checked = mesh.checked()  # the reader checked the arrays
    if kind == "face":
        # The unit normals made in place of the cross products, which are not needed after
        # them (bit for bit FaceGeometry.normals).
        geometry = face_geometry(checked)
        return geometry.unit_normals(out=geometry.crosses), geometry.degenerate
    if kind == "vertex":
        smooth = vertex_normals(checked, weighting=weighting)
        return smooth.normals, smooth.missing
    corners = corner_blocks(checked, crease_angle=crease_angle, weighting=weighting)
    return corners.block(0, len(corners)), corners.missing


def normals_to_write(
    mesh: LoadedMesh, kind: NormalsKind, weighting: Weighting = "angle", crease_angle: float = 30.0
) -> tuple[Normals, NDArray[np.bool_]]:
    """:func:`compute_normals`, but corner normals as :class:`CornerBlocks`: a file of them
    written by :func:`normals_blocks` never holds their 72 bytes a face whole."""
    if kind != "corner":
        return compute_normals(mesh, kind, weighting, crease_angle)
    corners = corner_blocks(mesh.checked(), crease_angle=crease_angle, weighting=weighting)
    return corners, corners.missing


def export_normals(
    mesh: LoadedMesh,
    kind: NormalsKind,
    weighting: Weighting,
    crease_angle: float,
    file_format: NormalsFormat,
) -> bytes:
    """The normals as the bytes of a JSON, CSV or ``.npy`` file."""
    normals, missing = compute_normals(mesh, kind, weighting, crease_angle)
    return normals_file(normals, missing, kind, weighting, crease_angle, file_format)


def normals_file(
    normals: Normals,
    missing: NDArray[np.bool_],
    kind: NormalsKind,
    weighting: Weighting,
    crease_angle: float,
    file_format: NormalsFormat,
) -> bytes:
    """Computed normals (see :func:`compute_normals`) as a JSON, CSV or ``.npy`` file."""
    return b"".join(normals_blocks(normals, missing, kind, weighting, crease_angle, file_format))


def normals_blocks(
    normals: Normals,
    missing: NDArray[np.bool_],
    kind: NormalsKind,
    weighting: Weighting,
    crease_angle: float,
    file_format: NormalsFormat,
    rows: int = BLOCK_ROWS,
) -> Iterator[bytes]:
    """The same file as :func:`normals_file`, in pieces of ``rows`` normals each: a server
    streams them, so the text of millions of normals is never whole in memory, and no single
    step holds the GIL for long."""
    if file_format == "npy":
        return _npy_blocks(normals, rows)
    if file_format == "csv":
        return _csv_blocks(normals, kind, rows)
    return _json_blocks(normals, missing, kind, weighting, crease_angle, rows)


def _json_blocks(
    normals: Normals,
    missing: NDArray[np.bool_],
    kind: NormalsKind,
    weighting: Weighting,
    crease_angle: float,
    rows: int,
) -> Iterator[bytes]:
    head = to_json(
        {
            "kind": kind,
            "weighting": None if kind == "face" else weighting,
            "crease_angle": crease_angle if kind == "corner" else None,
            "shape": list(normals.shape),
            "missing": int(np.count_nonzero(missing)),
            "missing_indices": np.argwhere(missing).tolist()
            if kind == "corner"
            else np.flatnonzero(missing).tolist(),
        }
    )
    yield head[:-1] + b',"normals":['
    for start in range(0, len(normals), rows):
        block = to_json(_rows(normals, start, start + rows).tolist())[1:-1]
        yield (b"," + block) if start else block
    yield b"]}"


def _rows(normals: Normals, start: int, stop: int) -> NDArray[np.float64]:
    if isinstance(normals, CornerBlocks):
        return normals.block(start, stop)
    return normals[start:stop]


def npy_bytes(array: NDArray[np.float64]) -> bytes:
    return b"".join(_npy_blocks(array, BLOCK_ROWS))


def _npy_blocks(normals: Normals, rows: int) -> Iterator[bytes]:
    if not isinstance(normals, CornerBlocks):
        normals = np.ascontiguousarray(normals, dtype=np.float64)
    header = io.BytesIO()
    described = {"descr": "<f8", "fortran_order": False, "shape": tuple(normals.shape)}
    np.lib.format.write_array_header_1_0(header, described)
    yield header.getvalue()
    for start in range(0, len(normals), rows):
        yield np.ascontiguousarray(_rows(normals, start, start + rows), dtype="<f8").tobytes()


def _csv_blocks(normals: Normals, kind: NormalsKind, rows: int) -> Iterator[bytes]:
    if kind == "corner":
        header = "face,corner,nx,ny,nz"
        fmt = "%d,%d,%.17g,%.17g,%.17g"
    else:
        header = f"{kind},nx,ny,nz"
        fmt = "%d,%.17g,%.17g,%.17g"
    yield header.encode() + b"\n"
    for start in range(0, len(normals), rows):
        block = _rows(normals, start, start + rows)
        if kind == "corner":
            index = (
                (np.indices(block.shape[:2]) + np.array([start, 0])[:, None, None]).reshape(2, -1).T
            )
        else:
            index = np.arange(start, start + len(block))[:, None]
        table = np.hstack([index.astype(np.float64), block.reshape(-1, 3)])
        buffer = io.BytesIO()
        np.savetxt(buffer, table, fmt=fmt, delimiter=",")
        yield buffer.getvalue()


def normals_ply(mesh: LoadedMesh, normals: NDArray[np.float64], kind: NormalsKind) -> bytes:
    """A binary PLY of the mesh with the normals as ``nx ny nz`` of its vertices or faces."""
    if kind == "vertex":
        return ply_bytes(mesh.vertices, mesh.faces, vertex_normals=normals)
    return ply_bytes(mesh.vertices, mesh.faces, face_normals=normals)
