"""Shared meshes for the mesh-file tests."""

from __future__ import annotations

import struct

import numpy as np

#: A tetrahedron, wound outward.
TETRA_VERTICES = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
TETRA_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def binary_stl(
    corners: np.ndarray,
    normals: np.ndarray | None = None,
    header: bytes = b"test",
    count: int | None = None,
) -> bytes:
    """A binary STL of (m, 3, 3) corners; ``count`` overrides the header's triangle count."""
    corners = np.asarray(corners, dtype="<f4").reshape(-1, 3, 3)
    normals = np.zeros((len(corners), 3)) if normals is None else normals
    body = b"".join(
        struct.pack("<12fH", *normal, *triangle.ravel(), 0)
        for normal, triangle in zip(normals, corners, strict=True)
    )
    stated = len(corners) if count is None else count
    return header.ljust(80, b" ") + struct.pack("<I", stated) + body


def ascii_stl(corners: np.ndarray, normals: np.ndarray) -> bytes:
    lines = ["solid test"]
    for normal, triangle in zip(
        np.asarray(normals).tolist(), np.asarray(corners).tolist(), strict=True
    ):
        lines += [f"  facet normal {normal[0]} {normal[1]} {normal[2]}", "    outer loop"]
        lines += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in triangle]
        lines += ["    endloop", "  endfacet"]
    lines.append("endsolid test")
    return "\n".join(lines).encode()
