"""Peak memory per MB of upload, for every format and every heavy path.

    make bench-memory     # or: .venv/bin/python -m benchmarks.memory [--mb 25] [--jobs 4]
    .venv/bin/python -m benchmarks.memory --markdown PATH   # also writes the table to PATH

Each format gets a torus of about ``--mb`` megabytes of file (its own vertices, shared by its
triangles; STL repeats them per corner as STL does). Each (format, path) runs in a fresh
process: after the imports, the workers' warm-up (``app.mesh.warmup.warm``: every job once on
small files) and a warm-up run of the same path on a small torus (so every module a job needs
is loaded and Python's caches are warm, as in the server's job workers) and with the allocator
set as the server's job workers set it (``tune_allocator``: blocks of 1 MB or more mapped on
their own; for a large binary STL, freed memory kept within the job and its memory faulted in
ahead, ``app.mesh.work.ahead``, whose pages count), the peak resident set is reset
(``/proc/self/clear_refs``), the file's bytes are read into memory as an upload is, and the path
runs once. The figure is the peak resident memory above that baseline (``VmHWM`` minus
``VmRSS`` before the upload was read), divided by the file's size: the upload's own bytes count
(1.0 of each figure), as they do on a server.

Paths: ``read`` (``read_mesh``), ``report`` (``analyse_mesh`` + ``build_report`` and its JSON,
as ``POST /api/mesh`` does), ``face``, ``vertex``, ``corner`` (the normals as ``.npy``, made
and written a block of faces at a time by ``normals_to_write`` and ``normals_blocks``, as the
server streams them), ``corner-json`` (the same as JSON) and ``fix`` (``orient`` +
``write_mesh`` in the upload's format, PLY for those not writable, as ``POST /api/mesh/fix``).
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from benchmarks import tables

FORMATS = ("stl", "stl-ascii", "obj", "ply", "ply-ascii", "off", "glb")
PATHS = ("read", "report", "face", "vertex", "corner", "corner-json", "fix")
#: About how many bytes of file each vertex of the torus takes (it has two triangles a vertex).
_BYTES_PER_VERTEX = {
    "stl": 100,
    "stl-ascii": 560,
    "obj": 90,
    "ply": 50,
    "ply-ascii": 80,
    "off": 80,
    "glb": 36,
}
_SUFFIX = {"stl-ascii": "stl", "ply-ascii": "ply"}


def torus(rings: int, segments: int) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A closed torus of ``rings * segments`` vertices and twice as many triangles, outward."""
    u = np.linspace(0, 2 * np.pi, rings, endpoint=False)[:, None]
    v = np.linspace(0, 2 * np.pi, segments, endpoint=False)[None, :]
    radius = 2.0 + 0.7 * np.cos(v)
    points = np.stack(
        [radius * np.cos(u), radius * np.sin(u), 0.7 * np.sin(v) + 0 * u], axis=-1
    ).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = i * segments + j
    b = ((i + 1) % rings) * segments + j
    c = ((i + 1) % rings) * segments + (j + 1) % segments
    d = i * segments + (j + 1) % segments
    faces = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)], axis=-1)
    return points, faces.reshape(-1, 3)


def _floats(array: NDArray[np.float64]) -> list[str]:
    return [" ".join(map(repr, row)) for row in array.tolist()]


def file_bytes(kind: str, points: NDArray[np.float64], faces: NDArray[np.int64]) -> bytes:
    """The torus as a file of ``kind``."""
    from mesh_normal.files import write_mesh

    if kind in ("stl", "obj", "ply"):
        return write_mesh(points, faces, kind)
    if kind == "stl-ascii":
        corners = points.astype(np.float32).astype(np.float64)[faces]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        lines = ["solid torus"]
        for n, (a, b, c) in zip(_floats(normal), corners.reshape(-1, 3, 3).tolist(), strict=True):
            lines += [f"facet normal {n}", "outer loop"]
            lines += [f"vertex {x!r} {y!r} {z!r}" for x, y, z in (a, b, c)]
            lines += ["endloop", "endfacet"]
        lines.append("endsolid torus\n")
        return "\n".join(lines).encode()
    if kind == "ply-ascii":
        header = (
            f"ply\nformat ascii 1.0\nelement vertex {len(points)}\nproperty double x\n"
            f"property double y\nproperty double z\nelement face {len(faces)}\n"
            "property list uchar int vertex_indices\nend_header\n"
        )
        rows = [f"3 {a} {b} {c}" for a, b, c in faces.tolist()]
        return (header + "\n".join([*_floats(points), *rows, ""])).encode()
    if kind == "off":
        rows = [f"3 {a} {b} {c}" for a, b, c in faces.tolist()]
        head = f"OFF\n{len(points)} {len(faces)} 0\n"
        return (head + "\n".join([*_floats(points), *rows, ""])).encode()
    return _glb(points.astype(np.float32), faces.astype(np.uint32))


def _glb(points: NDArray[np.float32], faces: NDArray[np.uint32]) -> bytes:
    binary = points.tobytes() + faces.tobytes()
    document = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": points.nbytes},
            {"buffer": 0, "byteOffset": points.nbytes, "byteLength": faces.nbytes},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": len(points),
                "type": "VEC3",
                "min": points.min(axis=0).tolist(),
                "max": points.max(axis=0).tolist(),
            },
            {"bufferView": 1, "componentType": 5125, "count": faces.size, "type": "SCALAR"},
        ],
    }
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
    chunks += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


