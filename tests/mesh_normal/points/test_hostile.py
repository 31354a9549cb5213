"""Hostile point clouds: compressed data that expand far, piles of coincident points,
LAS headers that lie. Each is answered within seconds: a sentence, or normals."""

from __future__ import annotations

import time

import numpy as np
import pytest

from mesh_normal.files import expansion
from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.expansion import ExpansionTooLarge
from mesh_normal.points.analysis import analyse_points
from mesh_normal.points.estimate import PointStatus, coincident_groups, point_normals
from mesh_normal.points.io.pcd import lzf_decompress
from mesh_normal.points.io.read import make_cloud, read_points
from tests.mesh_normal.points import _clouds as clouds
from tests.mesh_normal.points._hostile import (
    HOSTILE_POINTS,
    coincident_xyz,
    las_count,
    las_points,
    laz_bomb,
    lzf_bomb_pcd,
    zeros_lzf,
)
from tests.paths import ROOT

HOSTILE = ROOT / "tests" / "data" / "hostile"
#: Generous: unguarded, each case takes a minute or more, or gigabytes.
SECONDS = 10.0


# --- compressed data: charged before they are unpacked -------------------------------------


def test_zeros_lzf_unpacks_to_zeros() -> None:
    for size in (1, 2, 265, 1000):
        assert lzf_decompress(zeros_lzf(size), size).tobytes() == bytes(size)


def test_an_lzf_pcd_of_3_million_points_is_refused_before_unpacking() -> None:
    """436 KB of LZF holding 3,000,000 points (36 MB unpacked)."""
    data = lzf_bomb_pcd(3_000_000, 4, "F")
    assert len(data) < 450_000
    began = time.monotonic()
    with pytest.raises(ExpansionTooLarge) as caught:
        read_points(data, "bomb.pcd")
    assert time.monotonic() - began < SECONDS
    message = str(caught.value)
    assert caught.value.status_code == 413
    assert "the PCD file's LZF data, 3,000,000 points (34 MB unpacked)" in message
    assert message.startswith("The upload of 400 KB expands too far")


def test_an_lzf_pcd_within_its_budget_is_read() -> None:
    cloud = read_points(lzf_bomb_pcd(100_000, 4, "F"), "small.pcd")
    assert len(cloud.points) == 100_000 and not cloud.points.any()


def test_the_budget_is_shared_with_the_caller() -> None:
    """Inside an outer budget (a server's), the PCD is charged to it, not to a fresh one."""
    data = lzf_bomb_pcd(100_000, 4, "F")
    outer = expansion.expanding(len(data), most=10 * 2**20)
    with outer as budget, pytest.raises(ExpansionTooLarge, match="more than the 10 MB"):
        read_points(data, "small.pcd")
    assert budget.used == 0


def test_lzf_never_writes_past_the_size_it_is_given() -> None:
    """A lying size: the data go on after it; the output buffer is never overrun."""
    packed = zeros_lzf(10_000)
    with pytest.raises(MeshFileError, match="unpack to more than the 5,000 bytes"):
        lzf_decompress(packed, 5_000)
    with pytest.raises(MeshFileError, match="unpack to more than the 1 bytes"):
        lzf_decompress(bytes([1, 7, 7]), 1)  # a literal run of 2 into 1 byte


def test_a_laz_of_many_points_is_refused_before_decompressing() -> None:
    data = laz_bomb(1_500_000)
    assert len(data) < 20_000
    with pytest.raises(ExpansionTooLarge, match=r"the LAZ file's 1,500,000 compressed points"):
        read_points(data, "bomb.laz")


def test_a_laz_within_its_budget_is_read() -> None:
    cloud = read_points(laz_bomb(10_000), "small.laz")
    assert len(cloud.points) == 10_000


# --- LAS headers --------------------------------------------------------------------------


def test_fewer_points_than_the_header_says_are_refused() -> None:
    with pytest.raises(MeshFileError, match=r"^The LAS header says 1,000 points, but the file "):
        read_points(las_count(las_points(), 1000))


def test_more_points_than_the_header_says_are_read_as_it_says_with_a_note() -> None:
    cloud = read_points(las_count(las_points(1000), 10))
    assert len(cloud.points) == 10
    assert cloud.notes == (
        "The LAS header says 10 points, but its point data have room for 1,000; the 10 the "
        "header says were read, and the rest left out.",
    )
    assert read_points(las_points(1000)).notes == ()


@pytest.mark.parametrize(
    ("scale", "offset", "sentence"),
    [
        (0.0, 0.0, "The LAS file's x scale is 0; every point would sit at its offset."),
        (float("nan"), 0.0, "The LAS file's x scale is nan, not a finite number."),
        (float("inf"), 0.0, "The LAS file's x scale is inf, not a finite number."),
        (0.01, float("-inf"), "The LAS file's x offset is -inf, not a finite number."),
    ],
)
@pytest.mark.parametrize("compress", [False, True])
def test_a_degenerate_scale_or_offset_is_refused(
    scale: float, offset: float, sentence: str, compress: bool
) -> None:
    with pytest.raises(MeshFileError) as caught:
        read_points(las_points(scale=scale, offset=offset, compress=compress))
    assert str(caught.value) == sentence and caught.value.status_code == 400


# --- coincident points --------------------------------------------------------------------


def test_coincident_groups() -> None:
    points = np.array([[1.0, 2, 3], [0, 0, 0], [1, 2, 3], [-0.0, 0, 0], [1, 2, 4]])
    first, group = coincident_groups(points)
    assert list(first) == [0, 1, 4] and list(group) == [0, 1, 0, 1, 2]
    distinct = np.random.default_rng(0).random((50, 3))
    first, group = coincident_groups(distinct)
    assert list(first) == list(range(50)) and list(group) == list(range(50))


