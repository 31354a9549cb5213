"""Differential tests: files Open3D writes, read by Open3D and by us, give the same arrays."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mesh_normal.points.io.read import read_points
from mesh_normal.points.io.write import write_points
from tests.paths import DATA

o3d = pytest.importorskip("open3d")

RNG = np.random.default_rng(7)
POINTS = RNG.random((200, 3)) * [1000, 1000, 50] + [500000, 4000000, 0]
NORMALS = RNG.normal(size=(200, 3))
NORMALS /= np.linalg.norm(NORMALS, axis=1, keepdims=True)
COLORS = RNG.random((200, 3))


def open3d_cloud() -> Any:
    cloud = o3d.geometry.PointCloud()
    cloud.points = o3d.utility.Vector3dVector(POINTS)
    cloud.normals = o3d.utility.Vector3dVector(NORMALS)
    cloud.colors = o3d.utility.Vector3dVector(COLORS)
    return cloud


CASES = [
    ("pcd", {"write_ascii": True}),
    ("pcd", {}),
    ("pcd", {"compressed": True}),
    ("ply", {"write_ascii": True}),
    ("ply", {}),
    ("xyz", {}),
    ("xyzn", {}),
    ("xyzrgb", {}),
    ("pts", {}),
]


@pytest.mark.parametrize(("suffix", "options"), CASES, ids=lambda case: str(case))
def test_open3d_files_read_as_open3d_reads_them(
    tmp_path: Path, suffix: str, options: dict[str, bool]
) -> None:
    path = tmp_path / f"cloud.{suffix}"
    assert o3d.io.write_point_cloud(str(path), open3d_cloud(), **options)
    theirs = o3d.io.read_point_cloud(str(path))
    ours = read_points(path)
    np.testing.assert_array_equal(ours.points, np.asarray(theirs.points))
    if theirs.has_normals():
        np.testing.assert_array_equal(ours.normals, np.asarray(theirs.normals))
    else:
        assert ours.normals is None
    if theirs.has_colors():
        assert ours.colors is not None
        np.testing.assert_array_equal(ours.colors, np.round(np.asarray(theirs.colors) * 255))
    else:
        assert ours.colors is None
    np.testing.assert_array_equal(ours.kept, np.arange(len(POINTS)))


def test_compressible_pcd(tmp_path: Path) -> None:
    # Repeated normals and colours make Open3D's LZF write back references, long ones too.
    path = tmp_path / "cloud.pcd"
    cloud = o3d.geometry.PointCloud()
    cloud.points = o3d.utility.Vector3dVector(np.round(POINTS))
    cloud.normals = o3d.utility.Vector3dVector(np.tile([0.0, 0.0, 1.0], (len(POINTS), 1)))
    cloud.colors = o3d.utility.Vector3dVector(np.tile([0.2, 0.4, 0.6], (len(POINTS), 1)))
    o3d.io.write_point_cloud(str(path), cloud, compressed=True)
    assert path.stat().st_size < len(POINTS) * 28 / 2
    theirs, ours = o3d.io.read_point_cloud(str(path)), read_points(path)
    np.testing.assert_array_equal(ours.points, np.asarray(theirs.points))
    np.testing.assert_array_equal(ours.normals, np.asarray(theirs.normals))
    np.testing.assert_array_equal(ours.colors, np.round(np.asarray(theirs.colors) * 255))


@pytest.mark.parametrize("fmt", ["ply", "xyz"])
def test_open3d_reads_what_we_write(tmp_path: Path, fmt: str) -> None:
    path = tmp_path / f"cloud.{fmt}"
    path.write_bytes(write_points(POINTS, NORMALS, fmt))
    theirs = o3d.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(np.asarray(theirs.points), POINTS)
    if fmt == "ply":
        np.testing.assert_array_equal(np.asarray(theirs.normals), NORMALS)


@pytest.mark.parametrize(
    ("name", "count", "normals"),
    [("colored_cloud.pcd", 1000, True), ("pcl_logo.pcd", 12909, False)],
)
def test_files_pcl_wrote(name: str, count: int, normals: bool) -> None:
    path = DATA / "points" / name
    theirs, ours = o3d.io.read_point_cloud(str(path)), read_points(path)
    assert len(ours.points) == count
    np.testing.assert_array_equal(ours.points, np.asarray(theirs.points))
    assert (ours.normals is not None) == normals
    if normals:
        np.testing.assert_array_equal(ours.normals, np.asarray(theirs.normals))
    assert ours.colors is not None
    np.testing.assert_array_equal(ours.colors, np.round(np.asarray(theirs.colors) * 255))
