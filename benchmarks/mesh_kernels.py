"""Mesh normal kernels, ours against trimesh, libigl and Open3D, side by side in one run.

    .venv/bin/python -m benchmarks.mesh_kernels [--repeats 7] [--sizes 69451 871414 14000000]

The meshes are synthetic stand-ins with the triangle counts of the Stanford bunny (69,451),
dragon (871,414) and Lucy (14,000,000): a torus grid with noise of a tenth of its step on its
radius (about half as many vertices as faces, valence 6), faces shuffled and cut to the exact
count. Each kernel runs ``repeats`` times, all libraries alternately (above 2 million faces,
trimesh's and libigl's at most ``--large-repeats`` times: more would run this machine out of
memory; ours and Open3D's all ``repeats``); the best time is reported and, in brackets, the
median (ratios of medians in brackets too); only ratios within one run count. ``--idle N``
adds rows for face and area-weighted vertex normals against Open3D where each call follows a
second of sleep.

trimesh's face normals are ``trimesh.triangles.normals(vertices[faces])`` (the gather is
included, as it is in ours). Its angle-weighted vertex normals are ``mesh.vertex_normals``
of a fresh ``Trimesh(process=False)``; it has no area weighting, so the area row uses
``trimesh.geometry.mean_vertex_normals`` on the raw cross products, the same sum (and the
uniform row on the unit normals). libigl: ``igl.per_face_normals`` and
``igl.per_vertex_normals`` with each of its weightings. Open3D: ``compute_triangle_normals``
and ``compute_vertex_normals`` (area-weighted) of a ``TriangleMesh`` built before the clock
starts: in the plain rows a new mesh for each call, whose call makes its output vector anew
(as trimesh, libigl and ours make new arrays); in the rows "against Open3D's into its kept
vector", the same mesh each time, whose call writes into the vector it kept from the last
(ours still into new arrays); "into the last call's arrays" is ours with ``out=`` against
that kept vector, the same work. Corner normals have no equivalent. A second table probes
what each library returns for degenerate and tiny faces, and a third the extra memory of our
kernels (tracemalloc).
``--markdown PATH`` writes a summary (ours / the peer's time of each kernel, best and median)
and the degenerate faces' table to a file, after a line naming the machine and the date.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from benchmarks import tables
from mesh_normal.mesh.corners import corner_normals
from mesh_normal.mesh.faces import face_normals
from mesh_normal.mesh.vertices import vertex_normals

SIZES = (69_451, 871_414, 14_000_000)


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
    faces = np.concatenate(
        [
            np.stack([corners[0], corners[1], corners[2]], -1).reshape(-1, 3),
            np.stack([corners[0], corners[2], corners[3]], -1).reshape(-1, 3),
        ]
    )
    faces = faces[rng.permutation(len(faces))[:triangles]]
    return vertices.reshape(-1, 3), faces


Kernels = dict[str, Callable[[], object]]  # a Fresh too


def trimesh_kernels(vertices: np.ndarray, faces: np.ndarray) -> Kernels:
    import trimesh  # a test dependency, imported only here

    def face() -> object:
        return trimesh.triangles.normals(vertices[faces])

    def angle() -> object:
        return trimesh.Trimesh(vertices=vertices, faces=faces, process=False).vertex_normals

    def summed(kind: str) -> Callable[[], object]:
        def run() -> object:
            mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
            each = mesh.triangles_cross if kind == "area" else mesh.face_normals
            total = trimesh.geometry.mean_vertex_normals(len(vertices), faces, each)
            return trimesh.util.unitize(total)

        return run

    if importlib.util.find_spec("scipy") is None:  # else a Python loop per vertex
        return {"face": face}
    return {"face": face, "area": summed("area"), "angle": angle, "uniform": summed("uniform")}


def igl_kernels(vertices: np.ndarray, faces: np.ndarray) -> Kernels:
    if importlib.util.find_spec("igl") is None:
        return {}
    import igl

    def vertex(weighting: str) -> Callable[[], object]:
        kind = getattr(igl, f"PER_VERTEX_NORMALS_WEIGHTING_TYPE_{weighting.upper()}")
        return lambda: igl.per_vertex_normals(vertices, faces, kind)

    return {
        "face": lambda: igl.per_face_normals(vertices, faces),
        **{weighting: vertex(weighting) for weighting in ("area", "angle", "uniform")},
    }


class Fresh:
    """A peer's call on a new object each time, the object made outside the clock
    (``prepare``, which :func:`best_times` calls before it starts it): Open3D's mesh, whose
    call then makes its output vector anew, as ours makes new arrays."""

    def __init__(self, make: Callable[[], Any], call: Callable[[Any], object]) -> None:
        self.make, self.call = make, call
        self.made: Any = None
        self.used: Any = None

    def prepare(self) -> None:
        self.made = self.make()

    def __call__(self) -> object:
        made, self.made = self.made, None
        self.used = made if made is not None else self.make()
        return self.call(self.used)

    def release(self) -> None:
        """Free the mesh of the last call, after the clock stops (not its own work)."""
        self.used = None


def timed(kernel: Callable[[], object], idle: float = 0.0) -> float:
    """Seconds of one call, a ``Fresh`` one's mesh made before (unless prepared already) and
    freed after the clock, as is every result: freeing hundreds of megabytes is no part of the
    work measured. ``idle``: seconds of sleep just before the clock starts."""
    if isinstance(kernel, Fresh) and kernel.made is None:
        kernel.prepare()
    if idle:
        time.sleep(idle)
    start = time.perf_counter()
    result = kernel()
    elapsed = time.perf_counter() - start
    del result
    if isinstance(kernel, Fresh):
        kernel.release()
    return elapsed


def open3d_kernels(vertices: np.ndarray, faces: np.ndarray) -> Kernels:
    if importlib.util.find_spec("open3d") is None:
        return {}
    import open3d as o3d

    triangles = faces.astype(np.int32)

    def mesh() -> o3d.geometry.TriangleMesh:
        return o3d.geometry.TriangleMesh(
            o3d.utility.Vector3dVector(vertices), o3d.utility.Vector3iVector(triangles)
        )

    def face(made: o3d.geometry.TriangleMesh) -> object:
        return np.asarray(made.compute_triangle_normals().triangle_normals)

    def area(made: o3d.geometry.TriangleMesh) -> object:
        return np.asarray(made.compute_vertex_normals().vertex_normals)

    flat, smooth = mesh(), mesh()  # built here, outside the timed calls
    return {
        "face": Fresh(mesh, face),
        "area": Fresh(mesh, area),
        "face kept": lambda: face(flat),
        "area kept": lambda: area(smooth),
    }


def largest_angle(ours: np.ndarray, theirs: np.ndarray) -> float:
    """Largest angle in radians between matching nonzero rows."""
    both = (np.abs(ours).sum(axis=1) > 0) & (np.abs(theirs).sum(axis=1) > 0)
    a, b = ours[both], theirs[both]
    # atan2 of |a x b| and a . b: arccos of a dot product near 1 cannot resolve below 1e-8.
    angles = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
    return float(angles.max(initial=0.0))


PEERS = ("trimesh", "libigl", "Open3D")
#: The table's rows: ours, the peers' kernel, the label. Open3D's "face" and "area" calls are
#: of a new mesh each (its output vector made anew, as ours are new arrays); its "kept" calls
#: write into the vector its mesh keeps from the call before (as ours with ``out=``).
ROWS = (
    ("face", "face", "face normals"),
    ("face", "face kept", "face normals, new arrays, against Open3D's into its kept vector"),
    ("face out", "face kept", "face normals into the last call's arrays (`out=`)"),
    ("area", "area", "vertex normals, area-weighted"),
    ("area", "area kept", "vertex normals, area-weighted, against Open3D's into its kept vector"),
    ("angle", "angle", "vertex normals, angle-weighted"),
    ("uniform", "uniform", "vertex normals, uniform"),
    ("corner", "corner", "corner normals, crease 30°"),
    ("corner 1", "corner 1", "corner normals, crease 1° (most vertices pairwise)"),
)
LARGE = 2_000_000


#: ours / a peer's time, best (median), by (kernel, peer) and size: the table ``--markdown`` writes.
Summary = dict[tuple[str, str], dict[int, str]]


def run(
    size: int,
    repeats: int,
    idle: int = 0,
    peer_repeats: int | None = None,
    summary: Summary | None = None,
) -> list[str]:
    vertices, faces = torus_mesh(size)
    kept = face_normals(vertices, faces)  # Open3D writes into the vector its mesh keeps
    ours: Kernels = {
        "face": lambda: face_normals(vertices, faces),
        "face out": lambda: face_normals(vertices, faces, out=kept),
        "area": lambda: vertex_normals(vertices, faces, "area"),
        "angle": lambda: vertex_normals(vertices, faces, "angle"),
        "uniform": lambda: vertex_normals(vertices, faces, "uniform"),
    }
    if size < LARGE:  # the pairwise corner normals of Lucy take minutes and gigabytes
        ours["corner"] = lambda: corner_normals(vertices, faces, 30.0)
        ours["corner 1"] = lambda: corner_normals(vertices, faces, 1.0)
    # Each kernel once before timing: ours compiled or loaded from the cache (a call as tiny
    # as one face runs in Python and loads nothing), Open3D's output vectors made. trimesh
    # and libigl keep nothing between calls; trimesh at the Lucy size, once more, would run
    # this machine out of memory.
    for call in ours.values():
        call()
    peers = dict(
        zip(
            PEERS,
            (
                trimesh_kernels(vertices, faces),
                igl_kernels(vertices, faces),
                open3d_kernels(vertices, faces),
            ),
            strict=True,
        )
    )
    open3d = peers["Open3D"]
    for call in open3d.values():
        call()
    kernels = {("ours", k): v for k, v in ours.items()}
    kernels.update({(peer, k): v for peer, their in peers.items() for k, v in their.items()})
    limits = {
        key: peer_repeats
        for key in kernels
        if peer_repeats is not None and key[0] in ("trimesh", "libigl")
    }
    times, medians = best_times(kernels, repeats, limits)
    rows = []
    for key, same, label in ROWS:
        if key not in ours:
            continue
        mine = times["ours", key]
        theirs = [times.get((peer, same)) for peer in PEERS]
        cells = [f"{t:.1f}" if t else "" for t in theirs]
        ratios = [
            f"{t / mine:.2f}x ({medians[peer, same] / medians['ours', key]:.2f}x)" if t else ""
            for t, peer in zip(theirs, PEERS, strict=True)
        ]
        rows.append(
            f"| {size:,} | {label} | {mine:.1f} ({medians['ours', key]:.1f}) | "
            + " | ".join(cells + ratios)
            + " |"
        )
        peer = "Open3D" if times.get(("Open3D", same)) else "trimesh"
        if summary is not None and times.get((peer, same)):
            summary.setdefault((label, peer), {})[size] = (
                f"{mine / times[peer, same]:.2f} ({medians['ours', key] / medians[peer, same]:.2f})"
            )
    if idle and open3d:
        rows += after_idle(size, ours, open3d, idle, summary)
    if "angle" in peers["trimesh"]:
        import trimesh

        mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        gap = largest_angle(vertex_normals(vertices, faces).normals, mesh.vertex_normals)
        rows.append(
            f"| {size:,} | (largest angle between our and trimesh's angle-weighted "
            f"normals: {gap:.1e} rad) | | | | | | | |"
        )
    return rows


def best_times(
    kernels: dict[tuple[str, str], Callable[[], object]],
    repeats: int,
    limits: dict[tuple[str, str], int] | None = None,
) -> tuple[dict[tuple[str, str], float], dict[tuple[str, str], float]]:
    """Best and median wall times in milliseconds of each kernel, the kernels run alternately,
    each ``repeats`` times or its limit in ``limits``."""
    times: dict[tuple[str, str], list[float]] = {name: [] for name in kernels}
    for round_ in range(repeats):
        # Open3D's new meshes made first in each round, not right before their calls: just
        # made, a mesh of the Dragon's size would be in the cache, as no other input is then.
        for kernel in kernels.values():
            if isinstance(kernel, Fresh):
                kernel.prepare()
        for name, kernel in kernels.items():
            if round_ >= (limits or {}).get(name, repeats):
                continue
            times[name].append(timed(kernel))
    best = {name: 1e3 * min(values) for name, values in times.items()}
    return best, {name: 1e3 * statistics.median(values) for name, values in times.items()}


def after_idle(
    size: int, ours: Kernels, open3d: Kernels, repeats: int, summary: Summary | None = None
) -> list[str]:
    """Ours against Open3D on calls that each follow a second of sleep (threads parked, caches
    cold), alternately: the best and median times and Open3D / ours of each."""
    rows = []
    for key, same, label in (row for row in ROWS if row[0] in ("face", "area")):
        times: dict[str, list[float]] = {"ours": [], "Open3D": []}
        for _ in range(repeats):
            if isinstance(open3d[same], Fresh):  # made before ours runs (see best_times)
                open3d[same].prepare()
            for name, call in (("ours", ours[key]), ("Open3D", open3d[same])):
                times[name].append(1e3 * timed(call, idle=1.0))
        (mine, theirs) = (min(times["ours"]), min(times["Open3D"]))
        middle = {name: statistics.median(values) for name, values in times.items()}
        rows.append(
            f"| {size:,} | {label}, each after 1 s idle | {mine:.1f} ({middle['ours']:.1f}) "
            f"| | | {theirs:.1f} | | | {theirs / mine:.2f}x "
            f"({middle['Open3D'] / middle['ours']:.2f}x) |"
        )
        if summary is not None:
            summary.setdefault((f"{label}, each after 1 s idle", "Open3D"), {})[size] = (
                f"{mine / theirs:.2f} ({middle['ours'] / middle['Open3D']:.2f})"
            )
    return rows


def summary_table(summary: Summary, sizes: list[int]) -> str:
    """Ours / the peer's time of each kernel at each size, best (median): under 1, ours wins."""
    rows = [
        "| kernel | ours / | " + " | ".join(f"{size:,} triangles" for size in sizes) + " |",
        "|---|---|" + "---:|" * len(sizes),
    ]
    for (label, peer), cells in summary.items():
        rows.append(f"| {label} | {peer} | " + " | ".join(cells.get(s, "") for s in sizes) + " |")
    return "\n".join(rows)