def test_coincident_groups_are_exact_whatever_the_hash() -> None:
    """Rows differing in one bit, in every column, many times over: never merged."""
    base = np.random.default_rng(1).random((1000, 3))
    nudged = [base] + [np.nextafter(base, 2.0 * (axis + 1)) for axis in range(3)]
    points = np.concatenate(nudged * 3)
    first, group = coincident_groups(points)
    assert len(first) == len(np.unique(points, axis=0))
    np.testing.assert_array_equal(points[first][group], points)


def test_200_000_identical_points_are_answered_in_seconds() -> None:
    """No normal can be estimated: every point is ``duplicates``, with a zero normal."""
    began = time.monotonic()
    cloud = read_points(coincident_xyz(200_000), "same.xyz")
    report = analyse_points(cloud).report
    assert time.monotonic() - began < SECONDS
    assert report.counts.duplicates == 200_000 and report.with_normal == 0
    assert report.spacing is not None and report.spacing.coincident == 200_000
    assert report.spacing.max == 0.0
    assert report.diagnosis[0] == (
        "200,000 points sit exactly where another point is (duplicates); each gets the normal "
        "of its place, estimated once."
    )


def test_repeated_points_get_the_normals_of_their_places() -> None:
    """100,000 sphere points, each 20 times, shuffled: as the 100,000 alone, in seconds."""
    points, truth = clouds.sphere(100_000)
    order = np.random.default_rng(2).permutation(2_000_000)
    repeated = np.repeat(points, 20, axis=0)[order]
    began = time.monotonic()
    result = point_normals(repeated)
    assert time.monotonic() - began < 3 * SECONDS
    alone = point_normals(points)
    np.testing.assert_array_equal(result.normals, np.repeat(alone.normals, 20, axis=0)[order])
    np.testing.assert_array_equal(result.status, np.repeat(alone.status, 20, axis=0)[order])
    assert [part.points for part in result.components] == [2_000_000]
    assert result.flipped == 20 * alone.flipped
    assert clouds.rmse(clouds.angles(alone.normals, truth)) < 1.0


def test_a_mix_of_piles_and_a_surface() -> None:
    """A pile of 100,000 at the centre, a sphere, and a few of its points 50 times over."""
    points, truth = clouds.sphere(20_000)
    mixed = np.r_[np.zeros((100_000, 3)), points, np.repeat(points[:500], 50, axis=0)]
    began = time.monotonic()
    result = point_normals(mixed, k=30)
    assert time.monotonic() - began < SECONDS
    sphere = result.normals[100_000:120_000]
    assert clouds.rmse(clouds.angles(sphere, truth)) < 1.0
    np.testing.assert_array_equal(result.normals[120_000:], np.repeat(sphere[:500], 50, axis=0))
    pile = result.normals[:100_000]
    assert np.all(pile == pile[0]) and result.neighbours[0] == 30


@pytest.mark.parametrize(
    ("copies", "status"),
    [(1, PointStatus.too_few_neighbours), (2, PointStatus.too_few_neighbours)],
)
def test_a_point_alone_in_its_radius(copies: int, status: PointStatus) -> None:
    """One or two points at a place with nothing else near: too few, as before."""
    points, _ = clouds.sphere(2_000)
    far = np.r_[points, np.tile([[9.0, 9, 9]], (copies, 1))]
    result = point_normals(far, k=None, radius=0.2)
    assert np.all(result.status[2_000:] == status)


def test_piles_alone_in_their_radius_are_duplicates_or_collinear() -> None:
    """Three copies alone: their points coincide; two places of copies: a line."""
    points, _ = clouds.sphere(2_000)
    pile = np.tile([[9.0, 9, 9]], (3, 1))
    pair = np.r_[np.tile([[-9.0, 9, 9]], (5, 1)), [[-9.0, 9, 9.05]]]
    result = point_normals(np.r_[points, pile, pair], k=None, radius=0.2)
    assert np.all(result.status[2_000:2_003] == PointStatus.duplicates)
    assert np.all(result.status[2_003:] == PointStatus.collinear)
    assert not result.normals[2_000:].any() and not result.curvature[2_000:].any()


def test_orientation_towards_a_reference_counts_every_copy() -> None:
    points, _ = clouds.sphere(5_000)
    doubled = np.r_[points, points]
    result = point_normals(doubled, orient="viewpoint", viewpoint=(0, 0, 0))
    assert [part.points for part in result.components] == [10_000]
    assert (
        result.flipped == 2 * point_normals(points, orient="viewpoint", viewpoint=(0, 0, 0)).flipped
    )


def test_duplicates_in_a_report_count_once_each() -> None:
    """Counts add up over the file's points, copies included."""
    points, _ = clouds.sphere(3_000)
    report = analyse_points(make_cloud("xyz", np.r_[points, points[:100]])).report
    assert report.points == 3_100 and report.with_normal == 3_100
    assert sum(part.points for part in report.orientation.parts) == 3_100
    assert report.spacing is not None and report.spacing.coincident == 200
    assert report.spacing.min == 0.0 and report.spacing.median > 0


# --- the stored files ---------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(HOSTILE_POINTS))
def test_the_stored_hostile_files(name: str) -> None:
    _, status, words = HOSTILE_POINTS[name]
    data = (HOSTILE / name).read_bytes()
    assert len(data) < 100_000
    began = time.monotonic()
    if status == 200:
        cloud = read_points(data, name)
        said = " ".join([*cloud.notes, *analyse_points(cloud).report.diagnosis])
    else:
        with pytest.raises(MeshFileError) as caught:
            read_points(data, name)
        assert caught.value.status_code == status
        said = str(caught.value)
    assert words in said
    assert time.monotonic() - began < SECONDS
