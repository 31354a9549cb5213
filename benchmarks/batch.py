"""The batch on many small files: files per second on one and two local workers, per-file cost.

    make bench-batch              # or: .venv/bin/python -m benchmarks.batch [--files 1000]
    make bench-batch ARGS="--files 100 --rounds 2"

N binary STL files of noisy tori (:func:`benchmarks.mesh_kernels.torus_mesh`) with face counts
spread evenly on a log scale from 1,000 to 100,000 (Thingi10K-sized; 1,000 files are about
1 GB), written once to ``$BATCH_BENCH_DIR`` (default ``/tmp/mesh-batch-bench``) and reused.
Each round, in turn:

1. the report of every file in this process (``mn.analyse(path)``, after one warm-up report, one
   thread as in a worker): the sum of the per-file report times, the work itself;
2. ``run_batch`` with one worker, then with two, each into a fresh output folder: the wall
   time from the call to the table written, worker start included;
3. the start alone: a batch of one tiny file.

Printed as a Markdown table (``--markdown PATH`` also writes it to a file): files per second
for each, the two-worker speed-up (target at least 1.8), and the per-file overhead,
(one-worker batch - sum of report times) / N, with and without the worker's start (target
under 10 ms). Medians over ``--rounds``; the machine is shared, so only ratios within one run
count (note the load, ``uptime``).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks import tables
from benchmarks.mesh_kernels import torus_mesh

CACHE = Path(os.environ.get("BATCH_BENCH_DIR", "/tmp/mesh-batch-bench"))
TARGET_SPEEDUP, TARGET_OVERHEAD = 1.8, 0.010


def face_counts(files: int, low: int = 1_000, high: int = 100_000) -> list[int]:
    """``files`` face counts, evenly spread on a log scale from ``low`` to ``high``."""
    return [round(n) for n in np.geomspace(low, high, files)]


def dataset(files: int) -> Path:
    """The folder of ``files`` STL files, written once and reused."""
    import mesh_normal as mn

    folder = CACHE / f"stl-{files}"
    if folder.exists() and len(list(folder.iterdir())) == files:
        return folder
    shutil.rmtree(folder, ignore_errors=True)
    partial = folder.with_suffix(".partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    for index, faces in enumerate(face_counts(files)):
        vertices, triangles = torus_mesh(faces, seed=index)
        (partial / f"torus-{index:05d}.stl").write_bytes(mn.write_mesh(vertices, triangles, "stl"))
    partial.rename(folder)
    return folder


def report_seconds(folder: Path) -> float:
    """The sum of the per-file report times, in this process."""
    import mesh_normal as mn

    total = 0.0
    for path in sorted(folder.iterdir()):
        start = time.perf_counter()
        mn.analyse(path)
        total += time.perf_counter() - start
    return total


def batch_seconds(inputs: Path, workers: int) -> tuple[float, float]:
    """One batch's wall time, from the call to the table written, and the CPU time its
    worker processes used (they are waited for when the batch ends)."""
    from mesh_normal.datasets.driver import batch_options, run_batch

    with tempfile.TemporaryDirectory(prefix="bench-batch-") as out:
        before = os.times()
        start = time.perf_counter()
        result = run_batch([str(inputs)], batch_options(out=out), workers=workers)
        seconds = time.perf_counter() - start
        after = os.times()
    statuses = set(result.table.column("status").to_pylist())
    assert statuses <= {"ok", "problems"}, statuses
    cpu = (after.children_user + after.children_system) - (
        before.children_user + before.children_system
    )
    return seconds, cpu


def main() -> None:
    # The reports in this process on one thread, as each worker runs them (MESH_NORMAL_THREADS=1).
    os.environ["MESH_NORMAL_THREADS"] = "1"
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--files", type=int, default=1_000)
    parser.add_argument("--rounds", type=int, default=2)
    tables.add_option(parser)
    args = parser.parse_args()
    out = tables.Report(args.markdown)
    import mesh_normal as mn

    folder = dataset(args.files)
    size = sum(path.stat().st_size for path in folder.iterdir())
    print(f"{args.files} STL files, 1,000 to 100,000 faces, {size / 1e6:,.0f} MB; load {load()}")
    tiny = CACHE / "tiny"
    tiny.mkdir(parents=True, exist_ok=True)
    vertices, faces = torus_mesh(100)
    (tiny / "tiny.stl").write_bytes(mn.write_mesh(vertices, faces, "stl"))
    from mesh_normal import _core

    _core.set_threads(1)  # in case the core was loaded before the variable was set
    mn.analyse(tiny / "tiny.stl")  # the first report's imports, out of the timed ones
    reports, ones, twos, starts = [], [], [], []
    cpu_ones, cpu_twos, cpu_starts = [], [], []
    for _ in range(args.rounds):
        reports.append(report_seconds(folder))
        seconds, cpu = batch_seconds(folder, 1)
        ones.append(seconds)
        cpu_ones.append(cpu)
        seconds, cpu = batch_seconds(folder, 2)
        twos.append(seconds)
        cpu_twos.append(cpu)
        seconds, cpu = batch_seconds(tiny, 1)
        starts.append(seconds)
        cpu_starts.append(cpu)
    report, one, two, start = (statistics.median(x) for x in (reports, ones, twos, starts))
    cpu_one, cpu_two = statistics.median(cpu_ones), statistics.median(cpu_twos)
    cpu_start = statistics.median(cpu_starts)
    n = args.files
    speedup, steady_speedup = one / two, (one - start) / (two - start)
    work_one, work_two = cpu_one - cpu_start, cpu_two - 2 * cpu_start
    overhead = (one - report) / n
    steady = (one - start - report) / n
    out.print(f"| measure ({n:,} files, {size / 1e6:,.0f} MB; medians of {args.rounds} rounds) "
              "| measured | target |")  # fmt: skip
    out.print("|---|---:|---:|")
    out.print(
        f"| sum of the per-file reports, in process | {report:.2f} s ({n / report:.1f} files/s) | |"
    )
    out.print(f"| batch, 1 worker | {one:.2f} s ({n / one:.1f} files/s) | |")
    out.print(f"| batch, 2 workers | {two:.2f} s ({n / two:.1f} files/s) | |")
    out.print(
        f"| 2 workers / 1 worker, the workers' start included | {speedup:.2f}x "
        f"| ≥ {TARGET_SPEEDUP}x: {'met' if speedup >= TARGET_SPEEDUP else 'missed'} |"
    )
    out.print(f"| 2 workers / 1 worker, without the start | {steady_speedup:.2f}x | |")
    out.print(
        f"| the workers' CPU time per file, 1 worker against 2 (starts left out: "
        f"{work_one:.2f} s and {work_two:.2f} s) | {work_one / work_two:.2f} | |"
    )
    out.print(
        f"| per-file overhead: (1-worker batch - sum of reports) / files, the start included "
        f"| {1e3 * overhead:.1f} ms | |"
    )
    out.print(
        f"| the same without the start ({start:.2f} s, once a batch) | {1e3 * steady:.1f} ms "
        f"| < {1e3 * TARGET_OVERHEAD:.0f} ms: {'met' if steady < TARGET_OVERHEAD else 'missed'} |"
    )
    print(f"load after: {load()}")
    out.write()


def load() -> str:
    return ", ".join(f"{value:.2f}" for value in os.getloadavg())


if __name__ == "__main__":
    main()
