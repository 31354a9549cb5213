"""The body reaches the multipart parser in pieces of a megabyte: the same bytes, the same form."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator

import pytest
from starlette.requests import Request

from app.web import uploads


async def _pieces(sizes: list[int]) -> AsyncIterator[bytes]:
    for number, size in enumerate(sizes):
        yield bytes([number % 256]) * size


def _gathered(sizes: list[int], size: int) -> list[bytes]:
    async def run() -> list[bytes]:
        return [piece async for piece in uploads.coalesced(_pieces(sizes), size)]

    return asyncio.run(run())


@pytest.mark.parametrize(
    "sizes", [[], [0], [5], [3, 3, 3, 3], [10, 0, 1], [4] * 25, [1, 100, 1, 1]]
)
def test_pieces_hold_the_same_bytes_in_order(sizes: list[int]) -> None:
    found = _gathered(sizes, 10)
    assert b"".join(found) == b"".join(bytes([n % 256]) * s for n, s in enumerate(sizes))
    assert all(len(piece) >= 10 for piece in found[:-1])  # only the last may be shorter


def _request(body: bytes, boundary: bytes, piece: int) -> Request:
    chunks = [body[i : i + piece] for i in range(0, len(body), piece)] or [b""]
    messages = iter(chunks)

    async def receive() -> dict[str, object]:
        chunk = next(messages, None)
        if chunk is None:
            return {"type": "http.request", "body": b"", "more_body": False}
        return {"type": "http.request", "body": chunk, "more_body": True}

    content_type = b"multipart/form-data; boundary=" + boundary
    scope = {"type": "http", "method": "POST", "path": "/", "query_string": b"",
             "headers": [(b"content-type", content_type)]}  # fmt: skip
    return Request(scope, receive)


def test_a_file_sent_in_64_kb_messages_is_read_whole() -> None:
    data = bytes(range(256)) * 12_000  # 3 MB: past the parser's spool to a temporary file
    boundary = b"b0undary"
    body = (
        b"--" + boundary + b'\r\nContent-Disposition: form-data; name="file"; filename="a.stl"'
        b"\r\n\r\n" + data + b"\r\n--" + boundary + b"\r\nContent-Disposition: form-data; "
        b'name="weld"\r\n\r\n0.5\r\n--' + boundary + b"--\r\n"
    )

    async def run() -> uploads.Received:
        return await uploads.read_files(_request(body, boundary, 65536), "mesh", ("weld",))

    received = asyncio.run(run())
    assert received.parts == (("a.stl", data),)
    assert received.fields == {"weld": "0.5"}
