"""Does heavy mesh work stall the pages? ``GET /`` latency while four heavy uploads run.

Starts ``uvicorn app.main:app`` twice: with the jobs in threads of the server process
(``MESH_IN_PROCESS=1``, four at once: the server without worker processes) and
with the worker processes (``MESH_WORKERS=2``, the default; the other two uploads wait their
turn). Each time, four ASCII STL files (the heaviest per byte for the GIL: regular-expression
passes in Python) are posted at once while a client asks for ``GET /`` every 20 ms; the
figures are that page's latencies while the uploads run.

Then the peak memory of corner normals as JSON, written whole and in blocks (as
``POST /api/mesh/normals`` streams them).

    .venv/bin/python -m benchmarks.stalls [--mb 40] [--markdown PATH]

``--markdown PATH`` writes the latencies' table to a file, after a line naming the machine and
the date.
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import numpy as np

from benchmarks import tables

ROOT = Path(__file__).resolve().parent.parent


def ascii_stl(megabytes: float) -> bytes:
    """A wavy height field as ASCII STL of about ``megabytes`` MB."""
    side = int((megabytes * 1e6 / 2 / 260) ** 0.5) + 1
    x, y = np.meshgrid(np.linspace(0, 1, side), np.linspace(0, 1, side))
    points = np.stack([x, y, 0.1 * np.sin(7 * x) * np.cos(5 * y)], axis=-1)
    a, b = points[:-1, :-1].reshape(-1, 3), points[:-1, 1:].reshape(-1, 3)
    c, d = points[1:, :-1].reshape(-1, 3), points[1:, 1:].reshape(-1, 3)
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    rows = [
        "facet normal 0 0 0\n outer loop\n"
        + "".join(f"  vertex {p[0]:.9e} {p[1]:.9e} {p[2]:.9e}\n" for p in triangle)
        + " endloop\nendfacet\n"
        for triangle in triangles
    ]
    return ("solid wave\n" + "".join(rows) + "endsolid wave\n").encode()


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def serve(environment: dict[str, str]) -> tuple[subprocess.Popen[bytes], str]:
    port = free_port()
    process = subprocess.Popen(
        [sys.executable, "-m", "uvicorn", "app.main:app", "--port", str(port)],
        cwd=ROOT,
        env={**os.environ, **environment},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    url = f"http://127.0.0.1:{port}"
    while True:
        try:
            if httpx.get(url + "/").status_code == 200:
                return process, url
        except httpx.TransportError:
            time.sleep(0.1)


def under_load(url: str, data: bytes, uploads: int = 4) -> dict[str, object]:
    """GET / every 20 ms while ``uploads`` heavy uploads run; the latencies in seconds."""
    # Wait until a first upload has been answered: the workers have loaded their kernels.
    httpx.post(url + "/api/mesh", files={"file": ("warm.stl", data[:200_000])}, timeout=600)
    statuses: list[int] = []
    start = time.perf_counter()

    def heavy() -> None:
        with httpx.Client(timeout=600) as client:
            reply = client.post(url + "/api/mesh", files={"file": ("wave.stl", data)})
            statuses.append(reply.status_code)

    threads = [threading.Thread(target=heavy) for _ in range(uploads)]
    for thread in threads:
        thread.start()
    latencies: list[float] = []
    with httpx.Client(timeout=600) as client:
        while any(thread.is_alive() for thread in threads):
            began = time.perf_counter()
            assert client.get(url + "/").status_code == 200
            latencies.append(time.perf_counter() - began)
            time.sleep(0.02)
    for thread in threads:
        thread.join()
    seconds = np.array(latencies)
    return {
        "statuses": sorted(statuses),
        "uploads_s": round(time.perf_counter() - start, 1),
        "requests": len(seconds),
        "p50_s": round(float(np.percentile(seconds, 50)), 3),
        "p99_s": round(float(np.percentile(seconds, 99)), 3),
        "max_s": round(float(seconds.max()), 3),
    }


def json_peak(faces: int, streamed: bool) -> float:
    """Peak resident MB over the normals themselves, for corner normals written as JSON."""
    code = f"""
import resource, numpy as np
from mesh_normal.files.normals import normals_blocks, normals_file
normals = np.random.default_rng(0).normal(size=({faces}, 3, 3))
missing = np.zeros(({faces}, 3), bool)
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
if {streamed}:
    size = sum(len(b) for b in normals_blocks(normals, missing, "corner", "angle", 30.0, "json"))
else:
    size = len(normals_file(normals, missing, "corner", "angle", 30.0, "json"))
print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base) / 1024, size / 2**20)
"""
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    extra, size = map(float, out.stdout.split())
    print(
        f"  corner normals of {faces:,} faces as JSON ({size:.0f} MB of text), "
        f"{'in blocks' if streamed else 'whole'}: +{extra:.0f} MB peak"
    )
    return extra


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mb", type=float, default=40, help="size of each upload, MB")
    tables.add_option(parser)
    arguments = parser.parse_args()
    out = tables.Report(arguments.markdown)
    data = ascii_stl(arguments.mb)
    print(f"four uploads of {len(data) / 2**20:.0f} MB ASCII STL, {os.cpu_count()} cores")
    out.print(
        f"| jobs run in (four uploads of {len(data) / 2**20:.0f} MB ASCII STL at once) "
        "| uploads answered | all four done in | `GET /` p50 | p99 | max |"
    )
    out.print("|---|---|---:|---:|---:|---:|")
    for label, environment in (
        (
            "threads of the server (`MESH_IN_PROCESS=1`, four at once)",
            {"MESH_IN_PROCESS": "1", "MESH_WORKERS": "4"},
        ),
        ("two worker processes (the default)", {"MESH_WORKERS": "2", "MESH_QUEUE_SECONDS": "600"}),
    ):
        process, url = serve(environment)
        try:
            figures = under_load(url, data)
        finally:
            process.terminate()
            process.wait()
        statuses = figures["statuses"]
        assert isinstance(statuses, list)
        answered = ", ".join(f"{statuses.count(s)} × {s}" for s in sorted(set(statuses)))
        out.print(
            f"| {label} | {answered} | {figures['uploads_s']} s | {figures['p50_s']} s "
            f"| {figures['p99_s']} s | {figures['max_s']} s |"
        )
    out.write()
    faces = 2_000_000
    whole, blocks = json_peak(faces, streamed=False), json_peak(faces, streamed=True)
    print(f"  JSON corner normals: {whole / blocks:.0f} times less peak memory in blocks")


if __name__ == "__main__":
    main()
