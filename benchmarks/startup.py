"""Start-up: the command line and the server, from a cold process, as ratios in one run.

``make bench-startup`` (``.venv/bin/python -m benchmarks.startup``, ``--rounds 7``):

- ``mesh-normal --help`` and ``mesh-normal analyze`` of a tetrahedron in OBJ, with hyperfine
  (best and median of its runs; targets 0.3 s and 1 s);
- the server's first page: ``uvicorn app.main:app`` until ``GET /`` answers, against a bare
  FastAPI app (``benchmarks.echo_app``) until ``GET /docs`` answers, the two alternating in
  each round; the ratio of each round, best and median (target 1.5);
- the first ``POST /api/mesh`` (the tetrahedron) right after that first page, and the second:
  the difference, best and median (target 0.2 s);
- the bytecode: how many of the environment's and the checkout's modules have a current .pyc.

The machine's load (``os.getloadavg``) is printed with the figures: on two shared cores the
times move by a half between runs, the ratios within one run much less. Then the figures as a
Markdown table, which ``--markdown PATH`` also writes to a file after a line naming the machine
and the date.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
import urllib.request
from pathlib import Path

from benchmarks import tables

ROOT = Path(__file__).resolve().parent.parent
VENV_BIN = Path(sys.executable).parent
TETRAHEDRON = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
PORTS = (19871, 19872)  # ours, the bare app


def hyperfine(command: list[str], runs: int) -> tuple[float, float]:
    """Best and median seconds of ``command`` (hyperfine, two warm-up runs)."""
    with tempfile.NamedTemporaryFile(suffix=".json") as out:
        subprocess.run(
            ["hyperfine", "--style", "none", "--warmup", "2", "--runs", str(runs),
             "--export-json", out.name, "--", subprocess.list2cmdline(command)],
            check=True, capture_output=True, cwd=ROOT,
        )  # fmt: skip
        times = json.loads(Path(out.name).read_text())["results"][0]["times"]
    return min(times), statistics.median(times)


def get(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=30) as response:
        return bytes(response.read())


def post(url: str, data: bytes) -> float:
    started = time.perf_counter()
    headers = {"Content-Type": "application/octet-stream"}  # the raw body, as a file
    request = urllib.request.Request(url, data=data, method="POST", headers=headers)
    with urllib.request.urlopen(request, timeout=120) as response:
        json.loads(response.read())
    return time.perf_counter() - started


def serve(
    app: str,
    port: int,
    path: str,
    uploads: int,
    mesh: tuple[str, bytes] = ("tetra.obj", TETRAHEDRON),
) -> tuple[float, list[float]]:
    """Seconds from starting uvicorn to the first answer of ``path``; then ``uploads`` uploads
    of ``mesh`` (a file name and its bytes; the tetrahedron by default), each timed."""
    free(port)
    started = time.perf_counter()
    server = subprocess.Popen(
        [str(VENV_BIN / "uvicorn"), app, "--host", "127.0.0.1", "--port", str(port)],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        while True:
            try:
                get(f"http://127.0.0.1:{port}{path}")
                break
            except OSError:
                if server.poll() is not None:
                    raise RuntimeError(f"{app} exited with {server.returncode}") from None
                time.sleep(0.005)
        first_page = time.perf_counter() - started
        name, data = mesh
        url = f"http://127.0.0.1:{port}/api/mesh?filename={name}"
        return first_page, [post(url, data) for _ in range(uploads)]
    finally:
        server.send_signal(signal.SIGINT)
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()


def free(port: int) -> None:
    """Wait until nothing listens on ``port`` (the last round's server and its workers gone),
    so that the first answer is the new server's."""
    for _ in range(600):
        with socket.socket() as probe:
            if probe.connect_ex(("127.0.0.1", port)) != 0:
                return
        time.sleep(0.1)
    raise RuntimeError(f"port {port} is still in use")


def bytecode() -> tuple[int, int]:
    """How many .py files of site-packages, mesh_normal/ and app/ have a current .pyc."""
    folders = [Path(sysconfig.get_paths()["purelib"]), ROOT / "mesh_normal", ROOT / "app"]
    total = compiled = 0
    for folder in folders:
        for source in folder.rglob("*.py"):
            total += 1
            cached = Path(importlib.util.cache_from_source(str(source)))
            compiled += cached.exists() and cached.stat().st_mtime >= source.stat().st_mtime
    return compiled, total


def figures(values: list[float]) -> str:
    return f"best {min(values):.3f}, median {statistics.median(values):.3f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7, help="server rounds (default 7)")
    parser.add_argument("--runs", type=int, default=15, help="hyperfine runs (default 15)")
    tables.add_option(parser)
    args = parser.parse_args()
    out = tables.Report(args.markdown)
    if shutil.which("hyperfine") is None:
        sys.exit("benchmarks.startup: hyperfine is not installed")
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    compiled, total = bytecode()
    print(f"bytecode: {compiled:,} of {total:,} modules have a current .pyc")
    cli = str(VENV_BIN / "mesh-normal")
    with tempfile.TemporaryDirectory() as folder:
        tetra = Path(folder) / "tetra.obj"
        tetra.write_bytes(TETRAHEDRON)
        subprocess.run([cli, "analyze", str(tetra)], check=True, capture_output=True)
        python = [sys.executable, "-c"]
        bare_best, bare_median = hyperfine([*python, "pass"], args.runs)
        numpy_best, numpy_median = hyperfine([*python, "import numpy"], args.runs)
        help_best, help_median = hyperfine([cli, "--help"], args.runs)
        tiny_best, tiny_median = hyperfine([cli, "analyze", str(tetra)], args.runs)
    # The interpreter's own start and NumPy's import, for scale on a loaded machine.
    print(f"python -c pass: best {bare_best:.3f} s, median {bare_median:.3f} s; "
          f"import numpy: best {numpy_best:.3f} s, median {numpy_median:.3f} s")  # fmt: skip
    print(f"mesh-normal --help: best {help_best:.3f} s, median {help_median:.3f} s (target 0.3)")
    print(f"mesh-normal analyze tetra.obj: best {tiny_best:.3f} s, median {tiny_median:.3f} s "
          f"(target 1); {tiny_best / numpy_best:.2f} times import numpy (best)")  # fmt: skip
    ratios, ours, bare, gaps = [], [], [], []
    serve("app.main:app", PORTS[0], "/", 1)  # the files read once (the system's cache)
    for _ in range(args.rounds):
        first, (one, two) = serve("app.main:app", PORTS[0], "/", 2)
        baseline, _ = serve("benchmarks.echo_app:app", PORTS[1], "/docs", 0)
        ours.append(first)
        bare.append(baseline)
        ratios.append(first / baseline)
        gaps.append(one - two)
    print(f"first page, ours (s): {figures(ours)}; bare FastAPI (s): {figures(bare)}")
    print(f"first page, ours / bare: {figures(ratios)} (target 1.5)")
    print(f"first upload minus second (s): {figures(gaps)} (target 0.2)")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    out.print(f"\n| measured (hyperfine: {args.runs} runs; servers: {args.rounds} rounds) | best "
              "| median | target |")  # fmt: skip
    out.print("|---|---:|---:|---:|")
    out.print(f"| `mesh-normal --help` | {help_best:.3f} s | {help_median:.3f} s | 0.3 s |")
    out.print(
        f"| `mesh-normal analyze tetra.obj` | {tiny_best:.3f} s | {tiny_median:.3f} s | 1 s |"
    )
    out.print(f"| `import numpy`, for scale | {numpy_best:.3f} s | {numpy_median:.3f} s | |")
    out.print(f"| first page, ours | {min(ours):.3f} s | {statistics.median(ours):.3f} s | |")
    out.print(
        f"| first page, bare FastAPI | {min(bare):.3f} s | {statistics.median(bare):.3f} s | |"
    )
    out.print(f"| first page, ours / bare FastAPI, per round | {min(ratios):.2f} "
              f"| {statistics.median(ratios):.2f} | 1.5 |")  # fmt: skip
    out.print(f"| first upload minus the second | {min(gaps):.3f} s "
              f"| {statistics.median(gaps):.3f} s | 0.2 s |")  # fmt: skip
    out.print(f"| modules with a current .pyc | {compiled:,} of {total:,} | | all |")
    out.write()


if __name__ == "__main__":
    main()
