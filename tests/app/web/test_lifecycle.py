"""The server's life around its jobs, under a real ``uvicorn`` (its plain command, none of the
Makefile's flags): a stop signal ends the running jobs at once, a killed server takes its
workers with it, clients that leave mid-body cost one log line at most, and a job past its
time is answered as such while its worker lives on."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import suppress
from pathlib import Path
from typing import Any
from urllib.parse import quote

import httpx
import pytest
from fastapi.testclient import TestClient

from app.config import Settings
from app.main import create_app
from app.mesh import work
from app.web.jobs import SHUTTING_DOWN
from tests.app import jobhooks
from tests.conftest import assert_error
from tests.meshes import CUBE_OBJ
from tests.paths import ROOT

#: The longest a test waits for something that must happen; it only bounds a failure.
PATIENCE_S = 120
#: How soon a stopped or killed server must be gone, with its workers.
GONE_WITHIN_S = 10


def eventually(condition: Callable[[], bool], seconds: float = PATIENCE_S) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "what the test waited for never happened"
        time.sleep(0.05)


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, ended but not yet reaped, does not)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(") ", 1)[1][0] != "Z"
    except FileNotFoundError:
        return False


class Server:
    """``uvicorn tests.app.jobserver:app`` (the report held by :func:`jobhooks.held` until a
    ``release`` file appears next to the upload's name), one worker, its log in a file."""

    def __init__(self, folder: Path, **env: str) -> None:
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            self.port = probe.getsockname()[1]
        self.url = f"http://127.0.0.1:{self.port}"
        self.log = folder / "server.log"
        command = [sys.executable, "-m", "uvicorn", "tests.app.jobserver:app"]
        command += ["--host", "127.0.0.1", "--port", str(self.port)]
        settings = {"MESH_WORKERS": "1", "MESH_QUEUE_SECONDS": "60", **env}
        with self.log.open("wb") as log:
            self.process = subprocess.Popen(
                command,
                cwd=ROOT,
                stdout=log,
                stderr=subprocess.STDOUT,
                env={**os.environ, **settings},
            )
        eventually(self.answers)

    def answers(self) -> bool:
        assert self.process.poll() is None, self.log.read_text()
        try:
            return httpx.get(self.url + "/healthz").status_code == 200
        except httpx.TransportError:
            return False

    def upload(self, folder: Path) -> httpx.Response:
        """A cube, named as if in ``folder`` (where the held report looks for ``release``)."""
        with httpx.Client(base_url=self.url, timeout=PATIENCE_S) as client:
            return client.post(
                "/api/mesh", params={"filename": str(folder / "cube.obj")}, content=CUBE_OBJ
            )

    def held_job(self, folder: Path) -> tuple[threading.Thread, list[httpx.Response], int]:
        """An upload whose job runs until released, in a thread: the thread, where its answer
        goes, and the worker's process id once the job has started."""
        folder.mkdir(exist_ok=True)
        answers: list[httpx.Response] = []

        def send() -> None:
            with suppress(httpx.TransportError):  # a killed server does not answer
                answers.append(self.upload(folder))

        thread = threading.Thread(target=send, daemon=True)
        thread.start()
        eventually((folder / "started").exists)
        return thread, answers, int((folder / "started").read_text())

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(PATIENCE_S)


@pytest.fixture
def server(tmp_path: Path) -> Iterator[Server]:
    running = Server(tmp_path)
    try:
        yield running
    finally:
        running.close()


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="reads /proc")
def test_a_stop_signal_ends_a_running_job_at_once(server: Server, tmp_path: Path) -> None:
    """SIGTERM to a plain ``uvicorn app.main:app`` (no graceful-shutdown flag) with a job that
    would run for ever: its client gets a 503 saying the server restarts, and the server and
    its worker are gone within seconds."""
    thread, answers, worker = server.held_job(tmp_path / "job")
    server.process.send_signal(signal.SIGTERM)
    server.process.wait(GONE_WITHIN_S)
    thread.join(GONE_WITHIN_S)
    assert answers, "the client got no answer"
    assert_error(answers[0], 503, None, "restarting")
    assert answers[0].json()["error"] == SHUTTING_DOWN
    eventually(lambda: not alive(worker), GONE_WITHIN_S)
    assert not (tmp_path / "job" / "finished").exists()


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="reads /proc")
def test_a_killed_server_takes_its_busy_worker_with_it(server: Server, tmp_path: Path) -> None:
    _, _, worker = server.held_job(tmp_path / "job")
    server.process.kill()
    server.process.wait(GONE_WITHIN_S)
    eventually(lambda: not alive(worker), GONE_WITHIN_S)


