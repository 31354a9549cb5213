"""analyse_points: the report on hand-built clouds (a plane grid, a sphere, duplicates, a PCD)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import TypeAdapter

from mesh_normal.points import read_points
from mesh_normal.points.analysis import analyse_points
from mesh_normal.points.io.read import make_cloud
from mesh_normal.points.report import POINT_AGREEMENT_DEGREES, PointReport
from tests.mesh_normal.points._clouds import sphere
from tests.mesh_normal.points._pcd import pcd_header


def grid(side: int = 10, step: float = 0.5) -> np.ndarray:
    """A side x side grid in the plane z = 0, ``step`` apart."""
    x, y = np.meshgrid(np.arange(side) * step, np.arange(side) * step)
    return np.column_stack([x.ravel(), y.ravel(), np.zeros(side * side)])


def test_plane_grid_faces_up_with_exact_spacing() -> None:
    points = grid()
    analysis = analyse_points(make_cloud("xyz", points), name="plane.xyz", size=1234)
    report = analysis.report
    assert report.points == 100 and report.with_normal == 100
    assert report.counts.ok == 100 and report.counts.unoriented == 0
    assert report.file.name == "plane.xyz" and report.file.bytes == 1234
    assert report.file.format == "xyz" and report.file.has_normals is False
    assert report.bounds is not None
    assert (report.bounds.min, report.bounds.max) == ([0.0, 0.0, 0.0], [4.5, 4.5, 0.0])
    assert report.spacing is not None
    # Every grid point's nearest other point is one step away, exactly.
    assert (report.spacing.min, report.spacing.median, report.spacing.max) == (0.5, 0.5, 0.5)
    assert report.spacing.coincident == 0
    assert report.neighbourhood.k is None and report.neighbourhood.radius is None
    assert report.orientation.mode == "mst" and report.orientation.part_count == 1
    np.testing.assert_array_equal(analysis.normals.normals, np.tile([0.0, 0.0, 1.0], (100, 1)))
    assert report.stored_normals is None
    assert report.diagnosis == ["Every point has a normal, oriented as asked."]


def test_sphere_points_out_and_stored_normals_agree() -> None:
    points, truth = sphere(2000, seed=3)
    report = analyse_points(make_cloud("ply", points, normals=truth)).report
    assert report.counts.ok == 2000
    assert report.orientation.flipped >= 0 and report.orientation.unoriented == 0
    stored = report.stored_normals
    assert stored is not None
    assert (stored.stored, stored.compared, stored.unusable) == (2000, 2000, 0)
    assert stored.agreeing == 2000 and stored.agreement_degrees == POINT_AGREEMENT_DEGREES
    assert stored.median_angle_degrees is not None and stored.median_angle_degrees < 2.0
    assert stored.same_side_fraction == 1.0
    assert report.diagnosis == ["Every point has a normal, oriented as asked."]


def test_flipped_stored_normals_are_diagnosed() -> None:
    points, truth = sphere(1000, seed=4)
    report = analyse_points(make_cloud("ply", points, normals=-truth)).report
    assert report.stored_normals is not None
    assert report.stored_normals.same_side_fraction == 0.0
    assert report.stored_normals.agreeing == 1000  # the lines agree; the sides do not
    assert any("other side from ours for 100%" in line for line in report.diagnosis)


def test_orient_file_keeps_the_stored_sides() -> None:
    points, truth = sphere(1000, seed=5)
    analysis = analyse_points(make_cloud("ply", points, normals=-truth), orient="file")
    assert analysis.report.stored_normals is not None
    assert analysis.report.stored_normals.same_side_fraction == 1.0
    assert np.all(np.einsum("ij,ij->i", analysis.normals.normals, truth) < 0)


def test_orient_file_without_stored_normals_is_one_sentence() -> None:
    with pytest.raises(ValueError, match=r'^orient="file" needs normals stored in the file'):
        analyse_points(make_cloud("xyz", grid()), orient="file")


def test_duplicates_and_isolated_points_are_diagnosed() -> None:
    plane = grid()
    doubled = np.vstack([plane, plane[:5], [[100.0, 100.0, 100.0]], [[100.0, 100.0, 100.0]]])
    report = analyse_points(make_cloud("xyz", doubled), k=None, radius=0.6).report
    assert report.spacing is not None and report.spacing.min == 0.0
    assert report.spacing.coincident == 12  # five pairs and the far pair
    # The far pair: their neighbourhood (within 0.6) is the two of them: too few.
    assert report.counts.too_few_neighbours == 2
    assert report.with_normal == 105
    assert report.neighbourhood.radius == 0.6 and report.neighbourhood.k is None
    text = " ".join(report.diagnosis)
    assert "12 points sit exactly where another point is" in text
    assert "2 points have fewer than 3 points within the radius 0.6" in text


def test_coincident_neighbourhoods_have_status_duplicates() -> None:
    plane = grid(4)
    stacked = np.vstack([plane, np.repeat([[9.0, 9.0, 9.0]], 5, axis=0)])
    report = analyse_points(make_cloud("xyz", stacked), k=None, radius=1.0).report
    assert report.counts.duplicates == 5
    assert any("(duplicated points)" in line for line in report.diagnosis)


def test_collinear_points_are_diagnosed() -> None:
    line = np.column_stack([np.arange(20.0), np.zeros(20), np.zeros(20)])
    report = analyse_points(make_cloud("xyz", line), k=5).report
    assert report.counts.collinear == 20 and report.with_normal == 0
    assert any("lie on a line" in line and "k = 5" in line for line in report.diagnosis)


def pcd_with_viewpoint(points: np.ndarray, viewpoint: str) -> bytes:
    body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
    return pcd_header("x y z", "4 4 4", "F F F", len(points), viewpoint=viewpoint) + body.encode()


def test_pcd_viewpoint_is_used_when_none_is_given() -> None:
    cloud = read_points(pcd_with_viewpoint(grid(), "1 2 -5 1 0 0 0"), "scan.pcd")
    report = analyse_points(cloud, orient="viewpoint").report
    assert report.file.format == "pcd" and report.file.viewpoint == [1.0, 2.0, -5.0]
    assert report.orientation.viewpoint == [1.0, 2.0, -5.0]
    assert report.orientation.viewpoint_from_file is True
    assert report.counts.ok == 100
    # The sensor is below the plane: every normal faces down.
    assert np.all(analyse_points(cloud, orient="viewpoint").normals.normals[:, 2] == -1.0)


def test_a_given_viewpoint_wins_over_the_file() -> None:
    cloud = read_points(pcd_with_viewpoint(grid(), "1 2 -5 1 0 0 0"), "scan.pcd")
    analysis = analyse_points(cloud, orient="viewpoint", viewpoint=(0, 0, 5))
    assert analysis.report.orientation.viewpoint_from_file is False
    assert analysis.report.orientation.viewpoint == [0.0, 0.0, 5.0]
    assert np.all(analysis.normals.normals[:, 2] == 1.0)


def test_viewpoint_without_one_anywhere_is_one_sentence() -> None:
    with pytest.raises(ValueError, match=r'^orient="viewpoint" needs a viewpoint'):
        analyse_points(make_cloud("xyz", grid()), orient="viewpoint")


def test_side_on_points_are_unoriented_with_the_reason() -> None:
    report = analyse_points(make_cloud("xyz", grid()), orient="direction", direction=(1, 0, 0))
    assert report.report.counts.unoriented == 100
    assert report.report.orientation.direction == [1.0, 0.0, 0.0]
    (line,) = report.report.diagnosis
    assert line.startswith("100 points have a normal whose side could not be decided (100 points")


def test_json_round_trips_and_is_strict() -> None:
    points, truth = sphere(300, seed=6)
    report = analyse_points(make_cloud("ply", points, normals=truth)).report
    text = report.to_json()
    assert "NaN" not in text and "Infinity" not in text
    assert TypeAdapter(PointReport).validate_python(json.loads(text)) == report


def test_first_hundred_parts_listed_and_all_counted() -> None:
    # 120 far-apart triangles of points: each its own part of the neighbour graph.
    rng = np.random.default_rng(7)
    blobs = [rng.normal(size=(6, 3)) * [1, 1, 0] + [50.0 * i, 0, 0] for i in range(120)]
    report = analyse_points(make_cloud("xyz", np.vstack(blobs)), k=6).report
    assert report.orientation.part_count == 120
    assert len(report.orientation.parts) == 100


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 60),
    doubled=st.integers(0, 10),
    k=st.integers(3, 12),
)
def test_the_counts_add_up(seed: int, n: int, doubled: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3)) * [1.0, 1.0, rng.uniform(0, 1)]
    points = np.vstack([points, points[:doubled]])
    report = analyse_points(make_cloud("xyz", points), k=k).report
    counts = report.counts.to_dict()
    assert sum(counts.values()) == report.points == len(points)
    assert report.with_normal == counts["ok"] + counts["unoriented"]
    parts = report.orientation.parts
    assert sum(part.points for part in parts) == report.with_normal
    assert sum(part.unoriented for part in parts) == counts["unoriented"]
    assert report.spacing is not None
    assert report.spacing.coincident >= 2 * min(doubled, n)  # each copy and its original
    assert report.diagnosis and all(line.endswith(".") for line in report.diagnosis)


def test_a_slab_thinner_than_its_neighbourhoods_is_said_to_be_far_from_flat() -> None:
    """1 x 1 x 0.02, 30,000 points: k = 30 reaches across the wall; a sphere does not."""
    slab = np.random.default_rng(0).uniform(size=(30_000, 3)) * [1.0, 1.0, 0.02]
    report = analyse_points(make_cloud("xyz", slab), k=30).report
    assert report.far_from_flat > report.points // 2
    assert any("far from flat" in line and "riemannian" in line for line in report.diagnosis)
    smooth = analyse_points(make_cloud("xyz", sphere(5000)[0])).report
    assert smooth.far_from_flat == 0
    assert not any("far from flat" in line for line in smooth.diagnosis)
