"""The fast lane for POST /api/normal writes exactly what the whole stack writes.

Every request here goes to two apps: the service as it is (the lane outermost of our
middleware) and the same app built without the lane. Status, headers (in order) and body must
be the same bytes; where the lane is meant to answer, the stack behind it must not have been
called at all, and where it must not answer (any doubt), it must have passed the request on.
"""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest
from fastapi import FastAPI
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app import config
from app.calculator.lane import NormalFastLane
from app.main import create_app

PATH = "/api/normal"
JSON = (b"content-type", b"application/json")
LIMIT = config.BODY_LIMITS.get(PATH, config.DEFAULT_BODY_LIMIT)


class Counting:
    """The stack behind the lane, counting the requests that reach it."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app
        self.calls = 0

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        self.calls += 1
        await self.app(scope, receive, send)


def build(with_lane: bool) -> tuple[FastAPI, Counting | None]:
    app = create_app()
    if not with_lane:
        app.user_middleware = [m for m in app.user_middleware if m.cls is not NormalFastLane]
        app.middleware_stack = app.build_middleware_stack()
        return app, None
    app.middleware_stack = app.build_middleware_stack()
    node: Any = app.middleware_stack
    while not isinstance(node, NormalFastLane):
        node = node.app
    behind = Counting(node.app)
    node.app = behind
    return app, behind


@pytest.fixture(scope="module")
def apps() -> tuple[FastAPI, FastAPI, Counting]:
    with_lane, behind = build(True)
    without, _ = build(False)
    assert behind is not None
    return with_lane, without, behind


def call(
    app: FastAPI,
    chunks: list[bytes],
    headers: list[tuple[bytes, bytes]],
    method: str = "POST",
    path: str = PATH,
    root_path: str = "",
    query: bytes = b"",
    end: Message | None = None,
) -> list[Message]:
    """Every message the app sends for one request whose body comes in ``chunks``."""
    scope: dict[str, Any] = {
        "type": "http",
        "asgi": {"version": "3.0", "spec_version": "2.4"},
        "http_version": "1.1",
        "method": method,
        "scheme": "http",
        "path": path,
        "raw_path": path.encode(),
        "query_string": query,
        "root_path": root_path,
        "headers": headers,
        "client": ("127.0.0.1", 50000),
        "server": ("127.0.0.1", 8000),
        "state": {},
    }
    pending: list[Message] = [
        {"type": "http.request", "body": chunk, "more_body": i < len(chunks) - 1}
        for i, chunk in enumerate(chunks)
    ]
    if end is not None:  # a disconnect instead of the body's last message
        pending[-1:] = [end]
    sent: list[Message] = []

    async def receive() -> Message:
        if pending:
            return pending.pop(0)
        await asyncio.sleep(0)
        return {"type": "http.disconnect"}

    async def send(message: Message) -> None:
        sent.append(message)

    async def run() -> None:
        await app(scope, receive, send)

    asyncio.run(run())
    return sent


def post(body: bytes, headers: list[tuple[bytes, bytes]] | None = None) -> dict[str, Any]:
    """Keyword arguments for :func:`call`: ``body`` as JSON with its true length."""
    given_headers = headers if headers is not None else [JSON]
    return {
        "chunks": [body],
        "headers": [*given_headers, (b"content-length", str(len(body)).encode())],
    }


def compare(
    apps: tuple[FastAPI, FastAPI, Counting], *, lane_answers: bool, **request: Any
) -> list[Message]:
    """The same request to both apps: the same messages; whether the lane answered itself."""
    with_lane, without, behind = apps
    before = behind.calls
    ours = call(with_lane, **request)
    theirs = call(without, **request)
    assert ours == theirs
    assert (behind.calls == before) is lane_answers, (lane_answers, ours[:1])
    return ours


def status_and_json(messages: list[Message]) -> tuple[int, Any]:
    body = b"".join(m.get("body", b"") for m in messages if m["type"] == "http.response.body")
    return messages[0]["status"], json.loads(body)


def body_of(a: Any, b: Any, c: Any, **extra: Any) -> bytes:
    return json.dumps({"a": a, "b": b, "c": c, **extra}).encode()


#: JSON decimals, whose exact forms are too long to show: the fast path's common case.
EXAMPLE = body_of([0.1, 0.2, 0.3], [1.7, -0.4, 2.2], [-0.6, 1.3, 0.9])
#: The calculator's example: small integers, whose exact forms the exact path writes.
INTEGERS = body_of([1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0])


def test_the_lane_answers_the_example_as_the_stack_does(apps) -> None:  # type: ignore[no-untyped-def]
    messages = compare(apps, lane_answers=True, **post(EXAMPLE))
    status, result = status_and_json(messages)
    assert status == 200
    assert result["normal"] == [-2.45, -2.29, 1.34]
    assert result["unit_normal"] == pytest.approx([-0.6784, -0.6341, 0.3710], abs=1e-4)
    names = [key for key, _ in messages[0]["headers"]]
    assert names[:2] == [b"content-length", b"content-type"]
    assert b"content-security-policy" in names and b"x-content-type-options" in names


coordinate = st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from(
    [0.0, -0.0, 1e-310, -5e-324, 1e308, -1.7976931348623157e308, 0.1, 1 + 2**-52]
)
point = st.lists(coordinate, min_size=3, max_size=3)


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(a=point, b=point, c=point, swap=st.booleans())
def test_random_triangles_get_the_stacks_exact_bytes(apps, a, b, c, swap) -> None:  # type: ignore[no-untyped-def]
    request = post(body_of(a, b, c, swap_winding=swap))
    with_lane, without, _ = apps
    ours = call(with_lane, **request)
    assert ours == call(without, **request)
    assert ours[0]["status"] == 200


@pytest.mark.parametrize(
    "body",
    [
        body_of([1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [3.0, 3.0, 3.0]),  # collinear
        body_of([1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),  # one point
        body_of([1e308, 0.0, 0.0], [-1e308, 1e308, 0.0], [0.0, 0.0, 1e308]),  # overflowing sums
        INTEGERS,  # exact forms that fit
    ],
)
def test_triangles_for_the_exact_path_go_to_the_stack(apps, body: bytes) -> None:  # type: ignore[no-untyped-def]
    messages = compare(apps, lane_answers=False, **post(body))
    assert messages[0]["status"] == 200


@pytest.mark.parametrize(
    "body",
    [
        body_of([0.1, 0.2, 0.3], [1.7, -0.4, 2.2], [-0.6, 1.3, 0.9], swap_winding=True),
        body_of([0.1, 0.2, 0.3], [1.7, -0.4, 2.2], [-0.6, 1.3, 0.9], swap_winding=False),
        b' {"a": [0.1, 0.2, 0.3], "b": [1.7, -0.4, 2.2], "c": [-0.6, 1.3, 0.9]}\n',
        b'{"c":[-0.6,1.3,0.9],"b":[1.7,-0.4,2.2],"a":[0.1,0.2,0.3]}',
        body_of([0.0, 0.0, 0.0], [1 + 2**-52, 1.0, 0.0], [1.0, 1 - 2**-53, 0.0]),  # a sliver
        body_of([1e6 + 0.1, 2e6, 3e6], [1e6 + 1.7, 2e6 - 0.4, 3e6 + 2.2], [1e6, 2e6 + 1.3, 3e6]),
    ],
)
def test_the_lane_answers_decimals_with_the_stacks_bytes(apps, body: bytes) -> None:  # type: ignore[no-untyped-def]
    messages = compare(apps, lane_answers=True, **post(body))
    assert messages[0]["status"] == 200


@pytest.mark.parametrize(
    "body",
    [
        body_of([1, 0, 0], [0, 2, 0], [0, 0, 3]),  # integers: the exact path
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, NaN]}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, 1e400]}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, "3"]}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0]}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0]}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, 3.0], "d": 1}',
        b'{"a": [1.0, 0.0, 0.0], "a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, 3.0]}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, 3.0], "swap_winding": 1}',
        b'{"a": [1.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, 3.0]',
        b"[1.0, 2.0, 3.0]",
        b"null",
        b"   ",
        b"\xff\xfe",
    ],
)
def test_whatever_the_lane_doubts_goes_to_the_stack(apps, body: bytes) -> None:  # type: ignore[no-untyped-def]
    compare(apps, lane_answers=False, **post(body))


@pytest.mark.parametrize(
    "headers",
    [
        [(b"content-type", b"application/json; charset=utf-8")],
        [(b"content-type", b"Application/JSON")],
        [(b"content-type", b"application/problem+json")],
        [(b"content-type", b"text/plain")],
        [JSON, JSON],
        [],
    ],
)
def test_other_content_types_go_to_the_stack(apps, headers) -> None:  # type: ignore[no-untyped-def]
    compare(apps, lane_answers=False, **post(EXAMPLE, headers))


@pytest.mark.parametrize(
    "length",
    [
        None,  # no Content-Length (chunked)
        b"",
        b"+181",
        b" 64",
        b"0",
        str(len(EXAMPLE) - 1).encode(),  # shorter than the body
        str(len(EXAMPLE) + 1).encode(),  # longer than the body
        str(LIMIT + 1).encode(),  # beyond the path's limit: 413 from the stack
    ],
)
def test_lengths_the_body_does_not_match_go_to_the_stack(apps, length) -> None:  # type: ignore[no-untyped-def]
    headers = [JSON] if length is None else [JSON, (b"content-length", length)]
    compare(apps, lane_answers=False, chunks=[EXAMPLE], headers=headers)


def test_two_content_lengths_go_to_the_stack(apps) -> None:  # type: ignore[no-untyped-def]
    length = (b"content-length", str(len(EXAMPLE)).encode())
    compare(apps, lane_answers=False, chunks=[EXAMPLE], headers=[JSON, length, length])


def test_a_body_in_pieces_is_read_whole(apps) -> None:  # type: ignore[no-untyped-def]
    pieces = [EXAMPLE[:7], b"", EXAMPLE[7:50], EXAMPLE[50:]]
    length = (b"content-length", str(len(EXAMPLE)).encode())
    messages = compare(apps, lane_answers=True, chunks=pieces, headers=[JSON, length])
    assert status_and_json(messages)[0] == 200


def test_a_body_beyond_its_length_is_replayed_whole(apps) -> None:  # type: ignore[no-untyped-def]
    pieces = [EXAMPLE[:20], EXAMPLE[20:], b" ", b'{"x": 1}']
    length = (b"content-length", str(len(EXAMPLE)).encode())
    compare(apps, lane_answers=False, chunks=pieces, headers=[JSON, length])


def test_a_disconnect_mid_body_reaches_the_stack(apps) -> None:  # type: ignore[no-untyped-def]
    length = (b"content-length", str(len(EXAMPLE)).encode())
    compare(
        apps,
        lane_answers=False,
        chunks=[EXAMPLE[:20], b"unsent"],
        headers=[JSON, length],
        end={"type": "http.disconnect"},
    )


@pytest.mark.parametrize("method", ["GET", "HEAD", "PUT", "OPTIONS"])
def test_other_methods_go_to_the_stack(apps, method: str) -> None:  # type: ignore[no-untyped-def]
    query = b"ax=1&ay=0&az=0&bx=0&by=2&bz=0&cx=0&cy=0&cz=3"
    compare(apps, lane_answers=False, method=method, query=query, **post(EXAMPLE))


def test_a_root_path_goes_to_the_stack(apps) -> None:  # type: ignore[no-untyped-def]
    compare(apps, lane_answers=False, root_path="/calc", **post(EXAMPLE))


@pytest.mark.parametrize("path", ["/api/normals", "/api/normal/", "/api/normal.csv", "/"])
def test_other_paths_go_to_the_stack(apps, path: str) -> None:  # type: ignore[no-untyped-def]
    compare(apps, lane_answers=False, path=path, **post(EXAMPLE))


def test_the_lane_is_outermost_of_our_middleware() -> None:
    app = create_app()
    assert app.user_middleware[0].cls is NormalFastLane
