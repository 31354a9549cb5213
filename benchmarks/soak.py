"""A soak: mixed traffic against one uvicorn worker with a memory limit, as public servers meet.

    make bench-soak       # or: .venv/bin/python -m benchmarks.soak [--seconds 60] [--limit-gb 4]

One worker (``uvicorn app.main:app --workers 1``) runs under ``prlimit --as`` (its address space
capped at ``--limit-gb``). For ``--seconds``, eight client threads send, at random:

- calculator requests (``POST /api/normal``) and pages (``GET /``, ``GET /mesh``);
- mesh uploads of every format (binary and ASCII STL, OBJ, binary and ASCII PLY, OFF, GLB, a
  .gltf with its .bin as two files, a .zip) to ``/api/mesh``, ``/api/mesh/normals`` (face,
  vertex and corner normals as JSON, CSV and .npy) and ``/api/mesh/fix``, of 1 to 20 MB;
- a few that are too large or hostile (a body over the upload limit, a PLY whose header claims
  a billion faces, a truncated STL, a zip bomb).

A separate probe thread times ``GET /`` every 50 ms. Reported: every status code with its count,
whether any 5xx other than a planned 503 came back, whether the worker process lived to the end,
its resident memory before and after (each once steady for 3 s: the workers warm up as they
start), and the probe's p50 / p99 / max; then one row of all that as a Markdown table, which
``--markdown PATH`` also writes to a file after a line naming the machine and the date.
The targets: no unplanned 5xx, no process death, resident memory back within 20 %
of its start, ``GET /`` p99 under 0.5 s.
"""

from __future__ import annotations

import argparse
import collections
import io
import os
import random
import shutil
import socket
import statistics
import subprocess
import sys
import threading
import time
import zipfile
from collections.abc import Callable
from pathlib import Path

import httpx
import numpy as np
import trimesh

from benchmarks import tables
from mesh_normal.files import write_mesh

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
CALCULATOR = {"a": [1.5, -2.25, 0.1], "b": [4.0, 0.5, -3.0], "c": [0.3, 7.0, 2.5]}


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def resident_mb(pid: int) -> float:
    """The resident memory of the process and all its descendants (worker processes)."""
    return sum(family_mb(pid).values())


