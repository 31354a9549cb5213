"""point_normals: accuracy on analytic clouds, offsets, statuses, degenerate input, checks."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mesh_normal.points import PointStatus, point_normals
from tests.mesh_normal.points import _clouds as clouds
from tests.mesh_normal.points._checks import assert_well_formed

OFFSETS = (0.0, 1e6, 1e8)


# --- accuracy on analytic clouds ---------------------------------------------------------------

#: (cloud, points, the largest unoriented RMSE in degrees at k = 30): measured 0.38, 1.21,
#: 0.39, 0.16 and (away from the edges) 0.01.
SHAPES = {
    "sphere": (clouds.sphere, 20_000, 0.5),
    "torus": (clouds.torus, 20_000, 1.5),
    "cylinder": (clouds.cylinder, 20_000, 0.5),
    "terrain": (clouds.terrain, 20_000, 0.25),
}


@pytest.mark.parametrize("offset", OFFSETS)
@pytest.mark.parametrize("name", SHAPES)
def test_smooth_shapes_are_accurate_and_oriented_at_any_offset(name: str, offset: float) -> None:
    make, n, limit = SHAPES[name]
    points, truth = make(n)
    result = point_normals(points + offset)
    assert_well_formed(result, n)
    assert result.valid.all() and result.unoriented == 0
    assert clouds.rmse(clouds.angles(result.normals, truth, unoriented=True)) < limit
    assert np.all(clouds.angles(result.normals, truth) < 90)  # outward, or up for the terrain


@pytest.mark.parametrize("offset", OFFSETS)
def test_a_cube_is_exact_away_from_its_sharp_edges(offset: float) -> None:
    size = (1.0, 1.0, 1.0)
    points, truth = clouds.box(30_000, size=size)
    result = point_normals(points + offset, k=30)
    # Neighbourhoods that reach over an edge blend two faces; 30 neighbours at this density
    # reach up to about 0.05 (measured: errors to 9 degrees at 0.04, none past 0.06).
    inside = ~clouds.near_edges(points, size, 0.06)
    assert clouds.angles(result.normals, truth, unoriented=True)[inside].max() < 1e-6
    assert np.all(clouds.angles(result.normals, truth)[inside] < 90)
    assert result.unoriented == 0


@pytest.mark.parametrize(("sigma", "limit"), [(0.002, 1.5), (0.01, 6.0)])
def test_noise_costs_accuracy_but_not_the_orientation(sigma: float, limit: float) -> None:
    points, truth = clouds.sphere(20_000)
    noisy = points + np.random.default_rng(1).normal(scale=sigma, size=points.shape)
    for offset in OFFSETS:
        result = point_normals(noisy + offset)
        assert clouds.rmse(clouds.angles(result.normals, truth, unoriented=True)) < limit
        assert np.all(clouds.angles(result.normals, truth) < 90)


@pytest.mark.parametrize("make", [clouds.sphere, clouds.torus, clouds.terrain])
def test_moving_a_cloud_exactly_changes_no_bit(make) -> None:  # type: ignore[no-untyped-def]
    points = clouds.rounded(make(5_000)[0])
    at_origin = point_normals(points)
    for offset in (1e6, 1e8):
        moved = point_normals(points + offset)
        np.testing.assert_array_equal(moved.normals, at_origin.normals)
        np.testing.assert_array_equal(moved.curvature, at_origin.curvature)


@pytest.mark.parametrize("offset", [1e6, 1e8])
def test_the_rounding_of_a_move_moves_the_normals_by_little(offset: float) -> None:
    # Moving by 1e8 rounds each coordinate by up to 7.5e-9; neighbourhoods here are about
    # 0.07 across, so the normals may turn by about 1e-7 rad: 1e-6 holds with room.
    points, _ = clouds.sphere(20_000)
    at_origin = point_normals(points)
    moved = point_normals(points + offset)
    dots = np.einsum("ij,ij->i", at_origin.normals, moved.normals)
    assert np.arccos(np.clip(dots, -1, 1)).max() < 1e-6


def test_curvature_is_the_surface_variation() -> None:
    points, _ = clouds.box(5_000)
    flat = ~clouds.near_edges(points, (1.0, 1.0, 1.0), 0.2)  # neighbourhoods reach 0.15
    result = point_normals(points, k=30)
    assert result.curvature[flat].max() < 1e-20
    sphere = point_normals(clouds.sphere(5_000)[0], k=30)
    assert sphere.curvature.min() > 0 and sphere.curvature.max() < 0.01


def test_radius_neighbourhoods() -> None:
    points, truth = clouds.sphere(20_000)
    within = point_normals(points, k=None, radius=0.08)
    capped = point_normals(points, k=20, radius=0.08)
    assert within.neighbours.min() >= 3 and within.neighbours.max() > 30
    assert capped.neighbours.max() == 20
    for result in (within, capped):
        assert clouds.rmse(clouds.angles(result.normals, truth, unoriented=True)) < 1.0
        assert np.all(clouds.angles(result.normals, truth) < 90)
    alone = point_normals(np.r_[points, [[5.0, 5, 5]]], k=None, radius=0.08)
    assert alone.status[-1] == PointStatus.too_few_neighbours and alone.neighbours[-1] == 1


# --- statuses and degenerate input ---------------------------------------------------------------


def test_two_points_have_too_few_neighbours() -> None:
    result = point_normals([[0.0, 0, 0], [1, 0, 0]])
    assert_well_formed(result, 2)
    assert list(result.status) == [PointStatus.too_few_neighbours] * 2
    assert not result.normals.any() and list(result.neighbours) == [2, 2]


@pytest.mark.parametrize("offset", OFFSETS)
def test_a_line_is_collinear_at_any_offset(offset: float) -> None:
    line = np.linspace(0, 1, 50)[:, None] * np.array([1.0, 2.0, 3.0]) + offset
    result = point_normals(line, k=10)
    assert_well_formed(result, 50)
    assert np.all(result.status == PointStatus.collinear) and not result.normals.any()


def test_coincident_points_are_duplicates_and_a_pair_of_positions_collinear() -> None:
    same = np.tile([[1e8, -3.0, 2.5]], (40, 1))
    result = point_normals(same)
    assert np.all(result.status == PointStatus.duplicates) and not result.normals.any()
    assert np.all(result.curvature == 0.0)
    two = np.r_[np.zeros((20, 3)), np.ones((20, 3))]
    assert np.all(point_normals(two).status == PointStatus.collinear)


def test_duplicated_points_of_a_surface_keep_their_normals() -> None:
    points, truth = clouds.sphere(5_000)
    doubled = point_normals(np.r_[points, points])
    assert doubled.valid.all()
    assert clouds.rmse(clouds.angles(doubled.normals, np.r_[truth, truth], True)) < 1.0


def test_a_symmetric_neighbourhood_is_ambiguous() -> None:
    star = np.array(
        [[0.0, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    )
    result = point_normals(star, k=7)
    assert np.all(result.status == PointStatus.ambiguous) and not result.normals.any()
    assert np.allclose(result.curvature, 1 / 3)


def test_non_finite_points_get_a_status_and_are_no_ones_neighbours() -> None:
    points, _ = clouds.sphere(2_000)
    broken = points.copy()
    broken[[3, 10, 500]] = [[np.nan, 0, 0], [np.inf, 1, 1], [0, 0, -np.inf]]
    result = point_normals(broken)
    assert_well_formed(result, 2_000)
    assert list(np.flatnonzero(result.status == PointStatus.not_finite)) == [3, 10, 500]
    assert not result.normals[[3, 10, 500]].any() and result.neighbours[3] == 0
    clean = point_normals(np.delete(points, [3, 10, 500], axis=0))
    np.testing.assert_allclose(np.delete(result.normals, [3, 10, 500], axis=0), clean.normals)
    assert result.counts()["not_finite"] == 3 and result.counts()["ok"] == 1997


def test_nothing_finite_and_nothing_at_all() -> None:
    result = point_normals(np.full((4, 3), np.nan))
    assert np.all(result.status == PointStatus.not_finite) and result.components == ()
    empty = point_normals(np.empty((0, 3)))
    assert empty.normals.shape == (0, 3) and empty.components == ()


def test_the_status_codes_are_stable() -> None:
    assert {status.name: int(status) for status in PointStatus} == {
        "ok": 0,
        "not_finite": 1,
        "too_few_neighbours": 2,
        "duplicates": 3,
        "collinear": 4,
        "ambiguous": 5,
        "unoriented": 6,
        "sharp": 7,
    }


# --- checked input -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"points": [[0.0, 0.0]]}, "shape"),
        ({"points": [["a", "b", "c"]]}, "numbers"),
        ({"points": [[1j, 0, 0]]}, "real"),
        ({"k": 2}, "at least 3"),
        ({"k": 3.5}, "whole number"),
        ({"radius": -1.0}, "radius"),
        ({"radius": float("nan")}, "radius"),
        ({"orient": "outward"}, "orient must be one of"),
        ({"orient": "viewpoint"}, "needs viewpoint"),
        ({"orient": "direction", "direction": [0, 0, 0]}, "not be zero"),
        ({"orient": "direction", "direction": [0, 1]}, "three finite numbers"),
        ({"orient": "file"}, "stored"),
        ({"orient": "file", "stored": np.zeros((3, 3))}, "(5, 3)"),
        ({"viewpoint": [0, 0, 1]}, 'only used with orient="viewpoint"'),
        ({"max_angle": 0}, "max_angle"),
        ({"max_angle": 120}, "max_angle"),
    ],
)
def test_bad_arguments_are_clear_errors(kwargs: dict, words: str) -> None:  # type: ignore[type-arg]
    arguments = {"points": np.random.default_rng(0).normal(size=(5, 3)), **kwargs}
    with pytest.raises(ValueError, match=re.escape(words)):
        point_normals(**arguments)
