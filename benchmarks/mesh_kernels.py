"""Mesh normal kernels, ours against trimesh, side by side in one run.

    .venv/bin/python -m benchmarks.mesh_kernels [--repeats 5] [--sizes 69451 871414]

The meshes are synthetic stand-ins with the triangle counts of the Stanford bunny (69,451)
and dragon (871,414): a torus grid with noise of a tenth of its step on its radius (about
half as many vertices as faces, valence 6), faces shuffled and cut to the exact count. Each kernel
runs ``repeats`` times, ours and trimesh's alternately, and the best time is reported.

trimesh's face normals are ``trimesh.triangles.normals(vertices[faces])`` (the gather is
included, as it is in ours). Its angle-weighted vertex normals are ``mesh.vertex_normals``
of a fresh ``Trimesh(process=False)``; it has no area weighting, so the area row uses
``trimesh.geometry.mean_vertex_normals`` on the raw cross products, the same sum. Both
build a SciPy sparse matrix: without SciPy, trimesh falls back to a Python loop per
vertex, and those rows are not measured. Open3D and libigl are not installed and not
measured.
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from collections.abc import Callable

import numpy as np

from app.core.mesh import face_normals
from app.core.mesh_normals import corner_normals, vertex_normals

SIZES = (69_451, 871_414)


def torus_mesh(triangles: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A noisy torus grid with exactly ``triangles`` faces, in shuffled order."""
    rng = np.random.default_rng(seed)
    around = int(np.ceil(np.sqrt(triangles / 2)))
    across = int(np.ceil(triangles / (2 * around)))
    i, j = np.meshgrid(np.arange(around), np.arange(across), indexing="ij")
    theta, phi = 2 * np.pi * i / around, 2 * np.pi * j / across
    # Noise of a tenth of the grid step: bumpy like a scan, yet a smooth surface.
    radius = 1 + 0.1 * (2 * np.pi / across) * rng.standard_normal(theta.shape)
    ring = 3 + radius * np.cos(phi)
    vertices = np.stack([ring * np.cos(theta), ring * np.sin(theta), radius * np.sin(phi)], -1)

    def index(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return (a % around) * across + b % across

    corners = index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)
    faces = np.concatenate([np.stack([corners[0], corners[1], corners[2]], -1).reshape(-1, 3),
                            np.stack([corners[0], corners[2], corners[3]], -1).reshape(-1, 3)])
    faces = faces[rng.permutation(len(faces))[:triangles]]
    return vertices.reshape(-1, 3), faces


def best_times(kernels: dict[str, Callable[[], object] | None], repeats: int) -> dict[str, float]:
    """Best wall time in milliseconds of each kernel, the kernels run alternately."""
    times: dict[str, list[float]] = {name: [] for name, kernel in kernels.items() if kernel}
    for _ in range(repeats):
        for name in times:
            kernel = kernels[name]
            assert kernel is not None
            start = time.perf_counter()
            kernel()
            times[name].append(time.perf_counter() - start)
    return {name: 1e3 * min(values) for name, values in times.items()}


def trimesh_kernels(
    vertices: np.ndarray, faces: np.ndarray
) -> dict[str, Callable[[], object] | None]:
    import trimesh  # a test dependency, imported only here

    def face() -> object:
        return trimesh.triangles.normals(vertices[faces])

    def angle() -> object:
        return trimesh.Trimesh(vertices=vertices, faces=faces, process=False).vertex_normals

    def area() -> object:
        mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        summed = trimesh.geometry.mean_vertex_normals(len(vertices), faces, mesh.triangles_cross)
        return trimesh.util.unitize(summed)

    sparse = importlib.util.find_spec("scipy") is not None
    return {"face": face, "area": area if sparse else None, "angle": angle if sparse else None}


def largest_angle(ours: np.ndarray, theirs: np.ndarray) -> float:
    """Largest angle in radians between matching nonzero rows."""
    both = (np.abs(ours).sum(axis=1) > 0) & (np.abs(theirs).sum(axis=1) > 0)
    a, b = ours[both], theirs[both]
    # atan2 of |a x b| and a . b: arccos of a dot product near 1 cannot resolve below 1e-8.
    angles = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
    return float(angles.max(initial=0.0))


def run(size: int, repeats: int) -> list[str]:
    vertices, faces = torus_mesh(size)
    ours = {
        "face": lambda: face_normals(vertices, faces),
        "area": lambda: vertex_normals(vertices, faces, "area"),
        "angle": lambda: vertex_normals(vertices, faces, "angle"),
        "corner": lambda: corner_normals(vertices, faces, 30.0),
        "corner 1": lambda: corner_normals(vertices, faces, 1.0),
    }
    theirs = trimesh_kernels(vertices, faces)
    kernels = {f"ours {k}": v for k, v in ours.items()}
    kernels.update({f"trimesh {k}": v for k, v in theirs.items()})
    times = best_times(kernels, repeats)
    labels = {"face": "face normals", "area": "vertex normals, area-weighted",
              "angle": "vertex normals, angle-weighted", "corner": "corner normals, crease 30°",
              "corner 1": "corner normals, crease 1° (most vertices pairwise)"}
    rows = []
    for key, label in labels.items():
        mine = times[f"ours {key}"]
        other = times.get(f"trimesh {key}")
        if other is None:
            reason = "no equivalent" if key.startswith("corner") else "not measured (no SciPy)"
            rows.append(f"| {size:,} | {label} | {mine:.1f} | {reason} | |")
        else:
            rows.append(f"| {size:,} | {label} | {mine:.1f} | {other:.1f} | {other / mine:.2f}x |")
    if theirs["angle"] is not None:
        import trimesh

        mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        gap = largest_angle(vertex_normals(vertices, faces).normals, mesh.vertex_normals)
        rows.append(f"| {size:,} | (largest angle between the angle-weighted results: "
                    f"{gap:.1e} rad) | | | |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    args = parser.parse_args()
    print("| triangles | kernel | ours (ms) | trimesh (ms) | trimesh / ours |")
    print("|---:|---|---:|---:|---:|")
    for size in args.sizes:
        for row in run(size, args.repeats):
            print(row, flush=True)
    print("\nOpen3D and libigl: not installed, not measured.")


if __name__ == "__main__":
    main()