def family_mb(pid: int) -> dict[int, float]:
    """The resident memory of the process and each of its descendants, by process id."""
    parents: dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents[int(stat.parent.name)] = int(fields[1])
    family = {pid}
    grown = True
    while grown:
        grown = False
        for child, parent in parents.items():
            if parent in family and child not in family:
                family.add(child)
                grown = True
    sizes: dict[int, float] = {}
    for member in sorted(family):
        try:
            for line in Path(f"/proc/{member}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    sizes[member] = int(line.split()[1]) / 1024
        except OSError:
            continue
    return sizes


def settled(pid: int, seconds: float = 3, within: float = 0.01) -> float:
    """The resident memory of the process and its descendants once it has stayed within
    ``within`` (a fraction) for ``seconds`` (at most two minutes)."""
    deadline = time.monotonic() + 120
    last = resident_mb(pid)
    steady_since = time.monotonic()
    while time.monotonic() < deadline:
        time.sleep(0.5)
        now = resident_mb(pid)
        if abs(now - last) > within * last:
            last, steady_since = now, time.monotonic()
        elif time.monotonic() - steady_since >= seconds:
            return now
    return last


def torus(triangles: int) -> tuple[np.ndarray, np.ndarray]:
    minor = max(8, int(np.sqrt(triangles / 8)))
    mesh = trimesh.creation.torus(1.0, 0.3, major_sections=4 * minor, minor_sections=minor)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def ascii_stl(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    out = io.StringIO()
    out.write("solid soak\n")
    for a, b, c in vertices[faces]:
        out.write(
            "facet normal 0 0 0\nouter loop\n"
            f"vertex {a[0]:.9g} {a[1]:.9g} {a[2]:.9g}\nvertex {b[0]:.9g} {b[1]:.9g} {b[2]:.9g}\n"
            f"vertex {c[0]:.9g} {c[1]:.9g} {c[2]:.9g}\nendloop\nendfacet\n"
        )
    out.write("endsolid soak\n")
    return out.getvalue().encode()


def off_text(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    lines = [f"OFF\n{len(vertices)} {len(faces)} 0"]
    lines += [f"{x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    lines += [f"3 {a} {b} {c}" for a, b, c in faces]
    return ("\n".join(lines) + "\n").encode()


def glb(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    data: bytes = trimesh.Trimesh(vertices, faces, process=False).export(file_type="glb")
    return data


def uploads(megabytes: float) -> dict[str, list[tuple[str, bytes]]]:
    """Every format, about ``megabytes`` each (binary STL is 50 bytes a triangle)."""
    vertices, faces = torus(int(megabytes * 2**20 / 50))
    files: dict[str, list[tuple[str, bytes]]] = {
        "stl": [("t.stl", write_mesh(vertices, faces, "stl"))],
        "obj": [("t.obj", write_mesh(vertices, faces, "obj"))],
        "ply": [("t.ply", write_mesh(vertices, faces, "ply"))],
        "glb": [("t.glb", glb(vertices, faces))],
    }
    small_v, small_f = torus(int(megabytes * 2**20 / 300))
    files["ascii stl"] = [("a.stl", ascii_stl(small_v, small_f))]
    files["off"] = [("t.off", off_text(small_v, small_f))]
    ascii_ply = trimesh.Trimesh(small_v, small_f, process=False)
    files["ascii ply"] = [("a.ply", bytes(ascii_ply.export(file_type="ply", encoding="ascii")))]
    files["gltf + bin"] = [
        ("Box.gltf", (DATA / "gltf" / "Box.gltf").read_bytes()),
        ("Box0.bin", (DATA / "gltf" / "Box0.bin").read_bytes()),
    ]
    archive = io.BytesIO()
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zipped:
        zipped.writestr("t.obj", files["obj"][0][1])
    files["zip"] = [("t.zip", archive.getvalue())]
    return files


def hostile(limit_mb: int) -> dict[str, list[tuple[str, bytes]]]:
    bomb = io.BytesIO()
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zipped:
        zipped.writestr("big.obj", b"v 0 0 0\n" * (2**27 // 8))  # 128 MB of text
    return {
        "too large": [("big.stl", b"\0" * ((limit_mb + 1) * 2**20))],
        "lying ply": [
            (
                "lie.ply",
                b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                b"property float y\nproperty float z\nelement face 1000000000\n"
                b"property list uchar int vertex_indices\nend_header\n" + b"\0" * 36,
            )
        ],
        "truncated stl": [("cut.stl", b"\0" * 80 + (10**6).to_bytes(4, "little") + b"\0" * 500)],
        "zip bomb": [("bomb.zip", bomb.getvalue())],
    }


class Soak:
    def __init__(self, base: str, seconds: float, files: dict[str, list[tuple[str, bytes]]]):
        self.base, self.seconds, self.files = base, seconds, files
        self.statuses: collections.Counter[tuple[str, int]] = collections.Counter()
        self.unplanned: list[str] = []
        self.probe: list[float] = []
        self.lock = threading.Lock()
        self.stop = time.monotonic() + seconds

    def record(self, kind: str, response: httpx.Response | None, error: str = "") -> None:
        status = response.status_code if response is not None else 0
        with self.lock:
            self.statuses[(kind, status)] += 1
            if (status >= 500 and status != 503) or response is None:
                said = error or ("" if response is None else response.text[:120])
                self.unplanned.append(f"{kind}: {status} {said}")

    def client(self, seed: int) -> None:
        rng = random.Random(seed)
        actions: list[tuple[float, Callable[[httpx.Client], tuple[str, httpx.Response]]]] = [
            (3, lambda c: ("calculator", c.post(self.base + "/api/normal", json=CALCULATOR))),
            (2, lambda c: ("page /", c.get(self.base + "/"))),
            (1, lambda c: ("page /mesh", c.get(self.base + "/mesh"))),
            (4, lambda c: self.mesh(c, rng)),
        ]
        weights = [w for w, _ in actions]
        with httpx.Client(timeout=120) as http:
            while time.monotonic() < self.stop:
                _, action = rng.choices(actions, weights)[0]
                try:
                    kind, response = action(http)
                    self.record(kind, response)
                except httpx.HTTPError as error:
                    self.record("transport", None, repr(error))

    def mesh(self, http: httpx.Client, rng: random.Random) -> tuple[str, httpx.Response]:
        kind = rng.choice(list(self.files))
        parts = [("file", part) for part in self.files[kind]]
        route = rng.choice(["report", "report", "normals", "fix"])
        if route == "report":
            return f"{kind} report", http.post(self.base + "/api/mesh", files=parts)
        if route == "fix":
            return f"{kind} fix", http.post(self.base + "/api/mesh/fix", files=parts)
        params = {
            "kind": rng.choice(["face", "vertex", "corner"]),
            "format": rng.choice(["json", "csv", "npy"]),
        }
        reply = http.post(self.base + "/api/mesh/normals", params=params, files=parts)
        return f"{kind} normals", reply

    def prober(self) -> None:
        with httpx.Client(timeout=30) as http:
            while time.monotonic() < self.stop:
                start = time.perf_counter()
                try:
                    http.get(self.base + "/").raise_for_status()
                except httpx.HTTPError as error:
                    self.record("probe", None, repr(error))
                self.probe.append(time.perf_counter() - start)
                time.sleep(0.05)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60)
    parser.add_argument("--limit-gb", type=float, default=4)
    parser.add_argument("--upload-mb", type=float, default=20, help="size of the largest uploads")
    parser.add_argument("--clients", type=int, default=8)
    tables.add_option(parser)
    args = parser.parse_args()
    out = tables.Report(args.markdown)
    if shutil.which("prlimit") is None:
        sys.exit("prlimit (util-linux) is missing")
    limit_mb = 50
    files = {**uploads(args.upload_mb), **hostile(limit_mb)}
    small = uploads(1)
    files.update({f"{name} (1 MB)": parts for name, parts in small.items() if name != "gltf + bin"})
    port = free_port()
    command = [
        "prlimit", f"--as={int(args.limit_gb * 2**30)}", "--",
        sys.executable, "-m", "uvicorn", "app.main:app", "--host", "127.0.0.1",
        "--port", str(port), "--workers", "1", "--no-access-log", "--log-level", "warning",
    ]  # fmt: skip
    env = {**os.environ, "MESH_UPLOAD_LIMIT_MB": str(limit_mb)}
    server = subprocess.Popen(command, env=env)
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(600):
            try:
                httpx.get(base + "/", timeout=1)
                break
            except httpx.HTTPError:
                time.sleep(0.1)
        # One upload, answered once the first worker is ready; then until the other workers
        # have warmed up too (each loads everything a job can need as it starts).
        with httpx.Client(timeout=120) as http:
            http.post(base + "/api/mesh", files=[("file", p) for p in small["stl"]])
        before = settled(server.pid)
        parts_before = family_mb(server.pid)
        soak = Soak(base, args.seconds, files)
        threads = [threading.Thread(target=soak.client, args=(i,)) for i in range(args.clients)]
        threads.append(threading.Thread(target=soak.prober))
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        alive = server.poll() is None
        after = settled(server.pid) if alive else float("nan")  # replaced workers warm up
        parts_after = family_mb(server.pid) if alive else {}
    finally:
        server.terminate()
        server.wait(timeout=20)
    probe = sorted(soak.probe)
    p99 = probe[int(0.99 * (len(probe) - 1))] if probe else float("nan")
    print(f"{args.seconds:.0f} s, {args.clients} clients, address space {args.limit_gb:g} GB, "
          f"uploads up to {args.upload_mb:g} MB, upload limit {limit_mb} MB")  # fmt: skip
    print("| request | status | count |\n|---|---:|---:|")
    for (kind, status), count in sorted(soak.statuses.items()):
        print(f"| {kind} | {status} | {count} |")
    print()
    print(f"unplanned 5xx or transport errors: {len(soak.unplanned)}")
    for line in soak.unplanned[:10]:
        print("  ", line)
    print(f"worker alive at the end: {alive}")
    print(
        f"resident memory: {before:.0f} MB before, {after:.0f} MB after ({after / before - 1:+.0%})"
    )
    print(
        "by process (MB, before -> after): "
        + ", ".join(
            f"{p}: {parts_before.get(p, 0):.0f} -> {parts_after.get(p, 0):.0f}"
            for p in sorted(set(parts_before) | set(parts_after))
        )
    )
    print(
        f"GET / while soaking: {len(probe)} probes, p50 {statistics.median(probe) * 1000:.0f} ms, "
        f"p99 {p99 * 1000:.0f} ms, max {probe[-1] * 1000:.0f} ms"
    )
    answered: collections.Counter[int] = collections.Counter()
    for (_, status), count in soak.statuses.items():
        answered[status] += count
    out.print(
        "\n| soak | answered (200 / 400 / 413 / planned 503) | unplanned 5xx | process alive "
        "| resident memory before -> after | `GET /` p50 / p99 / max |"
    )
    out.print("|---|---:|---:|---|---:|---:|")
    out.print(
        f"| {args.seconds:.0f} s, {args.clients} clients, uploads up to {args.upload_mb:g} MB "
        f"| {' / '.join(str(answered[status]) for status in (200, 400, 413, 503))} "
        f"| {len(soak.unplanned)} | {'yes' if alive else 'no'} "
        f"| {before:,.0f} -> {after:,.0f} MB ({after / before - 1:+.0%}) "
        f"| {statistics.median(probe) * 1000:.0f} / {p99 * 1000:.0f} / {probe[-1] * 1000:.0f} ms |"
    )
    out.write()


if __name__ == "__main__":
    main()
