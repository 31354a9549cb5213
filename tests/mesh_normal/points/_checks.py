"""The checks every PointNormals must pass, whatever the cloud."""

from __future__ import annotations

import numpy as np

from mesh_normal.points import PointNormals, PointStatus


def assert_well_formed(result: PointNormals, n: int) -> None:
    assert result.normals.shape == (n, 3) and result.normals.dtype == np.float64
    assert result.curvature.shape == (n,) and result.status.dtype == np.uint8
    assert np.isfinite(result.normals).all() and np.isfinite(result.curvature).all()
    lengths = np.linalg.norm(result.normals, axis=1)
    assert np.all(lengths[~result.valid] == 0.0)
    np.testing.assert_allclose(lengths[result.valid], 1.0, rtol=0, atol=1e-15)
    valid = np.isin(result.status, (PointStatus.ok, PointStatus.unoriented, PointStatus.sharp))
    np.testing.assert_array_equal(result.valid, valid)
    assert np.all((result.curvature >= 0) & (result.curvature <= 1 / 3 + 1e-15))
