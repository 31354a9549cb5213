"""POST /api/normals: a large batch is a heavy job (admitted, run in a worker process), a small
one is answered at once; many large batches at once leave the pages answering and the ones
beyond the queue get a 503 with Retry-After."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any

import httpx
import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.calculator import batch
from app.config import Settings
from app.main import create_app
from tests.conftest import assert_error
from tests.paths import ROOT

JSON = {"content-type": "application/json"}
PATIENCE_S = 120.0


def body_of(count: int, decimals: int = 3) -> bytes:
    """``count`` triangles with ``decimals`` digits after the point (100,000 with 3: ~8.5 MB)."""
    rng = np.random.default_rng(35)
    triangles = np.round(rng.uniform(-100, 100, size=(count, 3, 3)), decimals)
    return json.dumps({"triangles": triangles.tolist()}, separators=(",", ":")).encode()


@pytest.fixture
def counted() -> Iterator[tuple[TestClient, list[int]]]:
    """A client whose heavy jobs run in its threads, and the estimates of the jobs it ran."""
    app = create_app(settings=Settings(in_process=True))
    estimates: list[int] = []
    run = app.state.jobs.run

    async def counting(request: Any, estimate: int, function: Any, *args: Any) -> Any:
        estimates.append(estimate)
        return await run(request, estimate, function, *args)

    app.state.jobs.run = counting
    with TestClient(app, raise_server_exceptions=False) as client:
        yield client, estimates


def test_a_small_batch_is_no_job(counted: tuple[TestClient, list[int]]) -> None:
    client, estimates = counted
    one = [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]]
    answer = client.post("/api/normals", json={"triangles": one})
    assert answer.status_code == 200
    assert answer.json()["results"][0]["normal"] == [0.0, 0.0, 1.0]
    assert estimates == []


def test_a_large_batch_is_a_job_charged_for_its_triangles(
    counted: tuple[TestClient, list[int]],
) -> None:
    client, estimates = counted
    body = body_of(2_000)
    assert len(body) > batch.INLINE_BYTES
    answer = client.post("/api/normals", content=body, headers=JSON)
    assert answer.status_code == 200, answer.text[:300]
    assert answer.headers["content-type"] == "application/json"
    assert len(answer.json()["results"]) == 2_000
    assert estimates == [2_000 * batch.BYTES_PER_TRIANGLE + 2 * len(body)]


def test_a_bad_large_batch_is_refused_as_a_small_one_is(
    counted: tuple[TestClient, list[int]],
) -> None:
    client, estimates = counted
    body = body_of(2_000)[:-1] + b',"swap_winding":"yes"}'
    answer = client.post("/api/normals", content=body, headers=JSON)
    assert_error(answer, 422, "swap_winding")
    assert len(estimates) == 1


def test_a_batch_beyond_the_whole_budget_is_a_413() -> None:
    app = create_app(settings=Settings(in_process=True, memory_budget_mb=10))
    body = body_of(8_000)
    needed = f"about {batch.estimate(body) / 2**20:.0f} MB"
    assert needed == "about 17 MB"
    with TestClient(app, raise_server_exceptions=False) as client:
        answer = client.post("/api/normals", content=body, headers=JSON)
    assert_error(answer, 413, "triangles", "This batch", needed, "(10 MB)", "split it")


def test_the_estimate_counts_at_most_the_limit() -> None:
    huge = b'{"triangles":[' + b"[[0,0,0],[0,0,0],[0,0,0]]," * 200_000 + b"]}"
    most = batch.BYTES_PER_TRIANGLE * 100_000 + 2 * len(huge)
    assert batch.estimate(huge) == most


# --- on a real server: twelve full batches at once ----------------------------------------------


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """uvicorn with 2 worker processes, 2 places in the queue and a minute's wait there."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    log = (tmp_path_factory.mktemp("server") / "server.log").open("wb")
    env = {
        **os.environ,
        "MESH_WORKERS": "2",
        "MESH_QUEUE_LENGTH": "2",
        "MESH_QUEUE_SECONDS": "60",
    }
    command = [sys.executable, "-m", "uvicorn", "app.main:app", "--port", str(port)]
    process = subprocess.Popen(command, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + PATIENCE_S
        while True:
            assert process.poll() is None, "uvicorn exited"
            assert time.monotonic() < deadline, "the server did not start"
            try:
                # A batch over the inline size: answered once a worker is ready.
                if httpx.post(url + "/api/normals", content=body_of(500), headers=JSON).is_success:
                    break
            except httpx.TransportError:
                time.sleep(0.1)
        yield url
    finally:
        process.terminate()
        process.wait(30)
        log.close()


def test_pages_answer_while_twelve_full_batches_arrive(server: str) -> None:
    body = body_of(100_000)
    answers: list[httpx.Response] = []

    def send() -> None:
        answers.append(httpx.post(server + "/api/normals", content=body, headers=JSON, timeout=120))

    senders = [threading.Thread(target=send) for _ in range(12)]
    for sender in senders:
        sender.start()
    slowest = 0.0
    while any(sender.is_alive() for sender in senders):
        start = time.monotonic()
        assert httpx.get(server + "/", timeout=30).status_code == 200
        slowest = max(slowest, time.monotonic() - start)
        time.sleep(0.05)
    for sender in senders:
        sender.join()
    statuses = sorted(answer.status_code for answer in answers)
    print(f"slowest page {slowest:.3f} s; statuses {statuses}")
    assert slowest < 2, slowest
    assert set(statuses) <= {200, 503} and statuses.count(200) >= 2, statuses
    assert 503 in statuses, statuses  # 2 running and 2 waiting at most: the rest is refused
    for answer in answers:
        if answer.status_code == 503:
            assert int(answer.headers["retry-after"]) > 0
            assert set(answer.json()) == {"error", "field"}
        else:
            assert len(answer.json()["results"]) == 100_000