def vanish(port: int, body: bytes, content_type: str) -> None:
    """Send a request's head and the start of its body, then leave."""
    head = (
        f"POST /api/mesh?filename=gone.obj HTTP/1.1\r\nHost: x\r\nContent-Type: {content_type}"
        f"\r\nContent-Length: {len(body) + 100_000}\r\n\r\n"
    )
    with socket.create_connection(("127.0.0.1", port), timeout=PATIENCE_S) as connection:
        connection.sendall(head.encode() + body)
        time.sleep(0.05)  # the server starts reading the body


def test_clients_that_leave_mid_body_leave_no_traceback(server: Server, tmp_path: Path) -> None:
    part = b'--B\r\nContent-Disposition: form-data; name="file"; filename="a.obj"\r\n\r\n'
    for _ in range(10):
        vanish(server.port, CUBE_OBJ.encode(), "application/octet-stream")
        vanish(server.port, part + CUBE_OBJ.encode(), "multipart/form-data; boundary=B")
    (tmp_path / "fine").mkdir()
    (tmp_path / "fine" / "release").touch()
    answer = server.upload(tmp_path / "fine")  # and the server goes on
    assert answer.status_code == 200 and answer.json()["faces"] == 12
    log = server.log.read_text()
    assert "Traceback" not in log and "ClientDisconnect" not in log, log
    assert len(log.splitlines()) < 20, log


def test_clients_that_leave_right_after_their_body_cost_no_worker(
    server: Server, tmp_path: Path
) -> None:
    """Each job (which would run for ever) is stopped, however early its client left, and the
    one worker lives on: every job, and the next upload, ran in the same process."""
    folders = [tmp_path / f"gone{number}" for number in range(5)]
    for folder in folders:
        folder.mkdir()
        head = (
            f"POST /api/mesh?filename={quote(str(folder / 'cube.obj'))} HTTP/1.1\r\nHost: x\r\n"
            f"Content-Length: {len(CUBE_OBJ)}\r\n\r\n{CUBE_OBJ}"
        )
        with socket.create_connection(("127.0.0.1", server.port), timeout=PATIENCE_S) as client:
            client.sendall(head.encode())
    (tmp_path / "fine").mkdir()
    (tmp_path / "fine" / "release").touch()
    answer = server.upload(tmp_path / "fine")
    assert answer.status_code == 200 and answer.json()["faces"] == 12
    pids = {
        (folder / "started").read_text()
        for folder in [*folders, tmp_path / "fine"]
        if (folder / "started").exists()
    }
    assert len(pids) == 1, "a worker was replaced"
    assert not any((folder / "finished").exists() for folder in folders)


@pytest.fixture
def held_with_a_time_limit(monkeypatch: pytest.MonkeyPatch) -> Iterator[TestClient]:
    """The app with one real worker, jobs of 1 s at most, and the report held until released."""
    monkeypatch.setattr(work, "report", jobhooks.held)
    settings = Settings(workers=1, queue_seconds=30, job_seconds=1)
    with TestClient(create_app(settings=settings), raise_server_exceptions=False) as client:
        yield client


def post(client: TestClient, folder: Path) -> Any:
    folder.mkdir(exist_ok=True)
    return client.post("/api/mesh", params={"filename": str(folder / "cube.obj")}, content=CUBE_OBJ)


def test_a_job_past_its_time_is_a_422_and_its_worker_lives_on(
    held_with_a_time_limit: TestClient, tmp_path: Path
) -> None:
    slow = post(held_with_a_time_limit, tmp_path / "slow")
    assert_error(slow, 422, "file", "took longer than the 1 s", "send a smaller file")
    assert not (tmp_path / "slow" / "finished").exists()
    (tmp_path / "quick").mkdir()
    (tmp_path / "quick" / "release").touch()
    quick = post(held_with_a_time_limit, tmp_path / "quick")
    assert quick.status_code == 200 and quick.json()["faces"] == 12
    same = (tmp_path / "slow" / "started").read_text() == (
        tmp_path / "quick" / "started"
    ).read_text()
    assert same, "the worker was replaced"


def tagged(tag: str) -> list[int]:
    """The live processes whose environment holds ``MESH_TEST_TAG=tag``: a server started with
    it, and every process it started (a worker that outlived it included)."""
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{entry}/environ", "rb") as environ:
                if f"MESH_TEST_TAG={tag}".encode() not in environ.read().split(b"\0"):
                    continue
        except OSError:  # ended meanwhile, or not ours
            continue
        if alive(int(entry)):
            found.append(int(entry))
    return found


def workers_of(tag: str) -> list[int]:
    """The worker processes among :func:`tagged`'s."""
    found = []
    for pid in tagged(tag):
        with suppress(OSError), open(f"/proc/{pid}/cmdline", "rb") as cmdline:
            if b"mesh_normal.workers" in cmdline.read():
                found.append(pid)
    return found