def make_file(kind: str, megabytes: float, folder: Path) -> Path:
    vertices = megabytes * 1e6 / _BYTES_PER_VERTEX[kind]
    side = max(8, math.isqrt(int(vertices)))
    path = folder / f"torus-{kind}.{_SUFFIX.get(kind, kind)}"
    path.write_bytes(file_bytes(kind, *torus(side, side)))
    return path


def run_path(path_name: str, data: bytes, filename: str) -> None:
    """One path of the server's work on the upload ``data``."""
    from mesh_normal.files import read_mesh, write_mesh
    from mesh_normal.files.formats import WRITABLE
    from mesh_normal.files.normals import normals_blocks, normals_to_write
    from mesh_normal.mesh.orientation import orient
    from mesh_normal.mesh.report.analysis import analyse_mesh, build_report

    mesh = read_mesh(data, filename)
    if path_name == "report":
        build_report(analyse_mesh(mesh, filename, len(data))).to_json()
    elif path_name in ("face", "vertex", "corner", "corner-json"):
        # As the server answers: the normals computed (corner normals made a block at a time
        # as they are written), then written in blocks as they are sent.
        kind = "corner" if path_name == "corner-json" else path_name
        normals, missing = normals_to_write(mesh, kind, "angle", 30.0)  # type: ignore[arg-type]
        chosen = "json" if path_name == "corner-json" else "npy"
        for _block in normals_blocks(normals, missing, kind, "angle", 30.0, chosen):  # type: ignore[arg-type]
            pass
    elif path_name == "fix":
        fixed = orient(mesh.checked())
        chosen = mesh.format if mesh.format in WRITABLE else WRITABLE[0]
        write_mesh(mesh.vertices, fixed.faces, chosen, vertex_colors=mesh.vertex_colors)


def _status(field: str) -> int:
    """A line of ``/proc/self/status`` in bytes (``VmRSS``, ``VmHWM``)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024
    raise LookupError(field)


def child(path_name: str, file: Path, small: Path) -> None:
    """Measure one path in this (fresh) process and print its peak in bytes."""
    from app.mesh.warmup import warm
    from app.mesh.work import ahead
    from app.web.workers import tune_allocator
    from mesh_normal import allocator
    from mesh_normal.files import stl
    from mesh_normal.workers import MAPPED_FROM

    tune_allocator()  # as the server's job workers do when they start
    allocator.enable_jobs()
    warm()  # so do they: every job once, on small files
    run_path(path_name, small.read_bytes(), small.name)  # warm-up: this path's modules loaded
    gc.collect()
    Path("/proc/self/clear_refs").write_text("5")  # reset the peak to the current size
    baseline = _status("VmRSS")
    data = file.read_bytes()
    if stl.is_binary(data):  # as a worker's job does before it reads a binary STL
        ahead(len(data))
    run_path(path_name, data, file.name)
    allocator.end_job(MAPPED_FROM)  # its prefaulting ended (its pages counted), as a worker's
    print(json.dumps({"peak": _status("VmHWM") - baseline, "size": len(data)}))


def measure(path_name: str, file: Path, small: Path) -> float:
    command = [
        sys.executable,
        "-m",
        "benchmarks.memory",
        "--child",
        path_name,
        str(file),
        str(small),
    ]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode:
        print(f"{file.name} {path_name}: failed\n{done.stderr[-2000:]}", file=sys.stderr)
        return math.nan
    found = json.loads(done.stdout.strip().splitlines()[-1])
    return float(found["peak"]) / found["size"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--mb", type=float, default=25.0, help="file size per format, in MB")
    parser.add_argument("--jobs", type=int, default=max(1, min(4, (os.cpu_count() or 2) // 2)))
    parser.add_argument("--formats", default=",".join(FORMATS))
    parser.add_argument("--paths", default=",".join(PATHS))
    parser.add_argument("--child", nargs=3, metavar=("PATH", "FILE", "SMALL"))
    tables.add_option(parser)
    arguments = parser.parse_args()
    if arguments.child:
        path_name, file, small = arguments.child
        child(path_name, Path(file), Path(small))
        return
    out = tables.Report(arguments.markdown)
    formats, paths = arguments.formats.split(","), arguments.paths.split(",")
    with tempfile.TemporaryDirectory() as folder:
        files = {kind: make_file(kind, arguments.mb, Path(folder)) for kind in formats}
        (Path(folder) / "small").mkdir()
        smalls = {kind: make_file(kind, 0.05, Path(folder) / "small") for kind in formats}
        jobs = [(kind, name) for kind in formats for name in paths]
        with ThreadPoolExecutor(arguments.jobs) as pool:
            figures = dict(
                zip(
                    jobs,
                    pool.map(lambda job: measure(job[1], files[job[0]], smalls[job[0]]), jobs),
                    strict=True,
                )
            )
        sizes = {kind: files[kind].stat().st_size / 1e6 for kind in formats}
    print("Peak resident memory per MB of upload (the upload's own bytes included):\n")
    out.print("| format | file MB | " + " | ".join(paths) + " |")
    out.print("|---|---:|" + "---:|" * len(paths))
    for kind in formats:
        row = " | ".join(f"{figures[kind, name]:.1f}" for name in paths)
        out.print(f"| {kind} | {sizes[kind]:.1f} | {row} |")
    out.write()


if __name__ == "__main__":
    main()
