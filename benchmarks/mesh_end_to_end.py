"""Whole meshes end to end: the upload report against trimesh and Open3D, and Lucy on the CLI.

    make bench-mesh-e2e   # or: .venv/bin/python -m benchmarks.mesh_end_to_end
                          #     [--sizes 69451 871414] [--repeats 7] [--skip-lucy]
                          #     [--skip-readers] [--markdown PATH]

0. The readers table of :mod:`benchmarks.readers` (OBJ, PLY and OFF against trimesh's
   ``load(process=False)``), unless ``--skip-readers``.

1. ``POST /api/mesh`` with a binary STL as a multipart upload, against one uvicorn worker of
   ``app.main:app`` on a free loopback port; the file is in memory beforehand, the clock runs
   from sending it to the parsed JSON report (status 200 checked), after one warm-up upload per
   size. Alternating with each upload, in this process, the peers for "a report" from the same
   bytes: trimesh ``load(process=True)`` (its default, which merges vertices) reading
   ``is_watertight``, ``is_winding_consistent``, ``volume``, ``area`` and ``face_normals``;
   the same with ``process=False`` (no merging: the watertight and winding answers are then
   about a triangle soup); Open3D ``read_triangle_mesh`` of the file, then
   ``remove_duplicated_vertices`` (its STL reader keeps three vertices per triangle),
   ``compute_triangle_normals``, ``is_edge_manifold`` (closed), ``is_vertex_manifold``,
   ``is_orientable`` and the area (``is_watertight`` also tests self-intersection, which
   takes 44 s at the bunny size, so it is left out; so is the volume, which needs it).
   Median and best of ``--repeats``; the target is the dragon (871,414 faces) under 1.5 s.
2. ``mesh-normal normals LUCY.stl --kind vertex -o OUT.npy`` (and ``analyze``) as a
   subprocess on a 14,000,000-face binary STL (about 700 MB): wall time, peak RSS of that
   child (GNU time's ``%M``, see :func:`run_cli`) and the CLI's own stage times
   (``--progress``), against 30 s and 6 GiB. A small run first reads the library's files once
   (the system's cache).

``--markdown PATH`` also writes tables 1 and 2 to a file, after a line naming the machine and
the date (the readers write their own: ``benchmarks.readers --markdown``).

The meshes are :func:`benchmarks.mesh_kernels.torus_mesh` written by ``write_mesh`` into
``$MESH_E2E_DIR`` (default ``/tmp/mesh-e2e``) and reused when present. The machine is shared
and drifts 2-5x between runs, so only ratios within one run count.
"""

from __future__ import annotations

import argparse
import io
import itertools
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path

from benchmarks import tables
from benchmarks.mesh_kernels import torus_mesh
from benchmarks.run import free_port

SIZES = (69_451, 871_414)
LUCY = 14_000_000
TARGET_UPLOAD = 1.5  # seconds, dragon size
TARGET_LUCY_SECONDS, TARGET_LUCY_RSS = 30.0, 6 * 2**30
#: The target for ``mesh-normal analyze`` of the Lucy size: under 15 s, in the same memory.
TARGET_LUCY_ANALYZE_SECONDS = 15.0
CACHE = Path(os.environ.get("MESH_E2E_DIR", "/tmp/mesh-e2e"))
CLI = str(Path(sys.executable).with_name("mesh-normal"))


def stl_file(size: int) -> Path:
    """The synthetic torus with ``size`` faces as a binary STL, written once and reused."""
    path = CACHE / f"torus-{size}.stl"
    if path.exists() and path.stat().st_size == 84 + 50 * size:
        return path
    from mesh_normal.files import write_mesh

    CACHE.mkdir(parents=True, exist_ok=True)
    print(f"writing {path} ...", file=sys.stderr, flush=True)
    vertices, faces = torus_mesh(size)
    data = write_mesh(vertices, faces, "stl")
    del vertices, faces
    partial = path.with_suffix(".partial")
    partial.write_bytes(data)
    partial.replace(path)
    return path


@contextmanager
def server() -> Iterator[str]:
    """One uvicorn worker of the app on a free loopback port, answering before we go on."""
    import httpx

    port = free_port()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "uvicorn",
            "app.main:app",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--workers",
            "1",
            "--no-access-log",
            "--log-level",
            "warning",
        ]
    )
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(400):
            try:
                httpx.get(base + "/openapi.json", timeout=1).raise_for_status()
                break
            except httpx.HTTPError:
                time.sleep(0.05)
        else:
            raise RuntimeError("the server did not answer within 20 s")
        yield base
    finally:
        process.terminate()
        process.wait(timeout=30)


