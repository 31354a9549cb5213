"""Hostile uploads against the real server: status, time, memory and the first page meanwhile.

Starts ``uvicorn app.main:app`` on a free loopback port (its worker processes, the
environment as is), waits for it and for a first small upload, then runs each row and prints
one line of a Markdown table: the upload's size, the answer's status, the seconds to it, the
peak memory the server's processes added (server and workers: RSS every 20 ms),
the slowest ``GET /`` meanwhile (asked every 50 ms) and the start of the answer's sentence.

The rows: every file of ``tests/data/hostile/`` (``points_*`` to ``/api/points``, the others
to ``/api/mesh``), then bigger versions made in memory: a zip whose directory
lists 400,001 members, 200,000 identical points, 100,000 points each 20 times, 12 batches of
100,000 triangles at once, 600 clients that announce 1 MB and leave after 56 bytes, and the
sample pages asked 20 times at once while 5 uploads run.

    .venv/bin/python -m benchmarks.hostile [--rows NAME ...] [--markdown PATH]

``--markdown PATH`` also writes the table to a file, after a line naming the machine and date.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import httpx
import numpy as np
import psutil  # type: ignore[import-untyped]

from benchmarks import tables
from benchmarks.stalls import ascii_stl, free_port

ROOT = Path(__file__).resolve().parent.parent
HOSTILE = ROOT / "tests" / "data" / "hostile"
MESH, POINTS, NORMALS = "/api/mesh", "/api/points", "/api/normals"
#: Seconds any one request may take.
TIMEOUT = 60.0
#: Access-log lines of the page poller: left out of the log's growth.
POLL_LINE = '"GET / HTTP/1.1"'
SMALL_OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@dataclass
class Server:
    """The running server: its address, its process and the file its output goes to."""

    url: str
    root: psutil.Process
    log: Path

    @property
    def port(self) -> int:
        return int(self.url.rsplit(":", 1)[1])


@dataclass
class Row:
    """One line of the table."""

    name: str
    size: str
    status: str
    seconds: float
    added_mb: float
    slowest_page: float
    sentence: str

    def markdown(self) -> str:
        cells = [
            self.name,
            self.size,
            self.status,
            f"{self.seconds:.2f}",
            f"{self.added_mb:,.0f}",
            f"{self.slowest_page:.2f}",
            self.sentence[:90].replace("|", "\\|"),
        ]
        return "| " + " | ".join(cells) + " |"


HEADER = (
    "| row | upload | status | answer s | peak added MB | slowest GET / s | sentence |\n"
    "|---|---:|---|---:|---:|---:|---|"
)


def size_text(size: float) -> str:
    for unit in ("B", "KB", "MB"):
        if size < 1024 or unit == "MB":
            return f"{size:,.0f} {unit}" if unit == "B" else f"{size:,.1f} {unit}"
        size /= 1024
    raise AssertionError("unreachable")


# The server and what is watched while a row runs.


def tree_memory(root: psutil.Process) -> int:
    """Resident bytes of the server and its children (its workers)."""
    total = 0
    for process in [root, *root.children(recursive=True)]:
        with contextlib.suppress(psutil.Error):  # a worker replaced meanwhile
            total += int(process.memory_info().rss)
    return total


@contextlib.contextmanager
def serve() -> Iterator[Server]:
    """``uvicorn app.main:app`` on a free port, ready once a first small upload is answered;
    stopped (with every process it started) on leaving, even on error."""
    port = free_port()
    log = Path(tempfile.mkstemp(prefix="hostile-server-", suffix=".log")[1])
    command = [sys.executable, "-m", "uvicorn", "app.main:app", "--host", "127.0.0.1"]
    with log.open("wb") as output:
        process = subprocess.Popen(
            [*command, "--port", str(port)], cwd=ROOT, stdout=output, stderr=subprocess.STDOUT
        )
    server = Server(f"http://127.0.0.1:{port}", psutil.Process(process.pid), log)
    try:
        wait_until_ready(server, process)
        yield server
    finally:
        stop(process, server.root)
        print(f"\nserver log: {log}")


def wait_until_ready(server: Server, process: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + 120
    while True:
        if process.poll() is not None:
            raise RuntimeError("the server stopped:\n" + server.log.read_text()[-3000:])
        if time.monotonic() > deadline:
            raise RuntimeError("the server did not start within 120 s")
        with contextlib.suppress(httpx.TransportError):
            if httpx.get(server.url + "/healthz", timeout=5).status_code == 200:
                break
        time.sleep(0.1)
    # The workers warm up after start; a first upload waits until one is ready.
    files = {"file": ("warm.obj", SMALL_OBJ)}
    reply = httpx.post(server.url + MESH, files=files, timeout=120)
    if reply.status_code != 200:
        raise RuntimeError(f"the first upload was answered {reply.status_code}: {reply.text}")
    settle(server.root)


def settle(root: psutil.Process, seconds: float = 60) -> None:
    """Wait until the other workers have warmed up too (the server tree's memory steady for 2 s,
    at most ``seconds``), so that the first row's figures are its own."""
    deadline = time.monotonic() + seconds
    steady_since, last = time.monotonic(), tree_memory(root)
    while time.monotonic() < deadline and time.monotonic() - steady_since < 2:
        time.sleep(0.2)
        now = tree_memory(root)
        if abs(now - last) > 5 * 2**20:
            steady_since = time.monotonic()
        last = now


