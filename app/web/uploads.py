"""Reading uploaded files from a request: a multipart field ``file`` (repeatable) or a raw body.

The middleware counts the bytes as they arrive (see :class:`app.web.middleware.BodyLimit`)
and stops a body that grows past the limit. A multipart file is kept in memory as it arrives,
as a raw body is (:class:`_InMemory`), and its buffer becomes the upload's bytes without a copy;
nothing of an upload is written to disk or outlives its request.
The features (:mod:`app.mesh.uploads`, :mod:`app.points.api`) say what the files are.

Starlette's multipart parser, with its default spool, writes each piece of the body that the
server received (64 KB from uvicorn) to a temporary file in a thread of its pool: a hop to the
thread and back for every 64 KB, 0.15-0.2 s for a 42 MB STL. Its parser here is given the body
a megabyte at a time (:func:`coalesced`): the same parser and the same answers.
"""

from __future__ import annotations

import io
from collections.abc import AsyncGenerator, AsyncIterator
from contextlib import aclosing
from dataclasses import dataclass
from email.message import Message

from fastapi import Request
from python_multipart.multipart import parse_options_header
from starlette.datastructures import FormData, UploadFile
from starlette.exceptions import HTTPException
from starlette.formparsers import MultiPartException, MultiPartParser

from app.config import UPLOAD_FILES
from app.web.errors import ApiError


@dataclass(frozen=True, slots=True)
class Received:
    """The files sent (name and bytes, in their order; one for a raw body) and the text
    fields asked for that came with them."""

    parts: tuple[tuple[str | None, bytes], ...]
    fields: dict[str, str]


async def read_files(request: Request, what: str, text_fields: tuple[str, ...] = ()) -> Received:
    """The files of a multipart request's ``file`` field, or else the raw body (named by
    ``?filename=``); ``what`` names the file in the error sentences ("mesh")."""
    media_type = request.headers.get("content-type", "").split(";", 1)[0].strip().lower()
    if media_type == "multipart/form-data":
        return await _multipart(request, what, text_fields)
    if media_type == "application/x-www-form-urlencoded":
        raise ApiError(
            422,
            f"file is missing: send the {what} as the multipart/form-data field "
            "file, or as the raw request body.",
            "file",
        )
    data = await request.body()
    if not data:
        raise ApiError(422, f"The request body is empty: send a {what} file.", "file")
    return Received(((request.query_params.get("filename"), data),), {})


async def _multipart(request: Request, what: str, text_fields: tuple[str, ...]) -> Received:
    try:
        form = await _form(request)
    except HTTPException as error:  # Starlette's words for a malformed multipart body
        if str(error.detail).startswith("Too many files"):
            raise ApiError(
                400,
                f"At most {UPLOAD_FILES} files may be sent at once; send more as a .zip.",
                "file",
            ) from None
        detail = str(error.detail).strip().rstrip(".").replace(". ", "; ")
        raise ApiError(400, f"The multipart body cannot be read: {detail}.", "file") from None
    try:
        items = form.getlist("file")
        if not items or not all(isinstance(item, UploadFile) for item in items):
            given = "is missing" if not items else "must be a file, not a text field"
            raise ApiError(
                422, f"file {given}: send the {what} as the multipart field file.", "file"
            )
        files = [item for item in items if isinstance(item, UploadFile)]
        fields: dict[str, str] = {}
        for name in text_fields:
            value = form.get(name)
            if value is not None and not isinstance(value, str):
                raise ApiError(
                    422, f"{name} must be a text field holding a number, not a file.", name
                )
            if value is not None:
                fields[name] = value
        parts = tuple([(item.filename, await _contents(item)) for item in files])
    finally:
        await form.close()  # the spooled temporary files go now, not at garbage collection
    if len(parts) == 1 and not parts[0][1]:
        empty = parts[0][0] or ""
        raise ApiError(422, f"The uploaded file {empty} is empty.".replace("  ", " "), "file")
    return Received(parts, fields)


#: The body is handed to the multipart parser in pieces of at least this many bytes.
PIECE = 2**20


class _InMemory(MultiPartParser):
    """Starlette's parser, keeping each file in memory (a spool that never rolls over to a
    temporary file on disk: ``max_size`` 0): the body's size is already bounded by
    :class:`app.web.middleware.BodyLimit`, and its bytes are read into memory whole anyway.
    Its pieces are then written without a hop to a thread each, and read without reading a
    file back."""

    spool_max_size = 0

    def on_headers_finished(self) -> None:
        """Starlette's, but a part that names its file only as ``filename*`` (RFC 5987: how
        some clients send a name that is not ASCII) is that file, not a text field."""
        part = self._current_part
        disposition = part.content_disposition or b""
        extended = extended_filename(disposition)
        if extended is not None:
            # Starlette tells a file by a plain ``filename``: an empty one, then the real name.
            part.content_disposition = disposition + b'; filename=""'
        super().on_headers_finished()
        if extended is not None and part.file is not None:
            part.file.filename = extended


def extended_filename(disposition: bytes) -> str | None:
    """The file name a Content-Disposition header gives only as ``filename*`` (``UTF-8''``
    and the name percent-encoded, or split as ``filename*0*``, ``filename*1``...), decoded;
    ``None`` where it gives a plain ``filename`` (Starlette reads that one) or no name."""
    if b"filename*" not in disposition.lower():
        return None
    _, options = parse_options_header(disposition)
    if b"filename" in options:
        return None
    header = Message()
    header["content-disposition"] = disposition.decode("latin-1")
    return header.get_filename()


async def _contents(item: UploadFile) -> bytes:
    """The bytes of a file the parser received: its spool's own buffer where it is one
    (``getvalue``, without a copy), else read."""
    spool = getattr(item.file, "_file", None)
    if isinstance(spool, io.BytesIO):
        return spool.getvalue()
    await item.seek(0)
    return await item.read()


async def _form(request: Request) -> FormData:
    """``request.form(max_files=UPLOAD_FILES, max_fields=16)`` as Starlette does it (its
    parser, its limits, its 400 for a malformed body), with the body in larger pieces."""
    try:
        async with aclosing(request.stream()) as body, aclosing(coalesced(body)) as stream:
            parser = _InMemory(request.headers, stream, max_files=UPLOAD_FILES, max_fields=16)
            return await parser.parse()
    except MultiPartException as error:
        raise HTTPException(status_code=400, detail=error.message) from None


async def coalesced(stream: AsyncIterator[bytes], size: int = PIECE) -> AsyncGenerator[bytes, None]:
    """The bytes of ``stream`` in pieces of at least ``size`` (the last may be shorter)."""
    pieces: list[bytes] = []
    held = 0
    async for piece in stream:
        pieces.append(piece)
        held += len(piece)
        if held >= size:
            yield b"".join(pieces)
            pieces, held = [], 0
    if pieces:
        yield b"".join(pieces)
