"""benchmarks/memory.py: its files are the torus they claim, in every format, and each path runs."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.memory import FORMATS, PATHS, file_bytes, run_path, torus
from mesh_normal.files import read_mesh
from mesh_normal.topology import mesh_topology


@pytest.mark.parametrize("kind", FORMATS)
def test_each_format_holds_the_closed_torus(kind: str) -> None:
    points, faces = torus(6, 5)
    suffix = {"stl-ascii": "stl", "ply-ascii": "ply"}.get(kind, kind)
    mesh = read_mesh(file_bytes(kind, points, faces), f"torus.{suffix}")
    assert mesh.format == suffix and len(mesh.faces) == 60 and len(mesh.vertices) == 30
    assert mesh_topology(mesh.checked()).watertight
    np.testing.assert_allclose(np.sort(mesh.vertices, axis=0), np.sort(points, axis=0), atol=1e-6)


@pytest.mark.parametrize("path_name", PATHS)
def test_each_path_runs(path_name: str) -> None:
    run_path(path_name, file_bytes("ply", *torus(6, 5)), "torus.ply")
