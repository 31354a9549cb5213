"""The compiled k-d tree (cpp/nearest.cpp): each point's k nearest against scipy's cKDTree and a
brute-force reference, ties by index, the same bits on any number of threads, and what it
refuses."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from mesh_normal import _core

RNG = np.random.default_rng(5)
PROPERTY = settings(max_examples=40, deadline=None)


def nearest(points: np.ndarray, k: int, start: int = 0, stop: int | None = None) -> np.ndarray:
    stop = len(points) if stop is None else stop
    out = np.full((stop - start, k), -1, dtype=np.intp)
    _core.PointTree(points).nearest(start, stop, k, out)
    return out


def squared(points: np.ndarray, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """Squared distances as the tree computes them: dx * dx + dy * dy + dz * dz, in that order."""
    d = points[columns] - points[rows]
    return d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1] + d[..., 2] * d[..., 2]


def brute_force(points: np.ndarray, k: int) -> np.ndarray:
    """Each row's k nearest by (distance, index)."""
    m = len(points)
    everyone = np.broadcast_to(np.arange(m), (m, m))
    with np.errstate(over="ignore"):
        distances = squared(points, np.arange(m)[:, None], everyone)
    return np.array([np.lexsort((everyone[i], distances[i]))[:k] for i in range(m)])


def assert_matches_ckdtree(points: np.ndarray, k: int) -> None:
    m = len(points)
    ours = nearest(points, k)
    distances, theirs = cKDTree(points).query(points, k=k)
    theirs = theirs.reshape(m, k)
    expected = distances.reshape(m, k) ** 2
    found = squared(points, np.arange(m)[:, None], ours)
    np.testing.assert_allclose(found, expected, rtol=1e-12, atol=0)
    assert (ours[:, 0] == np.arange(m)).all()  # distinct points: each its own nearest
    # Nearest first, equal distances by the smaller index.
    steps = np.diff(found, axis=1)
    assert (steps >= 0).all()
    assert (np.diff(ours, axis=1)[steps == 0] > 0).all()
    # Where the k-th nearest is strictly nearer than the next, the set is determined.
    if k < m:
        beyond = cKDTree(points).query(points, k=k + 1)[0].reshape(m, k + 1)
        clear = beyond[:, k - 1] < beyond[:, k]
    else:
        clear = np.ones(m, dtype=bool)
    assert clear.mean() > 0.5
    np.testing.assert_array_equal(np.sort(ours[clear], axis=1), np.sort(theirs[clear], axis=1))


def uniform(m: int) -> np.ndarray:
    return RNG.uniform(-1.0, 1.0, size=(m, 3))


def sphere(m: int) -> np.ndarray:
    directions = RNG.normal(size=(m, 3))
    return directions / np.linalg.norm(directions, axis=1, keepdims=True)


def clusters_and_outliers(m: int) -> np.ndarray:
    centres = RNG.uniform(-1.0, 1.0, size=(5, 3))
    points = centres[RNG.integers(0, 5, size=m)] + RNG.normal(scale=1e-3, size=(m, 3))
    points[:8] = RNG.uniform(-1.0, 1.0, size=(8, 3)) * 1e6  # far away from everything
    return points


@pytest.mark.parametrize("cloud", [uniform, sphere, clusters_and_outliers])
@pytest.mark.parametrize("k", [1, 12, 96])
def test_the_nearest_are_ckdtrees(cloud: object, k: int) -> None:
    assert callable(cloud)
    assert_matches_ckdtree(cloud(3000), k)


@pytest.mark.parametrize("m", [1, 2, 3, 5, 17, 40])
def test_tiny_clouds_up_to_every_point(m: int) -> None:
    points = uniform(m)
    for k in sorted({1, (m + 1) // 2, m}):
        assert_matches_ckdtree(points, k)
        np.testing.assert_array_equal(nearest(points, k), brute_force(points, k))


@PROPERTY
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 120),
    st.integers(1, 40),
    st.sampled_from([1, 2, 4]),
)
def test_ties_go_to_the_smaller_index(seed: int, m: int, k: int, side: int) -> None:
    """Points on a small grid, repeats included: many equal distances, broken by index."""
    rng = np.random.default_rng(seed)
    points = rng.integers(-side, side + 1, size=(m, 3)).astype(np.float64) * 0.25
    k = min(k, m)
    np.testing.assert_array_equal(nearest(points, k), brute_force(points, k))


