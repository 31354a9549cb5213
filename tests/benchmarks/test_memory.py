"""benchmarks/memory.py: its files are the torus they claim, in every format, and each path runs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from benchmarks.memory import FORMATS, PATHS, file_bytes, measure, run_path, torus
from mesh_normal.files import read_mesh
from mesh_normal.mesh.topology import mesh_topology


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


@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="needs Linux's /proc")
def test_a_measurement_runs_in_its_child_process(tmp_path: Path) -> None:
    # The child does what a job worker does before a binary STL (keeps freed memory, prefaults):
    # a figure, not the NaN that a failed child gives.
    file, small = tmp_path / "torus.stl", tmp_path / "small.stl"
    file.write_bytes(file_bytes("stl", *torus(60, 50)))
    small.write_bytes(file_bytes("stl", *torus(6, 5)))
    assert math.isfinite(measure("read", file, small))
