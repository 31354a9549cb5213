"""Reading an uploaded mesh from a request: a multipart field ``file`` or a raw body
(:mod:`app.web.uploads`), with the optional field ``weld``.

The field ``file`` may come several times (a ``.gltf`` and its ``.bin``, an OBJ and its
``.mtl``): the files are then read as the members of one ``.zip`` would be
(:func:`mesh_normal.files.read_mesh_files`), up to :data:`app.config.UPLOAD_FILES` of them.
"""

from __future__ import annotations

import copy
import math
import mmap
from dataclasses import dataclass
from pickle import PickleBuffer
from typing import Any, SupportsIndex

from fastapi import Request

from app.config import UPLOAD_FILES
from app.web.errors import ApiError, clip
from app.web.uploads import read_files
from mesh_normal.files.archive import mesh_name
from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.formats import ACCEPTED_SUFFIXES
from mesh_normal.tolerances import WELD_LIMIT

#: A tetrahedron as OBJ text: the example upload in the API documentation.
EXAMPLE_FILE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"

#: The OpenAPI ``requestBody`` of every route that takes a mesh file.
UPLOAD_BODY: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "content": {
            "multipart/form-data": {
                "schema": {
                    "type": "object",
                    "properties": {
                        "file": {
                            "type": "array",
                            "minItems": 1,
                            "maxItems": UPLOAD_FILES,
                            "items": {"type": "string", "format": "binary"},
                            "description": "The mesh file: "
                            + ", ".join(ACCEPTED_SUFFIXES)
                            + " (a .zip holds one mesh file with its .bin or .mtl). Or the "
                            "field repeated, up to "
                            f"{UPLOAD_FILES} times: the mesh file with the files it names "
                            "(Box.gltf with Box0.bin, model.obj with model.mtl), read as "
                            "the members of one .zip.",
                            "example": [EXAMPLE_FILE],
                        }
                    },
                    "required": ["file"],
                }
            },
            "application/octet-stream": {
                "schema": {
                    "type": "string",
                    "format": "binary",
                    "description": "The mesh file's bytes as they are (name it with ?filename=).",
                    "example": EXAMPLE_FILE,
                }
            },
        },
    }
}


#: What the optional ``weld`` input means, for the API documentation.
WELD_HELP = (
    "Optional, off by default: also treat vertices closer than this fraction of the "
    f"bounding-box diagonal (0 to {WELD_LIMIT:g}; 1e-6 covers float32 rounding) as one point, "
    "for files whose pieces miss each other by rounding. The vertices are kept."
)

#: UPLOAD_BODY with the optional multipart field ``weld``: the report and the fix take it.
UPLOAD_WELD_BODY: dict[str, Any] = copy.deepcopy(UPLOAD_BODY)
UPLOAD_WELD_BODY["requestBody"]["content"]["multipart/form-data"]["schema"]["properties"][
    "weld"
] = {
    "type": "number",
    "minimum": 0,
    "maximum": WELD_LIMIT,
    "description": WELD_HELP + " With a raw body, send it as the query parameter weld.",
}


@dataclass(frozen=True, slots=True)
class Upload:
    """One mesh file, or several files read as one mesh (``parts``, by name; ``data`` is then
    empty and ``filename`` the name of the mesh file among them, if one is)."""

    data: bytes
    filename: str | None
    parts: tuple[tuple[str | None, bytes], ...] = ()
    weld: float | None = None  # the multipart field weld, checked
    #: In a job worker: the one file as it came from the server in shared memory, a read-only
    #: map of it (:func:`mesh_normal.workers.send`), instead of ``data`` (then empty).
    mapped: mmap.mmap | None = None

    @classmethod
    def several(cls, parts: tuple[tuple[str | None, bytes], ...], weld: float | None) -> Upload:
        try:
            filename: str | None = mesh_name((name or "" for name, _ in parts), "")
        except MeshFileError:  # reading the files says what is wrong, in its own sentence
            filename = None
        return cls(b"", filename, parts, weld)

    def __reduce_ex__(self, protocol: SupportsIndex) -> Any:
        """With protocol 5, the bytes are pickled out of band: they travel to a worker process
        (:mod:`mesh_normal.workers`) as they are, never copied into the pickle."""
        if int(protocol) < 5:
            return object.__reduce_ex__(self, protocol)
        parts = tuple((name, PickleBuffer(data)) for name, data in self.parts)
        data = PickleBuffer(self.data if self.mapped is None else self.mapped)
        return (_rebuilt, (data, self.filename, parts, self.weld))

    @property
    def size(self) -> int:
        """Bytes sent: the file's, or all the files' together."""
        if self.mapped is not None:
            return len(self.mapped)
        return sum(len(data) for _, data in self.parts) if self.parts else len(self.data)

    @property
    def names(self) -> list[str]:
        """The names of the files sent, in their order (``mesh`` for one without a name)."""
        if not self.parts:
            return [self.filename or "mesh"]
        return [name or "mesh" for name, _ in self.parts]


def _rebuilt(
    data: bytes | mmap.mmap,
    filename: str | None,
    parts: tuple[tuple[str | None, bytes], ...],
    weld: float | None,
) -> Upload:
    files = tuple((name, bytes(part)) for name, part in parts)
    if isinstance(data, mmap.mmap):  # one file, in shared memory: kept as it is, not copied
        return Upload(b"", filename, files, weld, mapped=data)
    return Upload(bytes(data), filename, files, weld)


def weld_field(text: str) -> float | None:
    """The ``weld`` form field as a number 0 to WELD_LIMIT; an empty field is off."""
    if not text.strip():
        return None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 <= value <= WELD_LIMIT):
        raise ApiError(
            422,
            f"weld must be a number from 0 to {WELD_LIMIT:g} (a fraction of the bounding-box "
            f"diagonal), not {clip(text)!r}.",
            "weld",
        )
    return value


def upload_weld(upload: Upload, query: float | None) -> float | None:
    """The weld of a request: the form field or the query parameter, not both."""
    if upload.weld is not None and query is not None:
        raise ApiError(
            422, "weld is given twice: send it as a form field or a query parameter.", "weld"
        )
    return query if upload.weld is None else upload.weld


async def read_upload(request: Request) -> Upload:
    """The mesh file of a multipart request's ``file`` field (and ``weld``), or the raw body."""
    received = await read_files(request, "mesh", ("weld",))
    weld = received.fields.get("weld")
    tolerance = None if weld is None else weld_field(weld)
    if len(received.parts) > 1:
        return Upload.several(received.parts, tolerance)
    filename, data = received.parts[0]
    return Upload(data, filename, weld=tolerance)
