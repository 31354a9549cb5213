"""Orienting meshes: our ``orient`` against trimesh's and libigl's, side by side in one run.

    make bench-orient  # or: python -m benchmarks.orientation [--repeats 5] [--markdown PATH]

Peers: ``trimesh.repair.fix_normals`` (consistent winding by a breadth-first walk, then the
volume's sign for watertight meshes only: open parts are not turned outward) and libigl's
``bfs_orient`` + ``orient_outward`` (per component, the sign of the flux from its centroid,
like the cone heuristic we had). Neither looks at the whole mesh for open parts; libigl's
``reorient_facets_raycast``, which does, is not in its Python binding. The cases:

- a closed torus (one closed part: the volume decides; no ray is cast);
- an open hemisphere (one open part: visibility, 64 samples x 32 rays);
- scan fragments (48 open patches of a sphere, each with its own vertices);
- a triangle soup (a closed sphere whose faces each have their own, jittered vertices: every
  face an open part; the 4,096 largest are decided by visibility, the budget's limit).

Each row: the best of ``--repeats`` runs per tool (after one warm-up run), and the ratio to
ours; and whether each tool got the outward answer (the meshes are built outward, then every
face is reversed, so the right fix flips every face it decides).
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from collections.abc import Callable

import numpy as np
import trimesh

from benchmarks import tables
from mesh_normal.mesh.orientation import orient


def sphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def torus() -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.torus(1.0, 0.3, major_sections=400, minor_sections=200)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def hemisphere() -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = sphere(7)
    return vertices, faces[vertices[faces].mean(axis=1)[:, 2] > 0]


def fragments() -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = sphere(7)
    centres = vertices[faces].mean(axis=1)
    directions = sphere(1)[0]  # 42 directions
    label = np.argmax(centres @ directions.T, axis=1)
    pieces, parts, base = [], [], 0
    for k in range(len(directions)):
        keep = faces[label == k]
        used, inverse = np.unique(keep, return_inverse=True)
        # Shrink each piece a little towards its own centre: gaps between the fragments.
        points = vertices[used]
        points = points.mean(axis=0) + 0.97 * (points - points.mean(axis=0))
        pieces.append(points)
        parts.append(inverse.reshape(-1, 3) + base)
        base += len(used)
    return np.concatenate(pieces), np.concatenate(parts)


def soup() -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = sphere(6)
    corners = vertices[faces].reshape(-1, 3)
    jitter = 1 + 1e-9 * np.random.default_rng(0).standard_normal((len(corners), 1))
    return corners * jitter, np.arange(len(corners)).reshape(-1, 3)


CASES: dict[str, Callable[[], tuple[np.ndarray, np.ndarray]]] = {
    "closed torus": torus,
    "open hemisphere": hemisphere,
    "42 scan fragments": fragments,
    "triangle soup": soup,
}


def ours(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    return orient(vertices, faces).faces


def trimesh_fix(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    trimesh.repair.fix_normals(mesh)
    return np.asarray(mesh.faces)


def igl_fix(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    import igl

    oriented, components = igl.bfs_orient(faces)
    result, _ = igl.orient_outward(vertices, oriented, np.asarray(components).reshape(-1, 1))
    return np.asarray(result)


def outward_share(result: np.ndarray, original: np.ndarray) -> float:
    """The share of faces wound as in the (outward) original."""
    same = np.all(np.sort(result, axis=1) == np.sort(original, axis=1), axis=1)
    rotations = [np.roll(result, k, axis=1) for k in range(3)]
    kept = np.logical_or.reduce([np.all(r == original, axis=1) for r in rotations])
    return float(np.mean(kept & same))


def best(function: Callable[[], object], repeats: int) -> float:
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    tables.add_option(parser)
    args = parser.parse_args()
    out = tables.Report(args.markdown)
    tools: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
        "mesh_normal": ours,
        "trimesh": trimesh_fix,
    }
    if importlib.util.find_spec("igl") is not None:
        tools["libigl"] = igl_fix
    out.print("| case | faces | " + " | ".join(f"{t} s (ratio), outward" for t in tools) + " |")
    out.print("|---|---:|" + "---:|" * len(tools))
    for name, build in CASES.items():
        vertices, outward = build()
        faces = outward[:, ::-1].copy()
        cells, mine = [], 0.0
        for fix in tools.values():
            seconds = best(lambda fix=fix, v=vertices, f=faces: fix(v, f), args.repeats)
            mine = mine or seconds
            share = outward_share(fix(vertices, faces), outward)
            cells.append(f"{seconds:.3f} ({seconds / mine:.2f}), {share:.0%}")
        out.print(f"| {name} | {len(faces):,} | " + " | ".join(cells) + " |")
    out.write()


if __name__ == "__main__":
    main()
