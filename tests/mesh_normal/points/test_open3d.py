"""Differential: the unoriented normals agree with Open3D's on clean clouds at the origin."""

from __future__ import annotations

import numpy as np
import pytest

from mesh_normal.points import point_normals
from tests.mesh_normal.points import _clouds as clouds

open3d = pytest.importorskip("open3d")

#: Radians. Measured: at most 3.9e-8 between the two on these clouds (Open3D solves the 3 x 3
#: eigenproblem in closed form, which costs it a few digits; our Jacobi solve is accurate to
#: about 1e-15 here).
AGREEMENT = 1e-7


def open3d_normals(points: np.ndarray, k: int = 30) -> np.ndarray:
    cloud = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(points))
    cloud.estimate_normals(open3d.geometry.KDTreeSearchParamKNN(k))
    return np.asarray(cloud.normals)


@pytest.mark.parametrize("make", [clouds.sphere, clouds.torus, clouds.terrain, clouds.box])
@pytest.mark.parametrize("k", [10, 30])
def test_the_same_lines_as_open3d(make, k: int) -> None:  # type: ignore[no-untyped-def]
    points, _ = make(20_000)
    ours = point_normals(points, k=k, orient="none")
    theirs = open3d_normals(points, k)
    assert ours.valid.all()
    dots = np.abs(np.einsum("ij,ij->i", ours.normals, theirs))
    sines = np.sqrt(np.maximum(0.0, 1.0 - dots**2))
    assert sines.max() < AGREEMENT
