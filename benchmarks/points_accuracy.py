"""Point-cloud normals on the PCPNet protocol: ours (defaults) against Open3D at k = 18, 112, 450.

    .venv/bin/python -m benchmarks.points_accuracy [--points 100000] [--repeats 3]
    .venv/bin/python -m benchmarks.points_accuracy --markdown docs/benchmarks/points-accuracy.md

The protocol of PCPNet (Guerrero et al. 2018): ``--points`` drawn uniformly by area on each
shape, the exact normal of the surface each came from, Gaussian noise of standard deviation 0,
0.00125, 0.006 and 0.012 of the bounding box's diagonal on every coordinate, and the RMS of the
unoriented angle (degrees) over 5,000 of the points, averaged over shapes. Open3D's PCA at the
benchmark's small, medium and large scales runs on the same points in the same run.

Shapes: analytic ones with exact normals (sphere, torus, box, capped cylinder, an L-shaped
prism, a fandisk-like block with a bevel and a cylindrical groove) and public test meshes from
``tests/data`` sampled by area with their face normals (cow, fuze, nut, ant closed; airplane open).

Also printed: on the noise-free shapes with sharp edges, ours over Open3D k=18; the share of
normals pointing into each closed shape after the default orientation (a normal left
unoriented counts when it points in); and the time of the defaults (estimation and
orientation) over Open3D k=112's estimation, per cloud in the same run (best and median of
``--repeats``).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks import tables

#: The table as printed; main() gives it the path of ``--markdown``.
OUT = tables.Report(None)

NOISE = (0.0, 0.00125, 0.006, 0.012)
OPEN3D_K = (18, 112, 450)
DATA = Path(__file__).resolve().parent.parent / "tests" / "data"


@dataclass(frozen=True)
class Shape:
    name: str
    sample: Callable[[int, np.random.Generator], tuple[np.ndarray, np.ndarray]]
    closed: bool  # the truth is outward: inward normals can be counted
    sharp: bool  # it has sharp edges


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def sample_triangles(
    vertices: np.ndarray, faces: np.ndarray, n: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points uniform by area on the triangles, each with its face's unit normal."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    area = np.linalg.norm(cross, axis=1)
    keep = area > 0
    a, b, c, cross, area = a[keep], b[keep], c[keep], cross[keep], area[keep]
    face = rng.choice(len(area), size=n, p=area / area.sum())
    u, v = rng.uniform(size=n), rng.uniform(size=n)
    outside = u + v > 1
    u[outside], v[outside] = 1 - u[outside], 1 - v[outside]
    points = a[face] + u[:, None] * (b[face] - a[face]) + v[:, None] * (c[face] - a[face])
    return points, cross[face] / area[face, None]


def sphere(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    normals = _unit(rng.normal(size=(n, 3)))
    return normals.copy(), normals


def torus(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    big, small = 1.0, 0.35
    u = rng.uniform(0, 2 * np.pi, 4 * n)
    v = rng.uniform(0, 2 * np.pi, 4 * n)
    keep = rng.uniform(0, big + small, 4 * n) < big + small * np.cos(v)  # area density
    u, v = u[keep][:n], v[keep][:n]
    normals = np.stack([np.cos(u) * np.cos(v), np.sin(u) * np.cos(v), np.sin(v)], axis=1)
    centre = np.stack([np.cos(u), np.sin(u), np.zeros(len(u))], axis=1) * big
    return centre + small * normals, normals


def ear_clipping(outline: np.ndarray) -> list[tuple[int, int, int]]:
    """Counter-clockwise triangles covering the simple counter-clockwise polygon ``outline``."""
    left = list(range(len(outline)))
    triangles = []

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    while len(left) > 3:
        for k in range(len(left)):
            i, j, h = left[k - 1], left[k], left[(k + 1) % len(left)]
            a, b, c = outline[i], outline[j], outline[h]
            if cross(a, b, c) <= 0:
                continue  # a reflex corner is no ear
            inside = any(
                cross(a, b, outline[q]) >= 0
                and cross(b, c, outline[q]) >= 0
                and cross(c, a, outline[q]) >= 0
                for q in left
                if q not in (i, j, h)
            )
            if not inside:
                triangles.append((i, j, h))
                left.pop(k)
                break
    triangles.append(tuple(left))
    return triangles


def prism(outline: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray]:
    """A closed triangle mesh: the counter-clockwise polygon ``outline`` (x, y) extruded in z,
    its caps cut into ears."""
    m = len(outline)
    bottom = np.c_[outline, np.zeros(m)]
    top = np.c_[outline, np.full(m, height)]
    vertices = np.vstack([bottom, top])
    faces = []
    for i in range(m):
        j = (i + 1) % m
        faces += [[i, j, m + j], [i, m + j, m + i]]
    for i, j, k in ear_clipping(outline):
        faces += [[i, k, j], [m + i, m + j, m + k]]  # the bottom faces down, the top up
    return vertices, np.array(faces)


def box(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    outline = np.array([[0, 0], [2, 0], [2, 1.5], [0, 1.5]], dtype=float)
    return sample_triangles(*prism(outline, 1.0), n, rng)


def l_prism(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    outline = np.array([[0, 0], [2, 0], [2, 0.8], [0.8, 0.8], [0.8, 2], [0, 2]], dtype=float)
    return sample_triangles(*prism(outline, 0.7), n, rng)


def fandisk_like(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A block with a bevelled corner and a cylindrical groove across its top: sharp convex and
    concave edges, flat and curved faces."""
    angles = np.linspace(0, np.pi, 25)
    groove = np.c_[1.0 + 0.4 * np.cos(angles), 1.2 - 0.4 * np.sin(angles)]
    outline = np.vstack([[[0, 0], [2, 0], [2, 0.8], [1.6, 1.2]], groove, [[0, 1.2]]])
    return sample_triangles(*prism(outline, 0.9), n, rng)