@PROPERTY
@given(st.integers(0, 2**32 - 1), st.integers(1, 300), st.integers(1, 64))
def test_any_cloud_matches_brute_force(seed: int, m: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(m, 3)) * rng.uniform(1e-3, 1e3, size=3)
    k = min(k, m)
    np.testing.assert_array_equal(nearest(points, k), brute_force(points, k))


def test_a_slice_of_rows_is_those_rows_of_the_whole() -> None:
    points = sphere(2000)
    whole = nearest(points, 30)
    for start, stop in [(0, 0), (0, 1), (700, 1300), (1999, 2000), (0, 2000)]:
        np.testing.assert_array_equal(nearest(points, 30, start, stop), whole[start:stop])


def test_the_same_bits_on_any_number_of_threads() -> None:
    points = clusters_and_outliers(20_000)
    before = _core.threads()
    try:
        found = []
        for threads in (1, 2, 3, 8):
            _core.set_threads(threads)
            found.append(nearest(points, 40))
    finally:
        _core.set_threads(before)
    for other in found[1:]:
        np.testing.assert_array_equal(other, found[0])


def test_the_tree_keeps_its_own_copy() -> None:
    points = uniform(500)
    tree = _core.PointTree(points)
    expected = nearest(points, 8)
    points[:] = 0.0
    out = np.empty((500, 8), dtype=np.intp)
    tree.nearest(0, 500, 8, out)
    np.testing.assert_array_equal(out, expected)
    assert len(tree) == 500


def test_huge_coordinates_overflow_to_ties() -> None:
    points = RNG.uniform(-1.0, 1.0, size=(50, 3)) * 1e300  # squared distances overflow
    np.testing.assert_array_equal(nearest(points, 50), brute_force(points, 50))


def test_a_pile_of_one_point() -> None:
    points = np.zeros((100, 3))
    np.testing.assert_array_equal(nearest(points, 7), np.tile(np.arange(7), (100, 1)))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_points_are_refused(bad: float) -> None:
    points = uniform(10)
    points[4, 1] = bad
    with pytest.raises(ValueError, match=r"^the points of a PointTree must be finite$"):
        _core.PointTree(points)


@pytest.mark.parametrize(
    "points",
    [
        np.zeros((10, 3), dtype=np.float32),
        np.zeros((10, 2)),
        np.zeros(30),
        np.zeros((3, 10)).T,  # not C-contiguous
    ],
)
def test_points_of_the_wrong_kind_are_a_type_error(points: np.ndarray) -> None:
    with pytest.raises(TypeError):
        _core.PointTree(points)


@pytest.mark.parametrize(
    ("start", "stop", "k", "message"),
    [
        (-1, 5, 3, "the query rows"),
        (0, 11, 3, "the query rows"),
        (6, 5, 3, "the query rows"),
        (0, 5, 0, "k must be"),
        (0, 5, 11, "k must be"),
    ],
)
def test_bad_rows_and_counts_are_refused(start: int, stop: int, k: int, message: str) -> None:
    tree = _core.PointTree(uniform(10))
    out = np.empty((max(0, stop - start), max(k, 1)), dtype=np.intp)
    with pytest.raises(ValueError, match=f"^{message}"):
        tree.nearest(start, stop, k, out)


@pytest.mark.parametrize("shape", [(4, 3), (5, 2), (5, 4)])
def test_an_output_of_the_wrong_shape_is_refused(shape: tuple[int, int]) -> None:
    tree = _core.PointTree(uniform(10))
    with pytest.raises(ValueError, match=r"^out needs one row per query row and k columns$"):
        tree.nearest(0, 5, 3, np.empty(shape, dtype=np.intp))


@pytest.mark.parametrize(
    "out",
    [
        np.empty((5, 3), dtype=np.int32),
        np.empty((5, 3)),
        np.empty((3, 5), dtype=np.intp).T,
        np.empty(15, dtype=np.intp),
    ],
)
def test_an_output_of_the_wrong_kind_is_a_type_error(out: np.ndarray) -> None:
    tree = _core.PointTree(uniform(10))
    with pytest.raises(TypeError):
        tree.nearest(0, 5, 3, out)


def test_a_read_only_output_is_a_type_error() -> None:
    out = np.empty((5, 3), dtype=np.intp)
    out.flags.writeable = False
    with pytest.raises(TypeError):
        _core.PointTree(uniform(10)).nearest(0, 5, 3, out)