# --- what each library returns for degenerate and tiny faces --------------------------------

PROBE = np.array(
    [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 0.0, 0.0],  # 0-2: collinear
        [0.0, 1.0, 0.0],  # 3: with 0 and 1, a valid face next to the collinear one
        [5.0, 5.0, 5.0],
        [5.0 + 1e-7, 5.0, 5.0],
        [5.0, 5.0 + 1e-7, 5.0],  # 4-6: legs of 1e-7
        [9.0, 9.0, 9.0],  # 7: only in a face with a repeated index
    ]
)
PROBE_FACES = np.array([[0, 1, 2], [0, 1, 3], [4, 5, 6], [7, 7, 1]])
PROBE_CASES = (  # (label, face normals row or None, vertex normals row or None, expected)
    ("collinear face: its face normal", 0, None, None),
    ("face with a repeated index: its face normal", 3, None, None),
    ("right triangle with 1e-7 legs: its face normal", 2, None, (0.0, 0.0, 1.0)),
    ("vertex 0 (a valid face and a collinear one): its normal", None, 0, (0.0, 0.0, 1.0)),
    ("vertex 2 (only in the collinear face): its normal", None, 2, None),
)


def verdict(row: np.ndarray, expected: tuple[float, ...] | None) -> str:
    if np.isnan(row).any():
        return "NaN"
    if not row.any():
        return "zero"
    if expected is not None and np.allclose(row, expected, atol=1e-9):
        return "right"
    return f"[{', '.join(f'{x:.2g}' for x in row)}]"


