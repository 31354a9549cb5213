"""The point functions take the clouds people hold: what read_points returns, an Open3D
PointCloud (with its normals), a trimesh.PointCloud, a PyVista PolyData and a mesh's vertices,
each giving the results of the raw points; anything else gets one sentence of what can be
passed. PyVista is not a test dependency: see tests/mesh_normal/mesh/test_held_meshes.py."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import trimesh

import mesh_normal as mn
from mesh_normal.points import analyse_points
from tests.mesh_normal.mesh.test_held_meshes import PolyData
from tests.mesh_normal.points import _clouds as clouds

open3d = pytest.importorskip("open3d")

POINTS, NORMALS = clouds.sphere(400)


def xyz_text(points: np.ndarray, normals: np.ndarray) -> bytes:
    rows = np.column_stack([points, normals]).tolist()
    return "".join(" ".join(repr(x) for x in row) + "\n" for row in rows).encode()


def open3d_cloud(points: np.ndarray, normals: np.ndarray | None) -> Any:
    cloud = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(points))
    if normals is not None:
        cloud.normals = open3d.utility.Vector3dVector(normals)
    return cloud


HOLDERS: dict[str, Callable[[], object]] = {
    "read_points": lambda: mn.read_points(xyz_text(POINTS, NORMALS), "s.xyzn"),
    "open3d": lambda: open3d_cloud(POINTS, NORMALS),
    "trimesh": lambda: trimesh.PointCloud(POINTS),
    "pyvista": lambda: PolyData(POINTS, np.empty(0, dtype=np.int64)),
    "mesh": lambda: trimesh.Trimesh(POINTS, np.empty((0, 3), dtype=np.int64), process=False),
}


@pytest.fixture(params=list(HOLDERS))
def held(request: pytest.FixtureRequest) -> object:
    return HOLDERS[request.param]()


def test_point_normals_of_a_held_cloud(held: object) -> None:
    ours, theirs = mn.point_normals(held, k=12), mn.point_normals(POINTS, k=12)
    np.testing.assert_array_equal(ours.normals, theirs.normals)
    np.testing.assert_array_equal(ours.status, theirs.status)


def test_a_held_cloud_is_reported(held: object) -> None:
    report = analyse_points(held, k=12).report
    assert report.points == len(POINTS) and report.counts.ok == len(POINTS)
    assert report.file.format == ("xyz" if isinstance(held, mn.PointCloud) else "memory")


@pytest.mark.parametrize("make", [HOLDERS["open3d"], HOLDERS["read_points"]], ids=["o3d", "read"])
def test_a_clouds_own_normals_orient_it(make: Callable[[], object]) -> None:
    flipped = mn.point_normals(make(), k=12, orient="file")
    np.testing.assert_array_equal(
        flipped.normals, mn.point_normals(POINTS, k=12, orient="file", stored=NORMALS).normals
    )
    report = analyse_points(make(), k=12, orient="file").report
    assert report.file.has_normals and report.stored_normals is not None
    assert report.stored_normals.compared == len(POINTS)
    assert report.stored_normals.same_side_fraction == 1.0


def test_an_open3d_cloud_without_normals_has_none() -> None:
    with pytest.raises(ValueError, match='orient="file" needs'):
        analyse_points(open3d_cloud(POINTS, None), orient="file")


@pytest.mark.parametrize(
    ("value", "words"),
    [
        ("scan.ply", "not a file: read it with mn.read_points first"),
        (7, "a PyVista PolyData, or a mesh \\(its vertices\\), not int"),
        ({"points": 1}, "not dict"),
    ],
)
def test_anything_else_gets_a_sentence_of_what_can_be_passed(value: object, words: str) -> None:
    with pytest.raises(TypeError, match=words):
        mn.point_normals(value)
    with pytest.raises(TypeError, match=words):
        analyse_points(value)  # type: ignore[arg-type]