@pytest.mark.skipif(not os.path.exists("/proc/self/environ"), reason="reads /proc")
@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
@pytest.mark.parametrize("moment", ["first worker", "first page", "0.5 s", "ready"])
def test_a_server_stopped_at_any_moment_leaves_no_process(
    tmp_path: Path, number: signal.Signals, moment: str
) -> None:
    """SIGTERM or SIGINT to a plain ``uvicorn app.main:app`` as its first worker process
    starts (before the first page), just after its first page, half a second later (the
    workers importing and warming), or once they are ready: the server and every process it
    started are gone within 5 s."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    tag = f"{os.getpid()}-{time.monotonic_ns()}"
    command = [sys.executable, "-m", "uvicorn", "app.main:app", "--port", str(port)]
    env = {**os.environ, "MESH_WORKERS": "2", "MESH_TEST_TAG": tag}
    with (tmp_path / "server.log").open("wb") as log:
        process = subprocess.Popen(
            [*command, "--host", "127.0.0.1"],
            cwd=ROOT,
            stdout=log,
            stderr=subprocess.STDOUT,
            env=env,
        )
    try:

        def answers() -> bool:
            assert process.poll() is None, (tmp_path / "server.log").read_text()
            try:
                return httpx.get(f"http://127.0.0.1:{port}/").status_code == 200
            except httpx.TransportError:
                return False

        if moment == "first worker":
            eventually(lambda: bool(workers_of(tag)))
        else:
            eventually(answers)
        if moment == "0.5 s":
            time.sleep(0.5)
        if moment == "ready":  # the workers (two, and one to spare) are ready: a job runs
            answer = httpx.post(
                f"http://127.0.0.1:{port}/api/mesh",
                params={"filename": "cube.obj"},
                content=CUBE_OBJ,
                timeout=PATIENCE_S,
            )
            assert answer.status_code == 200
            eventually(lambda: len(workers_of(tag)) == 3)
        assert tagged(tag)
        process.send_signal(number)
        stopped = time.monotonic()
        process.wait(GONE_WITHIN_S)
        eventually(lambda: not tagged(tag), 5 - (time.monotonic() - stopped))
    finally:
        for member in tagged(tag):
            with suppress(ProcessLookupError):
                os.kill(member, signal.SIGKILL)
        with suppress(ProcessLookupError):
            process.kill()


@pytest.mark.skipif(not os.path.exists("/proc/self/environ"), reason="reads /proc")
def test_a_job_that_does_not_stop_costs_the_next_job_no_wait(tmp_path: Path) -> None:
    """A client leaves while its job runs a loop that ignores the request to stop (as a native
    loop does): its worker is killed after the grace, and the next upload is a 200 from the
    worker that was kept to spare, ready before the kill (no worker had to start for it)."""
    tag = f"{os.getpid()}-{time.monotonic_ns()}"
    server = Server(tmp_path, MESH_TEST_TAG=tag)
    try:
        eventually(lambda: len(workers_of(tag)) == 2)  # one worker, one to spare
        (tmp_path / "fine").mkdir()
        (tmp_path / "fine" / "release").touch()
        assert server.upload(tmp_path / "fine").status_code == 200  # a worker is ready
        ready = set(workers_of(tag))
        gone = tmp_path / "gone"
        gone.mkdir()
        (gone / "stubborn").touch()
        head = (
            f"POST /api/mesh?filename={quote(str(gone / 'cube.obj'))} HTTP/1.1\r\nHost: x\r\n"
            f"Content-Length: {len(CUBE_OBJ)}\r\n\r\n{CUBE_OBJ}"
        )
        with socket.create_connection(("127.0.0.1", server.port), timeout=PATIENCE_S) as client:
            client.sendall(head.encode())
            eventually((gone / "started").exists)
        stubborn = int((gone / "started").read_text())
        eventually(lambda: not alive(stubborn))  # killed after the grace
        (tmp_path / "next").mkdir()
        (tmp_path / "next" / "release").touch()
        begun = time.monotonic()
        answer = server.upload(tmp_path / "next")
        seconds = time.monotonic() - begun
        assert answer.status_code == 200 and answer.json()["faces"] == 12
        next_pid = int((tmp_path / "next" / "started").read_text())
        assert next_pid in ready - {stubborn}, "the next job waited for a new worker"
        print(f"the next upload after a killed worker: {seconds * 1000:.0f} ms")
    finally:
        server.close()
        for member in tagged(tag):
            with suppress(ProcessLookupError):
                os.kill(member, signal.SIGKILL)