def full_rows(normals: object) -> np.ndarray:
    """trimesh returns the valid rows and a mask; fill the others with zero as Trimesh does."""
    if isinstance(normals, tuple):
        rows, valid = normals
        full = np.zeros((len(valid), 3))
        full[valid] = rows
        return full
    return np.asarray(normals)


def probe() -> list[str]:
    """One row per case, one column per library: what its face or vertex normal is."""
    import warnings

    results: dict[str, tuple[np.ndarray | None, np.ndarray | None]] = {
        "ours": (
            face_normals(PROBE, PROBE_FACES).normals,
            vertex_normals(PROBE, PROBE_FACES, "angle").normals,
        )
    }
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for name, kernels in (
            ("trimesh", trimesh_kernels(PROBE, PROBE_FACES)),
            ("libigl", igl_kernels(PROBE, PROBE_FACES)),
            ("Open3D", open3d_kernels(PROBE, PROBE_FACES)),
        ):
            smooth = kernels.get("angle", kernels.get("area"))
            results[name] = (
                full_rows(kernels["face"]()) if "face" in kernels else None,
                np.asarray(smooth()) if smooth else None,
            )
        if importlib.util.find_spec("igl"):
            import igl

            stable = np.asarray(igl.per_face_normals_stable(PROBE, PROBE_FACES))
            results["libigl stable"] = (stable, None)
    rows = ["| case | " + " | ".join(results) + " |", "|---|" + "---|" * len(results)]
    for label, face, vertex, expected in PROBE_CASES:
        cells = []
        for flat, smooth in results.values():
            array, row = (flat, face) if face is not None else (smooth, vertex)
            cells.append("" if array is None else verdict(np.asarray(array)[row], expected))
        rows.append(f"| {label} | " + " | ".join(cells) + " |")
    return rows


