"""A folder of 50+ files for the batch tests, with each file's expected row, worked by hand.

:func:`make_dataset` writes it (the Dask tests use it too): 40 cubes of side 1 to 40 in four
formats (a cube of side s: 8 vertices, 12 faces, area 6 s², volume s³, outward), an inside-out
cube, an open box, a cube with a degenerate face, five real meshes of ``tests/data``, and
broken ones: a cut-short PLY header, a PLY that claims four billion vertices, an empty STL, a
file that is not a mesh at all. Beside them a point cloud and a text file, which a mesh batch
skips (their suffixes name no mesh format).
"""

from __future__ import annotations

import shutil
import signal
from pathlib import Path
from typing import Any

import numpy as np

import mesh_normal as mn
from tests.paths import DATA

CUBE_VERTICES = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.float64,
)
#: Wound outward (counter-clockwise seen from outside).
CUBE_FACES = np.array(
    [
        [0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
        [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7],
    ]
)  # fmt: skip
CUBE_FORMATS = ("stl", "obj", "ply", "off")
REAL = ("cube.obj", "multibody.stl", "sphere.ply", "teapot.stl", "two_objects.obj")
#: The number of rows the folder gives a mesh batch.
MESH_FILES = 40 + 3 + len(REAL) + 4
#: Files in it that a mesh batch skips: the point cloud and the notes.
SKIPPED = 2

HOSTILE_PLY = (
    b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
    b"property float x\nproperty float y\nproperty float z\n"
    b"element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n" + bytes(96)
)


def cube_row(side: int) -> dict[str, Any]:
    """What the table says about a cube of side ``side``, worked by hand."""
    return {
        "status": "ok",
        "vertices": 8,
        "faces": 12,
        "components": 1,
        "area": 6.0 * side**2,
        "volume": float(side**3),
        "watertight": True,
        "winding_consistent": True,
        "orientation": "outward",
        "degenerate_faces": 0,
        "boundary_edges": 0,
        "nonmanifold_edges": 0,
        "faces_flipped": 0,
        "problems_found": [],
        "error": None,
    }


def make_dataset(root: Path) -> dict[str, dict[str, Any]]:
    """Write the folder under ``root``; returns the expected figures by path (as the table
    names them: ``root``'s path joined with the file's relative path)."""
    expected: dict[str, dict[str, Any]] = {}

    def put(relative: str, data: bytes, figures: dict[str, Any] | None = None) -> None:
        path = root / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        if figures is not None:
            expected[f"{root.as_posix()}/{relative}"] = {"size": len(data), **figures}

    for side in range(1, 41):
        fmt = CUBE_FORMATS[side % 4]
        folder = "cubes" if side <= 30 else "cubes/deeper/still"
        put(f"{folder}/cube_{side:02d}.{fmt}", cube(side, fmt), {"format": fmt, **cube_row(side)})
    inside_out = mn.write_mesh(CUBE_VERTICES, CUBE_FACES[:, ::-1], "stl")
    put(
        "problems/inside_out.stl",
        inside_out,
        {"status": "problems", "orientation": "inward", "volume": -1.0, "faces_flipped": 12},
    )
    put(
        "problems/open_box.obj",
        mn.write_mesh(CUBE_VERTICES, CUBE_FACES[2:], "obj"),
        {"status": "problems", "faces": 10, "watertight": False, "boundary_edges": 4,
         "volume": None, "problems_found": ["open"]},
    )  # fmt: skip
    # A face from vertex 0 through the middle of the edge 0-1 to 1: no area; the edge 0-1 now
    # has three faces (one non-manifold edge), 0-8 and 8-1 one each (two boundary edges).
    vertices = np.vstack([CUBE_VERTICES, [[0.5, 0.0, 0.0]]])
    faces = np.vstack([CUBE_FACES, [[0, 8, 1]]])
    put(
        "problems/degenerate.obj",
        mn.write_mesh(vertices, faces, "obj"),
        {"status": "problems", "faces": 13, "degenerate_faces": 1, "nonmanifold_edges": 1,
         "boundary_edges": 2},
    )  # fmt: skip
    for name in REAL:
        put(f"real/{name}", (DATA / name).read_bytes(), {})
    unreadable = {"status": "unreadable", "format": None, "faces": None}
    put(
        "broken/cut_short.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n",
        unreadable,
    )
    put("broken/hostile.ply", HOSTILE_PLY, unreadable)
    put("broken/empty.stl", b"", {**unreadable, "hash": mn_hash(b"")})
    put("broken/not_a_mesh.obj", b"\x00\x01 this is no OBJ \xff\xfe", {"status": "unreadable"})
    put("other/cloud.xyz", cloud_text())
    put("other/notes.txt", b"not a mesh\n")
    assert len(expected) == MESH_FILES
    return expected


def cube(side: int, fmt: str) -> bytes:
    """A cube of side ``side`` in ``fmt``, at the origin."""
    return mn.write_mesh(CUBE_VERTICES * side, CUBE_FACES, fmt)


def cloud_text() -> bytes:
    """A point cloud: 200 points on the unit sphere, as an XYZ text file."""
    points = np.random.default_rng(14).normal(size=(200, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    return "".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in points).encode()


def mn_hash(data: bytes) -> str:
    """The table's hash column: BLAKE2b-128 of the bytes (hashlib, not the library's)."""
    import hashlib

    return hashlib.blake2b(data, digest_size=16).hexdigest()


def copy_real(root: Path) -> None:
    """The real meshes alone (for small runs)."""
    for name in REAL:
        shutil.copy(DATA / name, root / name)


def hear_ctrl_c() -> None:
    """In the child before it starts: SIGINT back to its default. A test run started in the
    background by a shell without job control inherits SIGINT ignored, and then Python (and
    so the batch) ignores Ctrl-C too, as a background job should."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
