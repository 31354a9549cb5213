"""Properties of point_normals: permutation, rotation, translation and scale (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.points import PointStatus, point_normals
from tests.mesh_normal.points._checks import assert_well_formed

PROPERTY = settings(max_examples=25, deadline=None)


def ellipsoid(seed: int, n: int) -> np.ndarray:
    """A closed, smooth cloud with distinct distances: random points on an ellipsoid."""
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return directions * rng.uniform(0.5, 2.0, size=3)


def rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


seeds = st.integers(0, 2**32 - 1)
sizes = st.integers(60, 600)


@PROPERTY
@given(seeds, sizes, st.sampled_from(["mst", "riemannian", "none"]))
def test_the_order_of_the_points_does_not_matter(seed: int, n: int, orient: str) -> None:
    points = ellipsoid(seed, n)
    order = np.random.default_rng(seed + 1).permutation(n)
    first = point_normals(points, k=12, orient=orient)  # type: ignore[arg-type]
    shuffled = point_normals(points[order], k=12, orient=orient)  # type: ignore[arg-type]
    np.testing.assert_array_equal(shuffled.status, first.status[order])
    np.testing.assert_allclose(shuffled.normals, first.normals[order], rtol=0, atol=1e-12)
    np.testing.assert_allclose(shuffled.curvature, first.curvature[order], rtol=0, atol=1e-15)


@PROPERTY
@given(seeds, sizes)
def test_rotating_the_cloud_rotates_its_normals(seed: int, n: int) -> None:
    """Up to sign: the seeds of the orientation are extreme points along the axes, so on a
    cloud this sparse (12 neighbours of 60 points) a rotation may seed it differently."""
    points, turn = ellipsoid(seed, n), rotation(seed)
    first = point_normals(points, k=12, orient="none")
    turned = point_normals(points @ turn.T, k=12, orient="none")
    np.testing.assert_array_equal(turned.status, first.status)
    agreement = np.einsum("ij,ij->i", turned.normals, first.normals @ turn.T)
    np.testing.assert_allclose(np.abs(agreement), 1.0, rtol=0, atol=1e-8)
    np.testing.assert_allclose(turned.curvature, first.curvature, rtol=1e-6, atol=1e-15)


@PROPERTY
@given(seeds, sizes, st.floats(-1e8, 1e8), st.integers(-30, 30))
def test_moving_and_scaling_change_nothing(seed: int, n: int, shift: float, power: int) -> None:
    points = ellipsoid(seed, n)
    first = point_normals(points, k=12)
    # A power of two scales exactly: the same bits.
    scaled = point_normals(points * 2.0**power, k=12)
    np.testing.assert_array_equal(scaled.normals, first.normals)
    # A move rounds each coordinate by up to 2**-53 |shift| (7.5e-9 at 1e8); neighbourhoods
    # here are 0.1 to 1 across, so the normals turn by at most about 1e-6.
    moved = point_normals(points + shift, k=12)
    np.testing.assert_array_equal(moved.status, first.status)
    np.testing.assert_allclose(moved.normals, first.normals, rtol=0, atol=1e-6)


coordinates = st.one_of(
    st.sampled_from([0.0, 1.0, -1.0, 1e8, np.nan, np.inf, -np.inf]),
    st.floats(-1e12, 1e12, allow_nan=False),
)


@PROPERTY
@given(
    st.lists(st.tuples(coordinates, coordinates, coordinates), max_size=60),
    st.integers(3, 12),
    st.sampled_from(["mst", "riemannian", "none", "direction"]),
)
def test_any_cloud_gives_unit_or_zero_rows_and_statuses(
    rows: list[tuple[float, float, float]], k: int, orient: str
) -> None:
    points = np.array(rows, dtype=np.float64).reshape(-1, 3)
    direction = [0.0, 0.0, 1.0] if orient == "direction" else None
    result = point_normals(points, k=k, orient=orient, direction=direction)  # type: ignore[arg-type]
    assert_well_formed(result, len(points))
    assert np.all(result.status[~np.isfinite(points).all(axis=1)] == PointStatus.not_finite)
    assert sum(result.counts().values()) == len(points)
    assert result.unoriented == int((result.status == PointStatus.unoriented).sum())
