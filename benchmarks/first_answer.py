"""The first answer: a mesh reported by a new process, from a fresh environment, beside trimesh.

``make bench-first`` (``.venv/bin/python -m benchmarks.first_answer --mesh PATH``):

- builds the library's wheel (``uv build``) and installs it alone into a new virtual
  environment, as ``pip install mesh-normal`` would (its size is reported: target 230 MB);
- in that environment, ``python -c "import mesh_normal as mn; mn.analyse(PATH)"``: the first
  run ever (no bytecode, no cache of any kind), then the best and median of later runs, against
  trimesh's ``load(process=True)`` with its checks (watertight, winding, volume, normals) in the
  same environment, alternating (target: at most 0.3 of trimesh's);
- the work alone (a second ``analyse`` in the same process) and ``mesh-normal analyze PATH``
  (target 0.8 s);
- a fresh server from the checkout (``uvicorn app.main:app``, its workers, empty caches): the
  seconds from its first page to the answer of its first ``POST /api/mesh`` (target 3 s).

``--mesh`` defaults to a generated torus OBJ of 56,172 faces; the docs' table is from the
Stanford bunny as MeshLab ships it (``sample/bunny70k.ply``, written as OBJ). Then the figures
as a Markdown table (``--markdown PATH`` also writes it).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import tables
from benchmarks.mesh_kernels import torus_mesh
from benchmarks.startup import serve

ROOT = Path(__file__).resolve().parent.parent
VENV_BIN = Path(sys.executable).parent
PORT = 19873

OURS = "import mesh_normal as mn, sys; mn.analyse(sys.argv[1])"
TRIMESH = (
    "import sys, trimesh; m = trimesh.load(sys.argv[1], process=True); "
    "m.is_watertight, m.is_winding_consistent, m.volume, m.face_normals, m.vertex_normals"
)
WORK = (
    "import sys, time, mesh_normal as mn; mn.analyse(sys.argv[1]); t = time.perf_counter(); "
    "mn.analyse(sys.argv[1]); print(time.perf_counter() - t)"
)


def uv() -> str:
    found = shutil.which("uv", path=str(VENV_BIN)) or shutil.which("uv")
    return found or str(ROOT / ".tools" / "bin" / "uv")


def fresh_environment(folder: Path) -> Path:
    """The wheel built from the checkout and installed alone into ``folder/env``."""
    environment = {**os.environ, "UV_PYTHON_DOWNLOADS": "never"}
    run = {"check": True, "capture_output": True, "env": environment}
    subprocess.run([uv(), "build", "--no-config", "--wheel", "--out-dir", str(folder / "dist"),
                    str(ROOT)], cwd=folder, **run)  # fmt: skip
    (wheel,) = (folder / "dist").glob("*.whl")
    subprocess.run([uv(), "venv", "--quiet", "--python", sys.executable, str(folder / "env")],
                   cwd=folder, **run)  # fmt: skip
    python = folder / "env" / "bin" / "python"
    subprocess.run([uv(), "pip", "install", "--quiet", "--python", str(python), str(wheel)],
                   cwd=folder, **run)  # fmt: skip
    return python.parent


def megabytes(folder: Path) -> float:
    return sum(path.stat().st_size for path in folder.rglob("*") if path.is_file()) / 1e6


def timed(command: list[str], cwd: Path) -> float:
    started = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, cwd=cwd)
    return time.perf_counter() - started


def torus_obj(path: Path) -> None:
    vertices, faces = torus_mesh(56_172)
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    path.write_text("\n".join(lines) + "\n")


def first_upload(mesh: Path) -> float:
    """Seconds from a fresh server's first page to the answer of its first mesh upload."""
    _, (seconds,) = serve("app.main:app", PORT, "/", 1, (mesh.name, mesh.read_bytes()))
    return seconds


def figures(values: list[float]) -> tuple[float, float]:
    return min(values), statistics.median(values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", type=Path, help="the mesh (default: a torus OBJ, 56,172 faces)")
    parser.add_argument("--runs", type=int, default=7, help="later runs of each (default 7)")
    tables.add_option(parser)
    args = parser.parse_args()
    out = tables.Report(args.markdown)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        mesh = args.mesh.resolve() if args.mesh else folder / "torus.obj"
        if args.mesh is None:
            torus_obj(mesh)
        env = fresh_environment(folder)
        size = megabytes(folder / "env")
        python = str(env / "python")
        work = folder / "work"  # not the checkout: its sources would shadow the wheel
        work.mkdir()
        ours_first = timed([python, "-c", OURS, str(mesh)], work)
        theirs_first = timed([python, "-c", TRIMESH, str(mesh)], work)
        ours, theirs = [], []
        for _ in range(args.runs):
            ours.append(timed([python, "-c", OURS, str(mesh)], work))
            theirs.append(timed([python, "-c", TRIMESH, str(mesh)], work))
        alone = subprocess.run([python, "-c", WORK, str(mesh)], check=True, capture_output=True,
                               text=True, cwd=work).stdout  # fmt: skip
        cli = [timed([str(env / "mesh-normal"), "analyze", str(mesh)], work)
               for _ in range(args.runs)]  # fmt: skip
    upload = first_upload(mesh)
    ours_best, ours_median = figures(ours)
    theirs_best, theirs_median = figures(theirs)
    cli_best, cli_median = figures(cli)
    print(f"environment: {size:.0f} MB")
    out.print(f"\nThe mesh: {mesh.name} ({mesh.stat().st_size / 1e6:.1f} MB); later runs: "
              f"{args.runs} each, alternating.\n")  # fmt: skip
    out.print("| what | ours | trimesh, same run | ours / trimesh | target |")
    out.print("|---|---:|---:|---:|---:|")
    out.print(f"| `analyse` in a new process, first run ever | {ours_first:.2f} s "
              f"| {theirs_first:.2f} s | {ours_first / theirs_first:.2f} | 0.3 |")  # fmt: skip
    out.print(f"| the same, later runs (best) | {ours_best:.2f} s | {theirs_best:.2f} s "
              f"| {ours_best / theirs_best:.2f} | 0.3 |")  # fmt: skip
    out.print(f"| the same, later runs (median) | {ours_median:.2f} s | {theirs_median:.2f} s "
              f"| {ours_median / theirs_median:.2f} | 0.3 |")  # fmt: skip
    out.print(f"| the work alone (a second `analyse`) | {float(alone):.3f} s | | | |")
    out.print(f"| `mesh-normal analyze` (best, median) | {cli_best:.2f} s, {cli_median:.2f} s "
              "| | | 0.8 s |")  # fmt: skip
    out.print(f"| a fresh server's first upload (`POST /api/mesh`) | {upload:.2f} s | | | 3 s |")
    out.print(f"| the library's fresh environment | {size:.0f} MB | | | 230 MB |")
    out.write()


if __name__ == "__main__":
    main()