def stop(process: subprocess.Popen[bytes], root: psutil.Process) -> None:
    """Terminate the server, then any of its children still running (by their ids)."""
    children: list[psutil.Process] = []
    with contextlib.suppress(psutil.Error):
        children = root.children(recursive=True)
    process.terminate()
    try:
        process.wait(30)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(10)
    left = [child for child in children if child.is_running()]
    for child in left:
        with contextlib.suppress(psutil.Error):
            child.terminate()
    _, alive = psutil.wait_procs(left, timeout=10)
    for child in alive:
        with contextlib.suppress(psutil.Error):
            child.kill()


class Watch:
    """While a row runs: the server tree's peak memory and the first page's slowest answer."""

    def __init__(self, server: Server) -> None:
        self.server = server
        self.peak = self.start = tree_memory(server.root)
        self.slowest = 0.0
        self.done = threading.Event()
        self.threads = [threading.Thread(target=self._memory), threading.Thread(target=self._page)]

    def _memory(self) -> None:
        while not self.done.is_set():
            self.peak = max(self.peak, tree_memory(self.server.root))
            time.sleep(0.02)

    def _page(self) -> None:
        with httpx.Client(base_url=self.server.url, timeout=TIMEOUT) as client:
            while not self.done.is_set():
                began = time.monotonic()
                with contextlib.suppress(httpx.HTTPError):  # a timeout counts as its time
                    client.get("/")
                self.slowest = max(self.slowest, time.monotonic() - began)
                time.sleep(0.05)

    @property
    def added_mb(self) -> float:
        return (self.peak - self.start) / 2**20

    def __enter__(self) -> Watch:
        for thread in self.threads:
            thread.start()
        return self

    def __exit__(self, *_exc: object) -> None:
        self.done.set()
        for thread in self.threads:
            thread.join()


# Answers.


def sentence_of(reply: httpx.Response) -> str:
    """The answer's error sentence, or the start of its text if it has none; empty for a 200."""
    if reply.status_code == 200:
        return ""
    try:
        body = reply.json()
    except ValueError:
        return reply.text.strip()
    return str(body.get("error", body)) if isinstance(body, dict) else str(body)


def post_file(url: str, path: str, filename: str, data: bytes) -> httpx.Response:
    return httpx.post(url + path, files={"file": (filename, data)}, timeout=TIMEOUT)


def counted(statuses: list[int]) -> str:
    """``200×10, 503×2``."""
    return ", ".join(f"{status}×{count}" for status, count in sorted(Counter(statuses).items()))


# One function per kind of row.


