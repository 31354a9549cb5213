"""app/mesh/work.py run as heavy jobs: in worker processes (crashes, memory, stalls,
cancellation) and, in-process, against the job slots and the memory budget."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any
from urllib.parse import quote

import httpx
import pytest
from fastapi.testclient import TestClient

from app.config import Settings
from app.main import create_app
from app.mesh import work
from app.web.jobs import BUSY, NO_MEMORY
from tests.app import jobhooks
from tests.conftest import assert_error
from tests.meshes import CUBE_OBJ
from tests.paths import ROOT

#: The longest a test waits for something that must happen (a marker file, a process's end);
#: it only bounds a failure, it is never what a test asserts.
PATIENCE_S = 120


def eventually(condition: Callable[[], bool]) -> None:
    deadline = time.monotonic() + PATIENCE_S
    while not condition():
        assert time.monotonic() < deadline, "what the test waited for never happened"
        time.sleep(0.02)


def post(client: TestClient | httpx.Client, path: str, name: str = "cube.obj", **params: str):  # type: ignore[no-untyped-def]
    return client.post(path, params=params, files={"file": (name, CUBE_OBJ.encode())})


@pytest.fixture(scope="module")
def pool_client() -> Iterator[TestClient]:
    """The app with its real worker processes (two), as ``uvicorn app.main:app`` runs it."""
    settings = Settings(workers=2, queue_seconds=30)
    with TestClient(create_app(settings=settings), raise_server_exceptions=False) as client:
        yield client


# --- in worker processes ------------------------------------------------------------------------


@pytest.mark.parametrize("hook", [jobhooks.abort, jobhooks.exhaust])
def test_a_job_past_its_worker_s_memory_is_a_413_and_the_next_request_works(
    pool_client: TestClient, monkeypatch: pytest.MonkeyPatch, hook: Callable[..., Any]
) -> None:
    """A MemoryError, or an abort (as pydantic-core's when an allocation fails), in a worker
    under its memory cap: a 413 blaming the file (the same file would fail again), not a 503
    asking to try again; the server lives."""
    with monkeypatch.context() as patch:
        patch.setattr(work, "report", hook)
        response = post(pool_client, "/api/mesh")
    assert_error(response, 413, "file", "needs more memory than the", "send a smaller file")
    again = post(pool_client, "/api/mesh")
    assert again.status_code == 200 and again.json()["faces"] == 12


def test_a_worker_killed_from_outside_is_a_503_and_the_next_request_works(
    pool_client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Killed as by the system's out-of-memory killer: the server ran out of memory, not the
    file's cap; try again later."""
    with monkeypatch.context() as patch:
        patch.setattr(work, "report", jobhooks.killed)
        response = post(pool_client, "/api/mesh")
    assert_error(response, 503, None, "ran out of memory")
    assert response.json()["error"] == NO_MEMORY
    assert int(response.headers["retry-after"]) > 0
    again = post(pool_client, "/api/mesh")
    assert again.status_code == 200 and again.json()["faces"] == 12


def test_the_page_says_the_file_needs_more_memory(
    pool_client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    with monkeypatch.context() as patch:
        patch.setattr(work, "page", jobhooks.abort)
        response = post(pool_client, "/mesh")
    assert response.status_code == 413
    assert "needs more memory than the" in response.context["error"].error  # type: ignore[attr-defined]
    assert post(pool_client, "/mesh").status_code == 200


def test_pages_answer_while_a_job_holds_its_gil(
    pool_client: TestClient, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A job spinning in pure Python (in its worker) does not hold up GET /: the page answers
    before the job is let go."""
    monkeypatch.setattr(work, "report", jobhooks.held)
    answers: list[httpx.Response] = []
    heavy = threading.Thread(
        target=lambda: answers.append(post(pool_client, "/api/mesh", str(tmp_path / "cube.obj")))
    )
    heavy.start()
    try:
        eventually((tmp_path / "started").exists)
        for _ in range(5):
            assert pool_client.get("/").status_code == 200
            assert pool_client.get("/api/normal?ax=0&ay=0&az=0&bx=1&by=0&bz=0&cx=0&cy=1&cz=0")
        assert heavy.is_alive() and not (tmp_path / "finished").exists()
    finally:
        (tmp_path / "release").touch()
        heavy.join()
    assert answers[0].status_code == 200 and answers[0].json()["faces"] == 12


@pytest.fixture
def server(tmp_path: Path) -> Iterator[str]:
    """``uvicorn tests.app.jobserver:app`` (the report held by jobhooks.held), its address."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    log = (tmp_path / "server.log").open("wb")
    process = subprocess.Popen(
        [sys.executable, "-m", "uvicorn", "tests.app.jobserver:app", "--port", str(port)],
        cwd=ROOT,
        stdout=log,
        stderr=subprocess.STDOUT,
        env={**os.environ, "MESH_WORKERS": "1", "MESH_QUEUE_SECONDS": "60"},
    )
    url = f"http://127.0.0.1:{port}"

    def answers() -> bool:
        assert process.poll() is None, (tmp_path / "server.log").read_text()
        try:
            return httpx.get(url + "/").status_code == 200
        except httpx.TransportError:
            return False

    try:
        eventually(answers)
        yield url
    finally:
        process.terminate()
        process.wait(30)
        log.close()


def test_a_client_that_hangs_up_stops_its_job(server: str, tmp_path: Path) -> None:
    """The job stops when its client leaves (it would otherwise spin until released, then
    write ``finished``), and its worker lives on: the next job runs in the same process, with
    no new worker to warm up."""
    jobs, later = tmp_path / "jobs", tmp_path / "later"
    jobs.mkdir()
    later.mkdir()
    (later / "release").touch()
    host, port = server.removeprefix("http://").split(":")
    body = CUBE_OBJ.encode()
    head = (
        f"POST /api/mesh?filename={quote(str(jobs / 'cube.obj'))} HTTP/1.1\r\nHost: {host}\r\n"
        f"Content-Type: application/octet-stream\r\nContent-Length: {len(body)}\r\n\r\n"
    )
    with socket.create_connection((host, int(port))) as client:
        client.sendall(head.encode() + body)
        eventually((jobs / "started").exists)
        pid = int((jobs / "started").read_text())
    # The client is gone: the one worker is free again only if its job stopped.
    with httpx.Client(base_url=server, timeout=PATIENCE_S) as client:
        again = client.post("/api/mesh", params={"filename": str(later / "cube.obj")}, content=body)
    assert again.status_code == 200 and again.json()["faces"] == 12
    assert not (jobs / "finished").exists()
    assert int((later / "started").read_text()) == pid  # the same worker ran it


# --- in-process: the job slots and the memory budget -------------------------------------------


@pytest.fixture
def held_in_process(
    monkeypatch: pytest.MonkeyPatch,
) -> Iterator[tuple[threading.Event, threading.Event]]:
    """Jobs that wait for the test: (started, release), for report and page alike."""
    started, release = threading.Event(), threading.Event()
    report, page = work.report, work.page

    def wait(real: Callable[..., Any]) -> Callable[..., Any]:
        def waiting(*args: Any) -> Any:
            started.set()
            release.wait(PATIENCE_S)
            return real(*args)

        return waiting

    monkeypatch.setattr(work, "report", wait(report))
    monkeypatch.setattr(work, "page", wait(page))
    yield started, release
    release.set()


@pytest.mark.parametrize("path", ["/api/mesh", "/mesh"])
def test_full_job_slots_are_a_503_with_retry_after(
    held_in_process: tuple[threading.Event, threading.Event], path: str
) -> None:
    started, release = held_in_process
    settings = Settings(in_process=True, workers=1, queue_seconds=0)
    with TestClient(create_app(settings=settings), raise_server_exceptions=False) as client:
        first: list[httpx.Response] = []
        heavy = threading.Thread(target=lambda: first.append(post(client, path)))
        heavy.start()
        assert started.wait(PATIENCE_S)
        busy = post(client, path)
        assert client.get("/").status_code == 200  # pages never wait for mesh jobs
        release.set()
        heavy.join()
    assert first[0].status_code == 200
    assert busy.status_code == 503 and int(busy.headers["retry-after"]) > 0
    if path == "/mesh":
        assert busy.context["error"].error == BUSY  # type: ignore[attr-defined]
    else:
        assert_error(busy, 503, None, "busy")


@pytest.mark.parametrize("path", ["/api/mesh", "/mesh"])
def test_a_file_beyond_the_whole_budget_is_a_413(path: str) -> None:
    """64 MB for every job plus 6 bytes a byte of OBJ: an 8 MB OBJ needs about 110 MB."""
    big = CUBE_OBJ + "# padding\n" * 800_000
    settings = Settings(in_process=True, memory_budget_mb=100)
    with TestClient(create_app(settings=settings), raise_server_exceptions=False) as client:
        refused = client.post(path, files={"file": ("big.obj", big.encode())})
        fine = post(client, path)
    assert fine.status_code == 200
    if path == "/mesh":
        assert refused.status_code == 413
        assert "more than this server ever gives one file" in refused.text
    else:
        assert_error(refused, 413, "file", "110 MB", "100 MB", "smaller file")
