"""What one file's job is given: the file (:class:`FileTask`) and the batch's options
(:class:`BatchOptions`). Both are small frozen dataclasses, picklable, so that they travel to a
worker process or a Dask worker unchanged."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

NormalsKind = Literal["face", "vertex", "corner"]
NormalsFormat = Literal["npy", "ply"]


@dataclass(frozen=True, slots=True)
class FileTask:
    """One input file.

    ``url`` is what fsspec opens (a local path or a URL such as ``s3://bucket/a.stl``); ``path``
    is how the table names it (relative to the input it was found under, or the URL itself);
    ``size`` is its size in bytes as the listing gave it.
    """

    url: str
    path: str
    size: int


@dataclass(frozen=True, slots=True)
class BatchOptions:
    """The options every file of a batch is run with.

    ``out`` is the folder (a local path or an fsspec URL) the outputs go to; ``normals`` writes
    face, vertex or corner normals (``normals_format`` ``npy`` or ``ply``); ``fix`` writes the
    fixed mesh (consistent, outward winding) as PLY; ``points`` reads the inputs as point clouds
    and runs the point-cloud report. ``timeout`` (seconds) and ``max_file_mb`` bound one file;
    ``memory_mb`` bounds a worker process's memory beyond its start (``None``: no bound).
    ``weld`` and ``crease_angle`` are as for ``mn.analyse`` and ``mn.corner_normals``; ``k`` is
    the point-cloud neighbourhood.
    """

    out: str
    normals: NormalsKind | None = None
    normals_format: NormalsFormat = "npy"
    fix: bool = False
    points: bool = False
    timeout: float | None = 60.0
    max_file_mb: float | None = None
    memory_mb: float | None = None
    weld: float | None = None
    crease_angle: float = 30.0
    k: int = 30