def upload_row(server: Server, name: str, path: str, filename: str, data: bytes) -> Row:
    """One upload, posted as the file field of a multipart body."""
    with Watch(server) as watch:
        began = time.monotonic()
        reply = post_file(server.url, path, filename, data)
        took = time.monotonic() - began
    return Row(
        name,
        size_text(len(data)),
        str(reply.status_code),
        took,
        watch.added_mb,
        watch.slowest,
        sentence_of(reply),
    )


def corpus_row(server: Server, file: Path) -> Row:
    path = POINTS if file.name.startswith("points_") else MESH
    return upload_row(server, file.name, path, file.name, file.read_bytes())


def many_members_zip(members: int = 400_001) -> bytes:
    """A zip whose directory really lists ``members`` empty stored files (``f000001.txt``...),
    each with its local header, and zip64 end records for the count past 65,535."""
    date = (0 << 9) | (1 << 5) | 1  # 1980-01-01
    local: list[bytes] = []
    directory: list[bytes] = []
    offset = 0
    for number in range(1, members + 1):
        name = f"f{number:06d}.txt".encode()
        header = struct.pack("<4s5H3L2H", b"PK\x03\x04", 20, 0, 0, 0, date, 0, 0, 0, len(name), 0)
        local.append(header + name)
        directory.append(
            struct.pack(
                "<4s6H3L5H2L",
                *(b"PK\x01\x02", 20, 20, 0, 0, 0, date, 0, 0, 0, len(name)),
                *(0, 0, 0, 0, 0, offset),
            )
            + name
        )
        offset += len(header) + len(name)
    listed = b"".join(directory)
    end64 = struct.pack(
        "<4sQ2H2L4Q", b"PK\x06\x06", 44, 45, 45, 0, 0, members, members, len(listed), offset
    )
    locator = struct.pack("<4sLQL", b"PK\x06\x07", 0, offset + len(listed), 1)
    end = struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, 0xFFFF, 0xFFFF, len(listed), offset, 0)
    return b"".join(local) + listed + end64 + locator + end


def repeated_points(distinct: int = 100_000, times: int = 20) -> bytes:
    """``distinct`` random points as XYZ text, each line ``times`` times in a row."""
    points = np.random.default_rng(35).uniform(-1, 1, (distinct, 3))
    lines = [f"{x:.6f} {y:.6f} {z:.6f}\n".encode() for x, y, z in points.tolist()]
    return b"".join(line * times for line in lines)


def batch_body(triangles: int = 100_000) -> bytes:
    """``{"triangles": [[[ax, ay, az], [bx, by, bz], [cx, cy, cz]], ...]}`` at full precision."""
    corners = np.random.default_rng(35).uniform(-10, 10, (triangles, 3, 3))
    return json.dumps({"triangles": corners.tolist()}).encode()


def batches_row(server: Server, batches: int = 12) -> Row:
    """``batches`` full batches posted to ``/api/normals`` at once."""
    body = batch_body()

    def post(_: int) -> httpx.Response:
        headers = {"content-type": "application/json"}
        return httpx.post(server.url + NORMALS, content=body, headers=headers, timeout=TIMEOUT)

    with Watch(server) as watch, ThreadPoolExecutor(batches) as pool:
        began = time.monotonic()
        replies = list(pool.map(post, range(batches)))
        took = time.monotonic() - began
    sentences = [sentence_of(reply) for reply in replies if reply.status_code != 200]
    return Row(
        f"{batches} batches of 100,000 triangles",
        f"{batches} × {size_text(len(body))}",
        counted([reply.status_code for reply in replies]),
        took,
        watch.added_mb,
        watch.slowest,
        sentences[0] if sentences else "",
    )


