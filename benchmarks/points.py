"""Point-cloud normals: ours against Open3D's, speed and accuracy side by side in one run.

    make bench-points     # or: .venv/bin/python -m benchmarks.points [--quick] [--no-memory]
    .venv/bin/python -m benchmarks.points --markdown docs/benchmarks/points.md  # writes the table

Rows (``--quick``: a fifth of the sizes, for a smoke run):

- estimation: ``point_normals(points, k=30, orient="none")`` against Open3D's
  ``estimate_normals(KDTreeSearchParamKNN(30))``, 1M points on a unit sphere in random order;
- accuracy: the unoriented RMSE, in degrees, of both on a noiseless 1M-point sphere at k = 30,
  moved by 0, 1e6 and 1e8;
- orientation: our ``"mst"`` and ``"riemannian"`` orientation of 100k points on a torus (the step
  after estimation, timed alone) against Open3D's ``orient_normals_consistent_tangent_plane(30)``,
  with how many points each turned inward;
- memory: the peak resident memory of ``point_normals`` on 10M points, in a child process.

Times are the best of ``--repeats`` runs (after one warm-up for ours).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import open3d

from benchmarks import tables
from mesh_normal.points import estimate, point_normals
from mesh_normal.points.orient import along_tree

#: The table as printed; main() gives it the path of ``--markdown``.
OUT = tables.Report(None)


def sphere(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    normals = np.random.default_rng(seed).normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return normals.copy(), normals


def torus(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, 4 * n)
    v = v[rng.uniform(0, 1.3, 4 * n) < 1 + 0.3 * np.cos(v)][:n]
    normals = np.stack([np.cos(u) * np.cos(v), np.sin(u) * np.cos(v), np.sin(v)], axis=1)
    return np.stack([np.cos(u), np.sin(u), np.zeros(n)], axis=1) + 0.3 * normals, normals


def best(run: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times), result


def open3d_cloud(points: np.ndarray) -> Any:
    return open3d.geometry.PointCloud(open3d.utility.Vector3dVector(points))


def open3d_normals(points: np.ndarray, k: int = 30) -> np.ndarray:
    cloud = open3d_cloud(points)
    cloud.estimate_normals(open3d.geometry.KDTreeSearchParamKNN(k))
    return np.asarray(cloud.normals)


def rmse(normals: np.ndarray, truth: np.ndarray) -> float:
    dots = np.abs(np.einsum("ij,ij->i", normals, truth))
    return float(np.sqrt(np.mean(np.degrees(np.arccos(np.clip(dots, 0, 1))) ** 2)))


def estimation(n: int, repeats: int) -> None:
    points, _ = sphere(n)  # random order: the generator's
    point_normals(points[:1000], k=30, orient="none")
    ours, _ = best(lambda: point_normals(points, k=30, orient="none"), repeats)
    theirs, _ = best(lambda: open3d_normals(points), repeats)
    OUT.print(
        f"| estimation, {n:,} points, k = 30, random order | {ours:.2f} s | {theirs:.2f} s "
        f"| {ours / theirs:.2f} | |"
    )


def accuracy(n: int) -> None:
    points, truth = sphere(n, seed=1)
    ours = [rmse(point_normals(points + o, k=30, orient="none").normals, truth) for o in OFFSETS]
    theirs = [rmse(open3d_normals(points + o), truth) for o in OFFSETS]
    for offset, our, their in zip(OFFSETS, ours, theirs, strict=True):
        OUT.print(
            f"| unoriented RMSE, {n:,}-point sphere, offset {offset:g} | {our:.4f}° "
            f"| {their:.4f}° | |"
        )


def orientation(n: int, repeats: int) -> None:
    points, truth = torus(n)
    frame = estimate._frame(points)
    normals, _, _, codes, graph = estimate._estimate(frame, 30, None)
    truth_local = truth[frame.origin]
    for mode in ("mst", "riemannian"):

        def orient(mode: str = mode) -> np.ndarray:
            riemannian = mode == "riemannian"
            signs = along_tree(
                frame.points, normals, codes == 0, graph, 60.0, riemannian, frame.weight
            )
            return np.where(signs.flip[:, None], -normals, normals)

        ours, oriented = best(orient, repeats)
        inward = int((np.einsum("ij,ij->i", oriented, truth_local) < 0).sum())
        OUT.print(
            f"| orientation `{mode}`, {n:,}-point torus | {ours:.2f} s | | | {inward} inward |"
        )
    cloud = open3d_cloud(points)
    cloud.estimate_normals(open3d.geometry.KDTreeSearchParamKNN(30))
    start = time.perf_counter()
    cloud.orient_normals_consistent_tangent_plane(30)
    theirs = time.perf_counter() - start
    oriented = np.asarray(cloud.normals)
    inward = int((np.einsum("ij,ij->i", oriented, truth) < 0).sum())
    # Open3D's answer may be consistent but all inward: count the smaller side as wrong.
    wrong = min(inward, n - inward)
    OUT.print(
        f"| Open3D consistent tangent plane (30), {n:,}-point torus | | {theirs:.2f} s | "
        f"| {wrong} inconsistent (of {inward} inward) |"
    )


def memory(n: int, orient: str) -> None:
    script = (
        "import numpy as np, resource, json\n"
        "from mesh_normal.points import point_normals\n"
        f"p = np.random.default_rng(0).normal(size=({n}, 3))\n"
        "p /= np.linalg.norm(p, axis=1, keepdims=True)\n"
        "before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        f"r = point_normals(p, k=30, orient={orient!r})\n"
        "peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        "print(json.dumps([before, peak, int(r.valid.sum())]))\n"
    )
    start = time.perf_counter()
    output = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    ).stdout
    seconds = time.perf_counter() - start
    before, peak, valid = json.loads(output.splitlines()[-1])
    OUT.print(
        f"| memory, {n:,} points, orient `{orient}` | peak {peak / 2**20:.2f} GiB "
        f"(input {before / 2**20:.2f} GiB), {seconds:.0f} s | | | {valid:,} normals |"
    )


OFFSETS = (0.0, 1e6, 1e8)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a fifth of the sizes")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--no-memory", action="store_true", help="skip the 10M-point run")
    tables.add_option(parser)
    arguments = parser.parse_args()
    OUT.path = Path(arguments.markdown) if arguments.markdown else None
    scale = 5 if arguments.quick else 1
    OUT.print("| case | ours | Open3D | ratio | notes |")
    OUT.print("|---|---|---|---|---|")
    estimation(1_000_000 // scale, arguments.repeats)
    accuracy(1_000_000 // scale)
    orientation(100_000 // scale, arguments.repeats)
    if not arguments.no_memory:
        for orient in ("none", "mst"):
            memory(10_000_000 // scale, orient)
    OUT.write()


if __name__ == "__main__":
    main()
