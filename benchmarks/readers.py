"""The file readers against trimesh's, on the same bytes: OBJ, PLY (binary and ASCII) and OFF.

    make bench-readers    # or: .venv/bin/python -m benchmarks.readers [--size 871414] [--repeats 5]

Each file is :func:`benchmarks.mesh_kernels.torus_mesh` (its faces shuffled) at the Dragon size,
written once into ``$MESH_E2E_DIR`` (default ``/tmp/mesh-e2e``) and reused: OBJ with 6 and with
17 significant digits, binary PLY, ASCII PLY and OFF (the shortest round-trip text, up to 17
digits). Per round, alternating, in this process with the file's bytes in memory: ours is
``read_mesh(data, name)`` (every vertex kept, checked, read-only arrays); trimesh is
``trimesh.load(BytesIO(data), file_type=..., process=False)``. The OBJ rows are also timed as
a whole report (``read_mesh`` + ``analyse_mesh`` + ``build_report`` and its JSON, as
``POST /api/mesh`` does without HTTP): the target is at most 0.4 times trimesh's load. Best
and median of ``--repeats`` rounds after one warm-up; the machine is shared, so only the
ratios within one run count. ``--markdown PATH`` also writes the table to a file, after a
line naming the machine, its load and the date.
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from benchmarks import tables
from benchmarks.mesh_kernels import torus_mesh

SIZE = 871_414
CACHE = Path(os.environ.get("MESH_E2E_DIR", "/tmp/mesh-e2e"))
#: The target for the OBJ report, as a share of trimesh's load.
TARGET_OBJ = 0.4
#: Lines written at once.
_CHUNK = 1 << 16


def _text(
    vertices: np.ndarray, faces: np.ndarray, vertex: str, face: str, head: str, first: int
) -> bytes:
    """``head`` then a line per vertex (``vertex % (x, y, z)``) and per face (``face``)."""
    parts = [head.encode()]
    for rows, pattern, add in ((vertices, vertex, 0), (faces, face, first)):
        for start in range(0, len(rows), _CHUNK):
            block = (rows[start : start + _CHUNK] + add).tolist()
            parts.append("".join(pattern % tuple(row) for row in block).encode())
    return b"".join(parts)


def _ply_ascii(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    head = (
        f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\nproperty double x\n"
        f"property double y\nproperty double z\nelement face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    return _text(vertices, faces, "%r %r %r\n", "3 %d %d %d\n", head, 0)


def _write(kind: str, vertices: np.ndarray, faces: np.ndarray) -> bytes:
    from mesh_normal.files import write_mesh

    if kind == "obj6":
        return _text(vertices, faces, "v %.6g %.6g %.6g\n", "f %d %d %d\n", "", 1)
    if kind == "obj17":
        return _text(vertices, faces, "v %.17g %.17g %.17g\n", "f %d %d %d\n", "", 1)
    if kind == "ply":
        return write_mesh(vertices, faces, "ply")
    if kind == "ply-ascii":
        return _ply_ascii(vertices, faces)
    head = f"OFF\n{len(vertices)} {len(faces)} 0\n"
    return _text(vertices, faces, "%r %r %r\n", "3 %d %d %d\n", head, 0)


#: Each file: its name's suffix, trimesh's file type, and what it holds.
FILES = {
    "obj6": ("obj", "OBJ, 6 significant digits"),
    "obj17": ("obj", "OBJ, 17 significant digits"),
    "ply": ("ply", "PLY, binary"),
    "ply-ascii": ("ply", "PLY, ASCII"),
    "off": ("off", "OFF"),
}


def mesh_file(kind: str, size: int) -> Path:
    """The torus of ``size`` faces as ``kind``, written once and reused."""
    suffix, _ = FILES[kind]
    path = CACHE / f"readers-{kind}-{size}.{suffix}"
    if path.exists():
        return path
    CACHE.mkdir(parents=True, exist_ok=True)
    print(f"writing {path} ...", file=sys.stderr, flush=True)
    vertices, faces = torus_mesh(size)
    partial = path.with_suffix(".partial")
    partial.write_bytes(_write(kind, vertices, faces))
    partial.replace(path)
    return path


def ours_read(data: bytes, name: str) -> None:
    from mesh_normal.files import read_mesh

    read_mesh(data, name)


def ours_report(data: bytes, name: str) -> None:
    from mesh_normal.files import read_mesh
    from mesh_normal.mesh.report.analysis import analyse_mesh, build_report

    mesh = read_mesh(data, name)
    build_report(analyse_mesh(mesh, name, len(data))).to_json()


def trimesh_load(data: bytes, file_type: str) -> None:
    import trimesh

    trimesh.load(io.BytesIO(data), file_type=file_type, process=False)


def _timed(call: Callable[[], object]) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def bench(kinds: list[str], size: int, repeats: int) -> list[str]:
    rows = []
    for kind in kinds:
        suffix, label = FILES[kind]
        path = mesh_file(kind, size)
        data, name = path.read_bytes(), path.name
        calls: dict[str, Callable[[], object]] = {
            "read": partial(ours_read, data, name),
            "trimesh": partial(trimesh_load, data, suffix),
        }
        if suffix == "obj":
            calls["report"] = partial(ours_report, data, name)
        for call in calls.values():  # warm-up: kernels, caches
            call()
        samples: dict[str, list[float]] = {key: [] for key in calls}
        for _ in range(repeats):
            for key, call in calls.items():
                samples[key].append(_timed(call))
        best = {key: min(values) for key, values in samples.items()}
        median = {key: statistics.median(values) for key, values in samples.items()}
        for what in ("read", "report"):
            if what not in samples:
                continue
            ratio_best = best[what] / best["trimesh"]
            ratio_median = median[what] / median["trimesh"]
            target = 1.0 if what == "read" else TARGET_OBJ
            met = "met" if ratio_median <= target else "MISSED"
            rows.append(
                f"| {label} | {len(data) / 2**20:.1f} | {what} | "
                f"{median[what]:.3f} / {best[what]:.3f} | "
                f"{median['trimesh']:.3f} / {best['trimesh']:.3f} | "
                f"{ratio_median:.2f} / {ratio_best:.2f} | ≤ {target} ({met}) |"
            )
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


def table(rows: list[str], repeats: int, size: int = SIZE) -> str:
    head = (
        f"| file ({size:,} faces) | MiB | ours timed | ours, median / best of {repeats} (s) "
        "| trimesh load(process=False) (s) | ours / trimesh, median / best | target |"
    )
    return "\n".join([head, "|---|---:|---|---:|---:|---:|---|", *rows])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=SIZE)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--formats", default=",".join(FILES))
    tables.add_option(parser)
    args = parser.parse_args()
    out = tables.Report(args.markdown)
    rows = bench(args.formats.split(","), args.size, args.repeats)
    out.print("\n" + table(rows, args.repeats, args.size))
    out.write()


if __name__ == "__main__":
    main()
