"""Reading an uploaded mesh file from a request: a multipart field ``file`` or a raw body.

The middleware counts the bytes as they arrive (see :class:`app.web.middleware.BodyLimit`);
Starlette spools a large multipart file to an anonymous temporary file, which is gone when
it is closed. We close it as soon as its bytes are read, so no upload outlives its request.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fastapi import Request
from starlette.datastructures import UploadFile
from starlette.exceptions import HTTPException

from app.web.errors import ApiError
from mesh_normal.files.formats import ACCEPTED_SUFFIXES

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
                            "type": "string",
                            "format": "binary",
                            "description": "The mesh file: "
                            + ", ".join(ACCEPTED_SUFFIXES)
                            + " (a .zip holds one mesh file with its .bin or .mtl).",
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
                    "description": "The mesh file's bytes as they are (name it with ?filename=).",
                    "example": EXAMPLE_FILE,
                }
            },
        },
    }
}


@dataclass(frozen=True, slots=True)
class Upload:
    data: bytes
    filename: str | None


async def read_upload(request: Request) -> Upload:
    """The file of a multipart request's ``file`` field, or else the raw body."""
    media_type = request.headers.get("content-type", "").split(";", 1)[0].strip().lower()
    if media_type == "multipart/form-data":
        return await _multipart(request)
    if media_type == "application/x-www-form-urlencoded":
        raise ApiError(
            422,
            "file is missing: send the mesh as the multipart/form-data field "
            "file, or as the raw request body.",
            "file",
        )
    data = await request.body()
    if not data:
        raise ApiError(422, "The request body is empty: send a mesh file.", "file")
    return Upload(data, request.query_params.get("filename"))


async def _multipart(request: Request) -> Upload:
    try:
        form = await request.form(max_files=8, max_fields=16)
    except HTTPException as error:  # Starlette's words for a malformed multipart body
        detail = str(error.detail).strip().rstrip(".").replace(". ", "; ")
        raise ApiError(400, f"The multipart body cannot be read: {detail}.", "file") from None
    try:
        item = form.get("file")
        if not isinstance(item, UploadFile):
            given = "is missing" if item is None else "must be a file, not a text field"
            raise ApiError(422, f"file {given}: send the mesh as the multipart field file.", "file")
        data = await item.read()
        filename = item.filename
    finally:
        await form.close()  # the spooled temporary files go now, not at garbage collection
    if not data:
        raise ApiError(
            422, f"The uploaded file {filename or ''} is empty.".replace("  ", " "), "file"
        )
    return Upload(data, filename)
