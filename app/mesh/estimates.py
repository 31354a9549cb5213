"""How much memory a mesh job may take, estimated from the upload before the work starts.

The admission control (:mod:`app.web.jobs`) charges each job this estimate against the
server's memory budget. The factors are the peak memory measured per byte of upload by
``make bench-memory`` (the largest of reading, the report, the normals and the fix:
binary STL 5.1, ASCII STL 3.3, OBJ 4.9, binary PLY 4.9, ASCII PLY 3.8, OFF 6.0, GLB 5.9),
rounded up with a margin; lower them here, in this one table, when the readers take
less.
"""

from __future__ import annotations

from typing import Literal

from app.mesh.uploads import Upload
from app.web.errors import ApiError
from mesh_normal.files.archive import is_zip, open_zip
from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.expansion import expansion_limit
from mesh_normal.files.formats import suffix_format

#: Peak memory of reading and analysing a mesh, per byte of its file, by format (the larger
#: of its binary and ASCII figures, plus a margin). glTF and 3MF are not measured: they take a
#: cautious 26.
MEMORY_PER_BYTE: dict[str, float] = {
    "stl": 6,
    "obj": 6,
    "ply": 7,
    "off": 7,
    "glb": 7,
    "gltf": 26,
    "3mf": 26,
}
#: For a file whose format is not known before reading it: the largest factor.
UNKNOWN_PER_BYTE = max(MEMORY_PER_BYTE.values())

#: What each task adds per byte of the file to the reading's peak: the page's figures, the
#: fixed file written, the normals kept for the answer. On a smooth torus, the fix and
#: the normals add at most 0.2 to the report's peak; corner normals keep 4, as creased
#: vertices take about 100 bytes a corner (not measured there); the page is not measured.
#: JSON and CSV normals are streamed in blocks, so their text is never whole in memory.
Task = Literal["report", "page", "fix", "face", "vertex", "corner"]
TASK_PER_BYTE: dict[Task, float] = {
    "report": 0,
    "page": 2,
    "fix": 1,
    "face": 0.5,
    "vertex": 0.5,
    "corner": 4,
}

#: Bytes every job takes whatever its size (its arrays' bookkeeping, the report, the pickles).
JOB_OVERHEAD = 64 * 2**20


def estimate(upload: Upload, task: Task) -> int:
    """The bytes of memory this upload's job may take at its peak. A .zip whose directory
    lists more members than the reader accepts is refused here, before any work (a 413)."""
    files = upload.parts or ((upload.filename, upload.data),)
    total = 0.0
    for name, data in files:
        size, per_byte = _size_and_factor(name, data)
        total += size * (per_byte + TASK_PER_BYTE[task])
    return int(total) + JOB_OVERHEAD


def _size_and_factor(name: str | None, data: bytes) -> tuple[int, float]:
    """The bytes to read and their factor; for a .zip, its members' unpacked sizes."""
    from mesh_normal.files.read import sniff  # here: the readers and NumPy load after start-up

    if is_zip(data) and sniff(data) != "3mf":
        return _zip_size(data), UNKNOWN_PER_BYTE
    found = sniff(data) or suffix_format(name)
    return len(data), MEMORY_PER_BYTE.get(found or "", UNKNOWN_PER_BYTE)


def _zip_size(data: bytes) -> int:
    """The members' unpacked size, as the archive's directory states it (capped where the
    reader stops: its expansion budget); a zip that cannot be opened counts as its own size
    (the reader refuses it). The directory is counted before it is parsed (``open_zip``)."""
    try:
        with open_zip(data) as archive:
            unpacked = sum(info.file_size for info in archive.infolist())
    except MeshFileError as error:
        if error.status_code == 413:  # too many members: refused now, in the server
            raise ApiError(413, str(error), "file") from None
        return len(data)
    return min(max(unpacked, len(data)), expansion_limit(len(data)))