def leaving_clients_row(server: Server, clients: int = 600, sent: int = 56) -> Row:
    """``clients`` raw connections that announce a 1 MB multipart upload, send ``sent`` bytes
    of it, and close; the server log's growth (the page poller's lines left out)."""
    boundary = "hostile"
    head = (
        f"POST {MESH} HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n"
        f"Content-Type: multipart/form-data; boundary={boundary}\r\n"
        f"Content-Length: {2**20}\r\n\r\n"
    ).encode()
    part = (
        f'--{boundary}\r\nContent-Disposition: form-data; name="file"; filename="a.obj"\r\n\r\n'
    ).encode() + SMALL_OBJ * 4
    request = head + part[:sent]
    before = server.log.stat().st_size
    with Watch(server) as watch:
        began = time.monotonic()
        sockets = []
        for _ in range(clients):
            connection = socket.create_connection(("127.0.0.1", server.port), timeout=TIMEOUT)
            connection.sendall(request)
            sockets.append(connection)
        for connection in sockets:
            connection.close()
        took = time.monotonic() - began
        time.sleep(3)  # the server notices them leave
    with server.log.open("rb") as log:
        log.seek(before)
        lines = log.read().decode(errors="replace").splitlines()
    logged = [line for line in lines if POLL_LINE not in line]
    growth = sum(len(line) + 1 for line in logged)
    return Row(
        f"{clients} clients leave after {sent} bytes",
        f"{clients} × {sent} B of 1 MB",
        f"log +{size_text(growth)}, {len(logged)} lines",
        took,
        watch.added_mb,
        watch.slowest,
        logged[0].strip() if logged else "",
    )


def samples_row(server: Server, pages: int = 20, uploads: int = 5) -> Row:
    """``pages`` sample pages asked at once while ``uploads`` 4 MB ASCII STL uploads run."""
    from app.mesh.samples import SAMPLES

    names = list(SAMPLES)
    data = ascii_stl(4)

    def page(index: int) -> httpx.Response:
        address = f"{server.url}/mesh/sample/{names[index % len(names)]}"
        return httpx.get(address, timeout=TIMEOUT)

    def upload(_: int) -> httpx.Response:
        return post_file(server.url, MESH, "wave.stl", data)

    with Watch(server) as watch, ThreadPoolExecutor(pages + uploads) as pool:
        began = time.monotonic()
        asked = [pool.submit(page, index) for index in range(pages)]
        asked += [pool.submit(upload, index) for index in range(uploads)]
        replies = [future.result() for future in asked]
        took = time.monotonic() - began
    sentences = [sentence_of(reply) for reply in replies if reply.status_code != 200]
    return Row(
        f"{pages} sample pages + {uploads} uploads",
        f"{uploads} × {size_text(len(data))}",
        f"pages {counted([r.status_code for r in replies[:pages]])}; "
        f"uploads {counted([r.status_code for r in replies[pages:]])}",
        took,
        watch.added_mb,
        watch.slowest,
        sentences[0] if sentences else "",
    )


def generated_upload(
    server: Server, name: str, path: str, filename: str, make: Callable[[], bytes]
) -> Row:
    return upload_row(server, name, path, filename, make())


def rows() -> dict[str, Callable[[Server], Row]]:
    """Every row by its name (for ``--rows``), in the table's order."""
    found: dict[str, Callable[[Server], Row]] = {
        file.name: partial(corpus_row, file=file)
        for file in sorted(HOSTILE.iterdir())
        if file.name != "README.md"
    }
    generated = {
        "zip_400001_members": (MESH, "many.zip", many_members_zip),
        "points_200000_zeros": (POINTS, "zeros.xyz", lambda: b"0 0 0\n" * 200_000),
        "points_200000_same": (POINTS, "same.xyz", lambda: b"1.5 2.5 3.5\n" * 200_000),
        "points_100000_x20": (POINTS, "repeated.xyz", repeated_points),
    }
    for name, (path, filename, make) in generated.items():
        found[name] = partial(generated_upload, name=name, path=path, filename=filename, make=make)
    found["batches_12x100000"] = batches_row
    found["clients_leave_600"] = leaving_clients_row
    found["samples_20_uploads_5"] = samples_row
    return found


def main() -> None:
    table = rows()
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--rows", nargs="+", choices=list(table), metavar="NAME", help="only these rows"
    )
    tables.add_option(parser)
    arguments = parser.parse_args()
    out = tables.Report(arguments.markdown)
    chosen = arguments.rows or list(table)
    print(f"{len(chosen)} rows, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    with serve() as server:
        out.print(HEADER)
        for name in chosen:
            out.print(table[name](server).markdown())
    out.write()


if __name__ == "__main__":
    main()