def upload(client: object, base: str, name: str, data: bytes) -> int:
    response = client.post(
        base + "/api/mesh",  # type: ignore[attr-defined]
        files={"file": (name, data, "application/octet-stream")},
    )
    if response.status_code != 200:
        raise RuntimeError(f"POST /api/mesh: {response.status_code} {response.text[:300]}")
    return int(response.json()["faces"])


def trimesh_report(data: bytes, process: bool) -> None:
    import trimesh

    mesh = trimesh.load(io.BytesIO(data), file_type="stl", process=process)
    _ = (mesh.is_watertight, mesh.is_winding_consistent, mesh.volume, mesh.area, mesh.face_normals)


def open3d_report(path: Path) -> None:
    import open3d as o3d

    mesh = o3d.io.read_triangle_mesh(str(path))
    mesh.remove_duplicated_vertices()
    mesh.compute_triangle_normals()
    # is_watertight() would add is_self_intersecting(), 44 s alone at the bunny size
    _ = (
        mesh.is_edge_manifold(allow_boundary_edges=False),
        mesh.is_vertex_manifold(),
        mesh.is_orientable(),
        mesh.get_surface_area(),
    )


def timed(call: Callable[[], object]) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def bench_uploads(sizes: list[int], repeats: int) -> list[str]:
    import httpx

    have_open3d = _importable("open3d")
    files = {size: stl_file(size) for size in sizes}
    rows = []
    with server() as base, httpx.Client(timeout=600) as client:
        for size in sizes:
            path = files[size]
            data = path.read_bytes()
            peers: dict[str, Callable[[], object]] = {
                "trimesh process=True": partial(trimesh_report, data, True),
                "trimesh process=False": partial(trimesh_report, data, False),
            }
            if have_open3d:
                peers["Open3D"] = partial(open3d_report, path)
            ours = partial(upload, client, base, path.name, data)
            faces = ours()  # warm-up: kernels, caches
            if faces != size:
                raise RuntimeError(f"the report says {faces:,} faces, not {size:,}")
            for call in peers.values():
                call()
            samples: dict[str, list[float]] = {"ours": [], **{name: [] for name in peers}}
            for _ in range(repeats):
                samples["ours"].append(timed(ours))
                for name, call in peers.items():
                    samples[name].append(timed(call))
            median_ours = statistics.median(samples["ours"])
            cells = [f"{median_ours:.3f} / {min(samples['ours']):.3f}"]
            ratios = []
            for name in ("trimesh process=True", "trimesh process=False", "Open3D"):
                if name in samples:
                    median = statistics.median(samples[name])
                    cells.append(f"{median:.3f} / {min(samples[name]):.3f}")
                    ratios.append(f"{median / median_ours:.2f}x")
                else:
                    cells.append("")
                    ratios.append("")
            target = (
                f"< {TARGET_UPLOAD} s: {'met' if median_ours < TARGET_UPLOAD else 'MISSED'}"
                if size == 871_414
                else ""
            )
            rows.append(
                f"| {size:,} | {len(data) / 2**20:.1f} MiB | "
                + " | ".join(cells)
                + " | "
                + " | ".join(ratios)
                + f" | {target} |"
            )
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


