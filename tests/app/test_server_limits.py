"""The server's limits: the same uvicorn options in the Dockerfile's CMD, in `make run` and on the
operators' page (docs/operators.md, with every MESH_ setting), read by uvicorn's own command line,
and what they do on a real server (a huge header, the connection cap, an idle keep-alive
connection)."""

from __future__ import annotations

import json
import re
import shlex
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import pytest

from tests.paths import ROOT

#: What each option must be (docs/operators.md, "The server's limits").
EXPECTED = {
    "http": "h11",
    "h11_max_incomplete_event_size": 16384,
    "timeout_keep_alive": 5,
    "limit_concurrency": 100,
    "backlog": 256,
    "timeout_graceful_shutdown": 8,
}


def dockerfile_command() -> list[str]:
    text = (ROOT / "Dockerfile").read_text()
    found = re.search(r"^CMD (\[.*?\])\s*$", text.replace("\\\n", " "), re.MULTILINE)
    assert found, "the Dockerfile has a CMD in exec form"
    command: list[str] = json.loads(found.group(1))
    return command


def makefile_limits() -> list[str]:
    text = (ROOT / "Makefile").read_text().replace("\\\n", " ")
    found = re.search(r"^SERVER_LIMITS := (.*)$", text, re.MULTILINE)
    assert found, "the Makefile sets SERVER_LIMITS"
    return shlex.split(found.group(1))


def uvicorn_params(arguments: list[str]) -> dict[str, Any]:
    """The options as uvicorn's own command line reads them."""
    import uvicorn.main  # noqa: F401 (the module, not the function of the same name)

    command = sys.modules["uvicorn.main"].main
    return dict(command.make_context("uvicorn", list(arguments)).params)


def test_the_image_and_make_run_set_the_same_limits() -> None:
    command = dockerfile_command()
    assert command[:2] == ["uvicorn", "app.main:app"]
    image = uvicorn_params(command[1:])
    local = uvicorn_params(["app.main:app", *makefile_limits()])
    for name, value in EXPECTED.items():
        assert image[name] == value, name
        assert local[name] == value, name
    assert (image["host"], image["port"]) == ("0.0.0.0", 8000)


OPERATORS = ROOT / "docs" / "operators.md"


def operators_table(heading: str) -> dict[str, str]:
    """The first two cells of each row of the table under ``## heading`` on the operators' page,
    the first without its backticks (``| `MESH_WORKERS` | 2 | ... |`` -> ``MESH_WORKERS: 2``)."""
    text = OPERATORS.read_text(encoding="utf-8")
    found = re.search(rf"^## {re.escape(heading)}\n(.*?)(?=^## |\Z)", text, re.M | re.S)
    assert found, f"docs/operators.md has a section {heading!r}"
    rows = re.findall(r"^\| `([^|]+)` \| ([^|]*) \|", found.group(1), re.M)
    assert rows, f"the section {heading!r} has a table"
    return {name.strip("` "): cell.strip() for name, cell in rows}


def test_the_operators_page_lists_the_same_limits() -> None:
    options = shlex.split(" ".join(operators_table("The server's limits")))
    documented = uvicorn_params(["app.main:app", *options])
    assert documented == uvicorn_params(["app.main:app", *makefile_limits()])
    for name, value in EXPECTED.items():
        assert documented[name] == value, name


def test_the_operators_page_lists_every_setting_with_its_default() -> None:
    from pydantic_core import PydanticUndefined

    from app.config import Settings

    table = operators_table("Settings")
    names = {f"MESH_{name.upper()}": field for name, field in Settings.model_fields.items()}
    assert set(table) == set(names)
    for variable, field in names.items():
        default = field.default
        if default is None or default is PydanticUndefined:  # unset, or worked out at start
            continue
        expected = str(default).lower() if isinstance(default, bool) else f"{default:g}"
        assert table[variable] == expected, variable


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


@pytest.fixture(scope="module")
def server() -> Iterator[int]:
    """uvicorn with the Makefile's limits, but a cap of 3 connections (so that it is reached)."""
    port = free_port()
    limits = makefile_limits()
    limits[limits.index("--limit-concurrency") + 1] = "3"
    process = subprocess.Popen(
        [sys.executable, "-m", "uvicorn", "app.main:app", "--port", str(port), *limits],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        for _ in range(600):
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=1):
                    break
            except OSError:
                if process.poll() is not None:
                    pytest.fail("uvicorn exited")
                time.sleep(0.1)
        yield port
    finally:
        process.terminate()
        process.wait(timeout=30)


def request(port: int, data: bytes, timeout: float = 20) -> bytes:
    """Send ``data`` on a new connection; everything the server answers until it closes."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as connection:
        try:
            connection.sendall(data)
        except OSError:  # the server closed while we were still sending
            return b""
        answer = b""
        try:
            while chunk := connection.recv(65536):
                answer += chunk
        except ConnectionResetError:
            pass
        return answer


HEAD = b"HEAD / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"


def test_a_normal_request_is_answered(server: int) -> None:
    assert request(server, HEAD + b"\r\n").startswith(b"HTTP/1.1 200")


def test_a_huge_header_is_refused(server: int) -> None:
    answer = request(server, HEAD + b"X-Big: " + b"a" * 4_000_000 + b"\r\n\r\n")
    assert not answer.startswith(b"HTTP/1.1 200"), answer[:80]


def test_beyond_the_connection_cap_the_answer_is_503(server: int) -> None:
    idle = [socket.create_connection(("127.0.0.1", server), timeout=20) for _ in range(3)]
    try:
        answer = request(server, HEAD + b"\r\n")
        assert answer.startswith(b"HTTP/1.1 503"), answer[:80]
    finally:
        for connection in idle:
            connection.close()


def test_an_idle_keep_alive_connection_is_closed(server: int) -> None:
    # After its answer, a keep-alive connection that sends nothing is closed by the server
    # (after --timeout-keep-alive, 5 s); the client waits up to 30 s for that.
    with socket.create_connection(("127.0.0.1", server), timeout=30) as connection:
        connection.sendall(b"HEAD / HTTP/1.1\r\nHost: x\r\n\r\n")
        first = connection.recv(65536)
        assert first.startswith(b"HTTP/1.1 200")
        rest = b""
        while chunk := connection.recv(65536):  # b"": the server closed the connection
            rest += chunk
        assert rest == b""
