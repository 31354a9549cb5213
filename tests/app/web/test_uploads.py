"""The body reaches the multipart parser in pieces of a megabyte: the same bytes, the same form."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator

import pytest
from fastapi.testclient import TestClient
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


def _read(disposition: bytes, data: bytes = b"solid x\nendsolid x\n") -> uploads.Received:
    """A raw multipart body of one part, ``file``, with that Content-Disposition's parameters."""
    boundary = b"b0undary"
    body = (
        b"--" + boundary + b'\r\nContent-Disposition: form-data; name="file"; ' + disposition
        + b"\r\n\r\n" + data + b"\r\n--" + boundary + b"--\r\n"
    )  # fmt: skip

    async def run() -> uploads.Received:
        return await uploads.read_files(_request(body, boundary, 65536), "mesh", ("weld",))

    return asyncio.run(run())


@pytest.mark.parametrize(
    ("disposition", "name"),
    [
        (b"filename*=UTF-8''name.stl", "name.stl"),
        (b"filename*=UTF-8''na%C3%AFve%20mesh.stl", "na\u00efve mesh.stl"),
        (b"filename*=utf-8'en'%E2%9C%93.obj", "\u2713.obj"),
        (b"filename*=ISO-8859-1''caf%E9.ply", "caf\u00e9.ply"),
        (b"filename*0*=UTF-8''two%20; filename*1=parts.stl", "two parts.stl"),
        # A plain filename is Starlette's to read, as before, whatever else is there.
        (b"filename=\"plain.stl\"; filename*=UTF-8''other.stl", "plain.stl"),
        (b'filename="plain.stl"', "plain.stl"),
    ],
)
def test_a_part_named_by_filename_star_is_a_file(disposition: bytes, name: str) -> None:
    received = _read(disposition)
    assert received.parts == ((name, b"solid x\nendsolid x\n"),)


def test_a_part_with_no_file_name_is_still_a_text_field() -> None:
    with pytest.raises(uploads.ApiError) as refused:
        _read(b'other="x.stl"')
    assert refused.value.status_code == 422
    assert "must be a file, not a text field" in refused.value.error


@pytest.mark.parametrize(
    ("disposition", "name"),
    [
        (b"", None),
        (b"filename*=UTF-8''name.stl", "name.stl"),
        (b"FILENAME*=UTF-8''name.stl", "name.stl"),
        (b"filename*=UTF-8''%FF.stl", "\ufffd.stl"),  # not UTF-8: replaced, never an error
        (b"filename*=", ""),
        (b"filename=\"a.stl\"; filename*=UTF-8''b.stl", None),
    ],
)
def test_the_extended_filename_alone_is_read(disposition: bytes, name: str | None) -> None:
    assert uploads.extended_filename(b'form-data; name="file"; ' + disposition) == name


def test_a_mesh_named_by_filename_star_is_reported(client: TestClient) -> None:
    cube = (
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        b"f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
    )
    body = (
        b'--b0undary\r\nContent-Disposition: form-data; name="file"; '
        b"filename*=UTF-8''w%C3%BCrfel.obj\r\n\r\n" + cube + b"\r\n--b0undary--\r\n"
    )
    headers = {"content-type": "multipart/form-data; boundary=b0undary"}
    answer = client.post("/api/mesh", content=body, headers=headers)
    assert answer.status_code == 200, answer.text
    assert answer.json()["faces"] == 12
    assert answer.json()["file"]["name"] == "w\u00fcrfel.obj"
