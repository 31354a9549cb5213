"""The normals of ``POST /api/points/normals`` as JSON, CSV or ``.npy``, written in blocks.

The server streams them as the client reads, from the arrays the worker sent back, so the
text of millions of normals is never whole in memory (as :mod:`mesh_normal.files.normals` does for
a mesh's). PLY and XYZ, which carry the points too, are written whole by the worker.
"""

from __future__ import annotations

import io
from collections.abc import Iterator

import numpy as np

from app.web.jsonio import json_bytes
from mesh_normal.files.normals import BLOCK_ROWS, npy_bytes
from mesh_normal.types import BoolArray, FloatArray


def normals_blocks(
    normals: FloatArray, missing: BoolArray, orient: str, file_format: str, rows: int = BLOCK_ROWS
) -> Iterator[bytes]:
    """``normals`` (n, 3), zeros where ``missing``, as ``file_format``: json, csv or npy."""
    if file_format == "npy":
        return iter((npy_bytes(normals),))  # binary, no text to spare: one block
    if file_format == "csv":
        return _csv_blocks(normals, rows)
    return _json_blocks(normals, missing, orient, rows)


def _json_blocks(
    normals: FloatArray, missing: BoolArray, orient: str, rows: int
) -> Iterator[bytes]:
    head = json_bytes(
        {
            "orient": orient,
            "shape": list(normals.shape),
            "missing": int(np.count_nonzero(missing)),
            "missing_indices": np.flatnonzero(missing).tolist(),
        }
    )
    yield head[:-1] + b',"normals":['
    for start in range(0, len(normals), rows):
        block = json_bytes(normals[start : start + rows].tolist())[1:-1]
        yield (b"," + block) if start else block
    yield b"]}"


def _csv_blocks(normals: FloatArray, rows: int) -> Iterator[bytes]:
    """``point,nx,ny,nz`` rows; 17 significant digits, so every value round-trips."""
    yield b"point,nx,ny,nz\n"
    for start in range(0, len(normals), rows):
        block = normals[start : start + rows]
        index = np.arange(start, start + len(block), dtype=np.float64)[:, None]
        out = io.BytesIO()
        np.savetxt(out, np.hstack([index, block]), fmt="%d,%.17g,%.17g,%.17g")
        yield out.getvalue()