def _importable(name: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(name) is not None


def _vm_hwm(pid: int) -> int:
    """The peak resident memory of a live process in bytes (0 once it is gone)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0
    match = re.search(r"^VmHWM:\s+(\d+) kB", status, re.MULTILINE)
    return int(match.group(1)) * 1024 if match else 0


#: The CLI's progress lines by their first word, and what each stage does.
STAGES = {
    "reading": "read + weld",
    "computing": "normals",
    "checking": "report",
    "writing": "write .npy",
}
_STAGE = re.compile(r"\[\s*([\d.]+) s\] ([^\r\n]*)")


def run_cli(args: list[str]) -> tuple[float, int, dict[str, float], str]:
    """Wall seconds, peak RSS in bytes, seconds per CLI stage and stdout of one command.

    The peak comes from GNU time (``%M``) when ``/usr/bin/time`` exists, else from polling the
    child's ``VmHWM``. Not ``getrusage``/``wait4`` of our own child: Linux carries the parent's
    high-water mark across ``vfork`` + ``exec`` into the child's ``ru_maxrss``, so every
    command measured from this (large) process would report at least this process's peak.
    """
    gnu_time = Path("/usr/bin/time")
    with tempfile.TemporaryDirectory() as tmp:
        out, err, peak_file = (Path(tmp) / name for name in ("out", "err", "peak"))
        command = [CLI, "--progress", *args]
        if gnu_time.exists():
            command = [str(gnu_time), "-f", "%M", "-o", str(peak_file), *command]
        high_water = 0
        with out.open("w") as stdout_file, err.open("w") as stderr_file:
            start = time.perf_counter()
            process = subprocess.Popen(command, stdout=stdout_file, stderr=stderr_file)
            while process.poll() is None and not gnu_time.exists():
                high_water = max(high_water, _vm_hwm(process.pid))
                time.sleep(0.05)
            process.wait()
            wall = time.perf_counter() - start
        stdout, stderr = out.read_text(), err.read_text()
        peak = int(peak_file.read_text().split()[-1]) * 1024 if gnu_time.exists() else high_water
    if process.returncode not in (0, 1):
        raise RuntimeError(f"mesh-normal {' '.join(args)} exited {process.returncode}: {stderr}")
    marks = [
        (float(m.group(1)), STAGES.get(m.group(2).split(" ")[0], m.group(2)))
        for m in _STAGE.finditer(stderr)
    ]
    stages: dict[str, float] = {}
    for (at, stage), (until, _) in itertools.pairwise(marks):
        stages[stage] = stages.get(stage, 0.0) + until - at
    if marks:  # before the first mark: start-up and imports; after the last: exit
        stages["start-up + exit"] = wall - marks[-1][0]
    return wall, peak, stages, stdout


def bench_lucy(runs: int) -> list[str]:
    small = stl_file(SIZES[0])
    output = CACHE / "normals.npy"
    run_cli(["normals", str(small), "--kind", "vertex", "-o", str(output)])  # the files read once
    lucy = stl_file(LUCY)
    rows = []
    commands = [
        (
            "normals --kind vertex -o OUT.npy",
            ["normals", str(lucy), "--kind", "vertex", "-o", str(output)],
        )
    ] * runs
    commands.append(("analyze", ["analyze", str(lucy)]))
    for label, args in commands:
        wall, rss, stages, _ = run_cli(args)
        stage_text = ", ".join(f"{name} {seconds:.1f} s" for name, seconds in stages.items())
        limit = TARGET_LUCY_ANALYZE_SECONDS if label == "analyze" else TARGET_LUCY_SECONDS
        verdict = (
            f"{'met' if wall < limit else 'MISSED'} / "
            f"{'met' if rss < TARGET_LUCY_RSS else 'MISSED'}"
        )
        rows.append(
            f"| `mesh-normal {label}` | {wall:.1f} | {rss / 2**30:.2f} | {stage_text} | {verdict} |"
        )
        print(rows[-1], file=sys.stderr, flush=True)
    output.unlink(missing_ok=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--lucy-runs", type=int, default=2)
    parser.add_argument("--skip-lucy", action="store_true")
    parser.add_argument("--skip-readers", action="store_true")
    tables.add_option(parser)
    args = parser.parse_args()
    if not args.skip_readers:  # the file readers against trimesh's (benchmarks/readers.py)
        from benchmarks import readers

        reader_repeats = min(args.repeats, 5)
        print(
            readers.table(
                readers.bench(list(readers.FILES), readers.SIZE, reader_repeats), reader_repeats
            )
        )

    out = tables.Report(args.markdown)  # the uploads and the Lucy runs (readers: their own)
    rows = bench_uploads(args.sizes, args.repeats)
    out.print(
        f"\n| triangles | binary STL | ours: POST /api/mesh, median / best of {args.repeats} (s) "
        "| trimesh process=True, median / best (s) | trimesh process=False (s) | Open3D (s) "
        "| trimesh process=True / ours | process=False / ours | Open3D / ours | target |"
    )
    out.print("|---:|---:|" + "---:|" * 7 + "---|")
    out.print("\n".join(rows))
    if not args.skip_lucy:
        rows = bench_lucy(args.lucy_runs)
        size = (84 + 50 * LUCY) / 2**20
        out.print(
            f"\n| {LUCY:,} triangles, binary STL ({size:,.0f} MiB) | wall (s) | peak RSS (GiB) "
            "| stages (the CLI's --progress) | 30 s (analyze 15 s) / 6 GiB |"
        )
        out.print("|---|---:|---:|---|---|")
        out.print("\n".join(rows))
    out.write()


if __name__ == "__main__":
    main()
