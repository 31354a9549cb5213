"""The hostile uploads of ``tests/data/hostile/`` against the real server (uvicorn with its
worker processes): each is answered within seconds with the status it deserves, the server's
memory stays bounded, and the first page keeps answering meanwhile.

Each file is a few kilobytes that, unguarded, expand into gigabytes, minutes or a crash;
:data:`CORPUS` says where each goes and what the answer must be.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass

import httpx
import psutil
import pytest

from benchmarks.hostile import Server, Watch
from tests.conftest import assert_error
from tests.paths import ROOT

HOSTILE = ROOT / "tests" / "data" / "hostile"
#: Seconds the server may take to answer one hostile upload (its job's time limit is lower).
ANSWER_SECONDS = 30.0
#: Most memory the server's processes may add for an upload under 2 MB.
MEMORY_LIMIT = 600 * 2**20
#: Seconds the first page may take while a hostile upload is worked on: the target is 0.5 s;
#: the test allows for a shared, noisy machine.
PAGE_SECONDS = 2.0


@dataclass(frozen=True)
class Case:
    """A file of the corpus, where it is posted, and the answer: status and words in it."""

    name: str
    path: str
    status: int
    words: tuple[str, ...] = ()


MESH, POINTS = "/api/mesh", "/api/points"

CORPUS: tuple[Case, ...] = (
    Case("zip_many_entries.zip", MESH, 413, ("400,001 members", "at most 1,000")),
    Case("3mf_utf16_dtd.3mf", MESH, 400, ("declares a DTD",)),
    Case("3mf_billion_laughs_utf16.3mf", MESH, 400, ("declares a DTD",)),
    Case("3mf_in_zip.zip", MESH, 413, ("expands too far", "XML")),
    Case("3mf_2500_placements.3mf", MESH, 413, ("expands too far", "5,100,000 triangles")),
    Case("gltf_instances.glb", MESH, 413, ("expands too far", "4,000,000 triangles")),
    Case("gltf_zero_accessor.gltf", MESH, 413, ("expands too far", "accessors")),
    Case("gltf_node_cycle.gltf", MESH, 400, ("its own descendant", "3 -> 5 -> 3")),
    Case("gltf_two_parents.gltf", MESH, 400, ("two parents",)),
    Case("gltf_view_past_buffer.glb", MESH, 400, ("does not fit in its buffer",)),
    Case("digits_gltf_count.gltf", MESH, 400, ("too many digits",)),
    Case("digits_off_counts.off", MESH, 400, ("counts line",)),
    Case("digits_ply_list.ply", MESH, 400, ("list length",)),
    Case("points_lzf_bomb.pcd", POINTS, 413, ("1,500,000 points",)),
    Case("points_lzf_past_end.pcd", POINTS, 400, ("more than the 12 bytes",)),
    Case("points_coincident.xyz", POINTS, 200),
    Case("points_count_short.las", POINTS, 400, ("1,000 points", "only 4")),
    Case("points_count_long.las", POINTS, 200),
    Case("points_offset_nan.las", POINTS, 400, ("x offset is nan",)),
    Case("points_scale_zero.las", POINTS, 400, ("x scale is 0",)),
    Case("points_laz_bomb.laz", POINTS, 413, ("1,500,000 compressed points",)),
)


def test_the_corpus_names_every_file() -> None:
    listed = {case.name for case in CORPUS}
    present = {path.name for path in HOSTILE.iterdir() if path.name != "README.md"}
    assert listed == present


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    logged = tmp_path_factory.mktemp("server") / "server.log"
    log = logged.open("wb")
    command = [sys.executable, "-m", "uvicorn", "app.main:app", "--host", "127.0.0.1"]
    command += ["--port", str(port)]
    env = {**os.environ, "MESH_JOB_SECONDS": "10"}
    process = subprocess.Popen(command, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 120
    try:
        while True:
            assert process.poll() is None, logged.read_text()
            assert time.monotonic() < deadline, "the server did not start"
            try:
                if httpx.get(url + "/healthz").status_code == 200:
                    break
            except httpx.TransportError:
                pass
            time.sleep(0.1)
        # The workers warm up after the first page; a real upload waits until one is ready.
        httpx.post(
            url + "/api/mesh",
            params={"filename": "t.obj"},
            content=b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            timeout=120,
        )
        yield Server(url, psutil.Process(process.pid), logged)
    finally:
        process.terminate()
        process.wait(30)
        log.close()


@pytest.mark.parametrize("case", CORPUS, ids=lambda case: case.name)
def test_a_hostile_upload_is_answered(server: Server, case: Case) -> None:
    url = server.url
    data = (HOSTILE / case.name).read_bytes()
    with Watch(server) as watch:
        began = time.monotonic()
        response = httpx.post(
            url + case.path, files={"file": (case.name, data)}, timeout=ANSWER_SECONDS
        )
        took = time.monotonic() - began
    if case.status == 200:
        assert response.status_code == 200, response.text
    else:
        assert_error(response, case.status, "file", *case.words)
    assert took < ANSWER_SECONDS
    if len(data) < 2 * 2**20:
        assert watch.peak - watch.start < MEMORY_LIMIT, (watch.peak - watch.start) / 2**20
    assert watch.slowest < PAGE_SECONDS, watch.slowest