def memory(size: int) -> list[str]:
    """Peak memory allocated during each call beyond its output (tracemalloc)."""
    import tracemalloc

    vertices, faces = torus_mesh(size)
    rows = []
    for label, call in (
        ("face normals", lambda: face_normals(vertices, faces)),
        ("vertex normals, angle", lambda: vertex_normals(vertices, faces)),
    ):
        call()
        tracemalloc.start()
        result = call()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        output = sum(array.nbytes for array in (getattr(result, n) for n in result.__slots__))
        rows.append(
            f"| {size:,} | {label} | {output / 2**20:.1f} | {peak / 2**20:.1f} | "
            f"{(peak - output) / 2**20:.1f} | {(peak - output) / output:.2f} |"
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--large-repeats", type=int, default=2)
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument(
        "--idle", type=int, default=0, help="also time this many calls after 1 s of sleep each"
    )
    tables.add_option(parser)
    args = parser.parse_args()
    summary: Summary = {}
    print(
        "| triangles | kernel | ours (ms) | "
        + " | ".join(f"{p} (ms)" for p in PEERS)
        + " | "
        + " | ".join(f"{p} / ours" for p in PEERS)
        + " |"
    )
    print("|---:|---|---:|" + "---:|" * 6)
    for size in args.sizes:
        peers = None if size < LARGE else min(args.repeats, args.large_repeats)
        for row in run(size, args.repeats, args.idle if size < LARGE else 0, peers, summary):
            print(row, flush=True)
    out = tables.Report(args.markdown)
    out.print(f"\nOurs / the peer's time, best of {args.repeats} (median), alternately:\n")
    out.print(summary_table(summary, args.sizes))
    out.print(
        "\nDegenerate and tiny faces (angle-weighted vertex normals; Open3D's are by area):\n"
    )
    out.print("\n".join(probe()))
    out.write()
    print("\nExtra memory (MiB): peak allocated during the call, minus its output:\n")
    print("| triangles | kernel | output | peak | extra | extra / output |")
    print("|---:|---|---:|---:|---:|---:|")
    for size in args.sizes:
        print("\n".join(memory(size)), flush=True)


if __name__ == "__main__":
    main()