def cylinder(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    radius, height = 0.5, 1.5
    side, cap = 2 * np.pi * radius * height, np.pi * radius**2
    on_side = rng.uniform(size=n) < side / (side + 2 * cap)
    points, normals = np.empty((n, 3)), np.empty((n, 3))
    s = int(on_side.sum())
    angle = rng.uniform(0, 2 * np.pi, s)
    points[on_side] = np.c_[
        radius * np.cos(angle), radius * np.sin(angle), rng.uniform(0, height, s)
    ]
    normals[on_side] = np.c_[np.cos(angle), np.sin(angle), np.zeros(s)]
    c = n - s
    angle = rng.uniform(0, 2 * np.pi, c)
    r = radius * np.sqrt(rng.uniform(size=c))
    up = rng.uniform(size=c) < 0.5
    points[~on_side] = np.c_[r * np.cos(angle), r * np.sin(angle), np.where(up, height, 0.0)]
    normals[~on_side] = np.c_[np.zeros(c), np.zeros(c), np.where(up, 1.0, -1.0)]
    return points, normals


def mesh_file(name: str) -> Callable[[int, np.random.Generator], tuple[np.ndarray, np.ndarray]]:
    def sample(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        from mesh_normal.files.read import read_mesh

        mesh = read_mesh(DATA / name)
        return sample_triangles(mesh.vertices, mesh.faces, n, rng)

    return sample


SHAPES = (
    Shape("sphere", sphere, True, False),
    Shape("torus", torus, True, False),
    Shape("box", box, True, True),
    Shape("cylinder", cylinder, True, True),
    Shape("L-prism", l_prism, True, True),
    Shape("fandisk-like", fandisk_like, True, True),
    Shape("cow", mesh_file("cow.obj"), True, False),
    Shape("fuze", mesh_file("fuze.obj"), True, False),
    Shape("nut", mesh_file("nut.ply"), True, True),
    Shape("airplane", mesh_file("airplane.ply"), False, False),
    Shape("ant", mesh_file("ant.ply"), True, False),
)


def angles(normals: np.ndarray, truth: np.ndarray) -> float:
    """RMS of the unoriented angle, in degrees; a missing normal counts as 90."""
    dots = np.abs(np.einsum("ij,ij->i", normals, truth))
    return float(np.sqrt(np.mean(np.degrees(np.arccos(np.clip(dots, 0, 1))) ** 2)))


def open3d_normals(points: np.ndarray, k: int) -> np.ndarray:
    import open3d

    cloud = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(points))
    cloud.estimate_normals(open3d.geometry.KDTreeSearchParamKNN(k))
    return np.asarray(cloud.normals)


def noisy(shape: Shape, n: int, level: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    points, truth = shape.sample(n, rng)
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    if level:
        points = points + rng.normal(scale=level * diagonal, size=points.shape)
    return points, truth


@dataclass
class Run:
    """One shape at one noise level: the RMS angles, inward share, times."""

    ours: float
    theirs: dict[int, float]
    inward: float
    ours_seconds: list[float]
    theirs_seconds: list[float]


def measure(
    shape: Shape,
    n: int,
    level: float,
    repeats: int,
    seed: int = 0,
    estimate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None,
) -> Run:
    """``estimate(points)`` -> (normals, per-point valid) defaults to ``point_normals``'s."""
    from mesh_normal.points import point_normals

    def ours_default(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        result = point_normals(points)
        return result.normals, result.valid

    estimate = estimate or ours_default
    points, truth = noisy(shape, n, level, seed)
    subset = np.random.default_rng(seed + 1).choice(n, size=min(5000, n), replace=False)
    ours_seconds, theirs_seconds = [], []
    normals = np.zeros_like(points)
    for _ in range(repeats):
        start = time.perf_counter()
        normals, _ = estimate(points)
        ours_seconds.append(time.perf_counter() - start)
    theirs = {}
    for k in OPEN3D_K:
        start = time.perf_counter()
        found = open3d_normals(points, k)
        seconds = time.perf_counter() - start
        theirs[k] = angles(found[subset], truth[subset])
        if k == 112:
            theirs_seconds.append(seconds)
            for _ in range(repeats - 1):
                start = time.perf_counter()
                open3d_normals(points, k)
                theirs_seconds.append(time.perf_counter() - start)
    inward = float(np.mean(np.einsum("ij,ij->i", normals, truth) < 0)) if shape.closed else 0.0
    return Run(angles(normals[subset], truth[subset]), theirs, inward, ours_seconds, theirs_seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=100_000, help="points per shape")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs of each")
    parser.add_argument("--shapes", nargs="*", help="only these shapes (names)")
    tables.add_option(parser)
    arguments = parser.parse_args()
    OUT.path = Path(arguments.markdown) if arguments.markdown else None
    shapes = [s for s in SHAPES if not arguments.shapes or s.name in arguments.shapes]
    runs = {
        (shape.name, level): measure(shape, arguments.points, level, arguments.repeats)
        for level in NOISE
        for shape in shapes
    }
    OUT.print(f"{arguments.points:,} points a shape; RMS angle in degrees over 5,000 of them.\n")
    OUT.print("| noise | ours (defaults) | Open3D k=18 | k=112 | k=450 | ours / best of Open3D |")
    OUT.print("|---|---|---|---|---|---|")
    for level in NOISE:
        ours = float(np.mean([runs[s.name, level].ours for s in shapes]))
        theirs = [float(np.mean([runs[s.name, level].theirs[k] for s in shapes])) for k in OPEN3D_K]
        cells = " | ".join(f"{t:.2f}" for t in theirs)
        OUT.print(f"| {level:g} | {ours:.2f} | {cells} | {ours / min(theirs):.2f} |")
    sharp = [s for s in shapes if s.sharp]
    if sharp:
        ours = float(np.mean([runs[s.name, 0.0].ours for s in sharp]))
        pca = float(np.mean([runs[s.name, 0.0].theirs[18] for s in sharp]))
        names = ", ".join(s.name for s in sharp)
        OUT.print(
            f"\nNoise-free shapes with sharp edges ({names}): ours {ours:.2f}, "
            f"Open3D k=18 {pca:.2f}, ratio {ours / pca:.2f}.\n"
        )
    OUT.print("| shape | " + " | ".join(f"noise {level:g}" for level in NOISE) + " |")
    OUT.print("|---|" + "---|" * len(NOISE))
    for shape in shapes:
        cells = []
        for level in NOISE:
            run = runs[shape.name, level]
            best = min(run.theirs.values())
            inward = f", {100 * run.inward:.2f}% in" if shape.closed else ""
            cells.append(f"{run.ours:.2f} (O3D best {best:.2f}{inward})")
        OUT.print(f"| {shape.name} | " + " | ".join(cells) + " |")
    ratios = [
        min(r.ours_seconds) / min(r.theirs_seconds) for r in runs.values() if r.theirs_seconds
    ]
    medians = [
        statistics.median(r.ours_seconds) / statistics.median(r.theirs_seconds)
        for r in runs.values()
    ]
    closed = [runs[s.name, level].inward for s in shapes if s.closed for level in NOISE[:3]]
    OUT.print(
        f"\nTime of the defaults (estimate and orient) over Open3D k=112's estimate, per cloud: "
        f"best-of-repeats ratio median {statistics.median(ratios):.2f} (worst {max(ratios):.2f}), "
        f"median-of-repeats ratio median {statistics.median(medians):.2f}.\n"
        f"Inward after the default orientation, closed shapes, noise up to 0.006: worst "
        f"{100 * max(closed, default=0.0):.2f}%."
    )
    OUT.write()


if __name__ == "__main__":
    main()
