"""The server as several uvicorn workers (``uvicorn app.main:app --workers 2``): pages,
``/healthz`` and uploads through it, and each worker's bound on heavy jobs (a 503 with
Retry-After beyond it) while the pages keep answering.

The app is ``tests.app.jobserver`` (the report held by :func:`tests.app.jobhooks.held` until
a ``release`` file appears next to the upload's name), one heavy-job slot a worker and no
queue, so that the bound is reached on purpose.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest

from tests.paths import ROOT

CUBE_OBJ = (
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
)
PATIENCE_S = 120.0


def eventually(condition: Callable[[], bool], seconds: float = PATIENCE_S) -> None:
    import time

    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    logged = tmp_path_factory.mktemp("server") / "server.log"
    log = logged.open("wb")
    command = [sys.executable, "-m", "uvicorn", "tests.app.jobserver:app"]
    command += ["--host", "127.0.0.1", "--port", str(port), "--workers", "2"]
    env = {**os.environ, "MESH_WORKERS": "1", "MESH_QUEUE_SECONDS": "0", "MESH_QUEUE_LENGTH": "0"}
    process = subprocess.Popen(command, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env)
    url = f"http://127.0.0.1:{port}"

    def answers() -> bool:
        assert process.poll() is None, logged.read_text()
        try:
            return httpx.get(url + "/healthz").status_code == 200
        except httpx.TransportError:
            return False

    try:
        eventually(answers)
        yield url
    finally:
        process.terminate()
        process.wait(30)
        log.close()


def upload(url: str, folder: Path) -> httpx.Response:
    """A cube, named as if in ``folder`` (where the held report looks for ``release``)."""
    with httpx.Client(base_url=url, timeout=PATIENCE_S) as client:
        return client.post(
            "/api/mesh", params={"filename": str(folder / "cube.obj")}, content=CUBE_OBJ.encode()
        )


def test_pages_health_and_an_upload_answer(server: str, tmp_path: Path) -> None:
    health = httpx.get(server + "/healthz")
    assert health.status_code == 200
    assert health.headers["cache-control"] == "no-store"
    found = health.json()
    assert found["status"] == "ok" and found["jobs"]["slots"] == 1
    assert httpx.head(server + "/healthz").status_code == 200
    assert httpx.get(server + "/").status_code == 200
    (tmp_path / "release").touch()
    answer = upload(server, tmp_path)
    assert answer.status_code == 200 and answer.json()["faces"] == 12


def test_each_worker_bounds_its_heavy_jobs_and_pages_still_answer(
    server: str, tmp_path: Path
) -> None:
    """Three held jobs at once on two workers of one slot each: at least one is a 503 with
    Retry-After, the others run; pages and /healthz answer meanwhile; released, they finish."""
    folders = [tmp_path / f"job{number}" for number in range(3)]
    answers: dict[int, httpx.Response] = {}

    def send(number: int) -> None:
        answers[number] = upload(server, folders[number])

    for folder in folders:
        folder.mkdir()
    threads = [threading.Thread(target=send, args=(number,)) for number in range(3)]
    for thread in threads:
        thread.start()
    try:
        # Each job either started (held, in a worker's slot) or was refused at once.
        eventually(
            lambda: all((f / "started").exists() or i in answers for i, f in enumerate(folders))
        )
        refused = [answers[i] for i in answers if answers[i].status_code == 503]
        assert refused, {i: answers[i].status_code for i in answers}
        assert all(answer.headers["retry-after"].isdigit() for answer in refused)
        assert all(answer.json()["error"].startswith("The server is busy") for answer in refused)
        running = [f for f in folders if (f / "started").exists()]
        assert 1 <= len(running) <= 2  # one slot in each of the two workers
        assert httpx.get(server + "/", timeout=10).status_code == 200
        assert httpx.get(server + "/healthz", timeout=10).status_code == 200
    finally:
        for folder in folders:
            (folder / "release").touch()
        for thread in threads:
            thread.join(PATIENCE_S)
    finished = [answers[i] for i, f in enumerate(folders) if (f / "started").exists()]
    assert finished and all(a.status_code == 200 and a.json()["faces"] == 12 for a in finished)
