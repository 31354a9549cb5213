"""Tests for mesh_normal.triangle.batch: vectorised float64 normals with an exact fallback."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from mesh_normal import BatchNormals, TriangleNormal, triangle_normal, triangle_normals

#: The documented worst case for a row kept in float64: its unit normal points within
#: about sqrt(3) / 2**26 radians of the exact one (module docstring of mesh_normal.triangle.batch).
DOCUMENTED_ANGLE = 3e-8
#: What ordinary triangles (no near-cancellation) should achieve.
GENERAL = 1e-12

SLIVER = [[0.0, 0.0, 0.0], [1 + 2**-52, 1.0, 0.0], [1.0, 1 - 2**-53, 0.0]]
TINY_ROW = [[0.0, 0.0, 0.0], [1e-200, 0.0, 0.0], [0.0, 1e-200, 0.0]]
HUGE_ROW = [[0.0, 0.0, 0.0], [1e200, 0.0, 0.0], [0.0, 1e200, 0.0]]
HUGE_EDGES = [[1e308, -1e308, 0.0], [-1e308, 1e308, 0.0], [1e308, 1e308, 1e308]]
UNIT_RIGHT = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


def as_array(value: float | None) -> float:
    return 0.0 if value is None else value


def assert_all_finite(r: BatchNormals) -> None:
    for array in (r.normal, r.magnitude, r.unit_normal, r.area):
        assert array.dtype == np.float64
        assert np.isfinite(array).all()


def assert_shapes(r: BatchNormals, count: int) -> None:
    assert len(r) == count
    assert r.normal.shape == r.unit_normal.shape == (count, 3)
    assert r.magnitude.shape == r.area.shape == (count,)
    for mask in (r.degenerate, r.out_of_range, r.exact):
        assert mask.shape == (count,)
        assert mask.dtype == np.bool_


def compare_with_exact(
    triangles: np.ndarray, *, swap: bool = False, tolerance: float = GENERAL
) -> tuple[BatchNormals, list[TriangleNormal]]:
    """Check every row of the batch against the exact single-triangle path."""
    array = np.asarray(triangles, dtype=np.float64)
    before = array.copy()
    r = triangle_normals(array, swap_winding=swap)
    assert np.array_equal(array, before)  # the input is not modified
    assert_shapes(r, len(array))
    assert_all_finite(r)
    exact_results = []
    for i, row in enumerate(array.tolist()):
        e = triangle_normal(*row, swap_winding=swap)
        exact_results.append(e)
        assert bool(r.degenerate[i]) == e.degenerate, i
        missing = None in (*e.normal, e.magnitude, e.area)
        assert bool(r.out_of_range[i]) == missing, i
        if e.degenerate:
            assert r.exact[i], i
            assert (r.unit_normal[i] == 0).all() and (r.normal[i] == 0).all()
            assert r.magnitude[i] == r.area[i] == 0.0
            continue
        assert e.unit_normal is not None
        if r.exact[i]:
            assert r.normal[i].tolist() == [as_array(x) for x in e.normal], i
            assert r.magnitude[i] == as_array(e.magnitude), i
            assert r.area[i] == as_array(e.area), i
            assert r.unit_normal[i].tolist() == list(e.unit_normal), i
            continue
        # A row kept in float64: everything in range, close to the exact values.
        assert not missing, i
        assert e.magnitude is not None and e.area is not None
        unit_error = float(np.abs(r.unit_normal[i] - e.unit_normal).max())
        assert unit_error <= tolerance, (i, unit_error)
        assert abs(r.magnitude[i] - e.magnitude) <= tolerance * e.magnitude, i
        assert abs(r.area[i] - e.area) <= tolerance * e.area, i
        normal_error = float(np.abs(r.normal[i] - np.array(e.normal, dtype=float)).max())
        assert normal_error <= tolerance * e.magnitude, (i, normal_error)
        assert r.magnitude[i] == 2 * r.area[i] or r.area[i] < np.finfo(float).tiny
    return r, exact_results


# --- agreement with the exact path ------------------------------------------------------


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize(
    "scale", [1.0, 1e-3, 1e3, 1e-150, 1e150, 2.0**-1000, 2.0**1000], ids=lambda s: f"{s:g}"
)
def test_random_triangles_agree_with_the_exact_path(scale: float, swap: bool) -> None:
    rng = np.random.default_rng(12345)
    triangles = rng.uniform(-1.0, 1.0, size=(400, 3, 3)) * scale
    r, _ = compare_with_exact(triangles, swap=swap)
    assert not r.degenerate.any()


def test_random_triangles_with_offsets_and_log_scales() -> None:
    rng = np.random.default_rng(99)
    count = 500
    scales = 10.0 ** rng.uniform(-100, 100, size=(count, 1, 1))
    offsets = rng.uniform(-10, 10, size=(count, 1, 3)) * scales
    triangles = offsets + rng.normal(size=(count, 3, 3)) * scales
    r, _ = compare_with_exact(triangles)
    # Ordinary triangles stay on the fast float64 path.
    assert (~r.exact).sum() >= count * 0.95


def test_random_integer_triangles() -> None:
    rng = np.random.default_rng(5)
    triangles = rng.integers(-5, 6, size=(600, 3, 3)).astype(np.float64)
    r, exact = compare_with_exact(triangles)
    assert r.degenerate.any() and not r.degenerate.all()  # small grids do have flat ones
    for i, e in enumerate(exact):
        if not e.degenerate and not r.exact[i]:
            # Integer normals of this size are computed exactly even in float64.
            assert r.normal[i].tolist() == list(e.normal)


finite = st.floats(allow_nan=False, allow_infinity=False)
wide_triangles = hnp.arrays(
    np.float64,
    st.tuples(st.integers(0, 12), st.just(3), st.just(3)),
    elements=st.one_of(finite, st.floats(-10, 10), st.integers(-3, 3).map(float)),
)


@given(wide_triangles, st.booleans())
@settings(max_examples=200, deadline=None)
def test_any_doubles_agree_with_the_exact_path_within_the_documented_bound(
    triangles: np.ndarray, swap: bool
) -> None:
    compare_with_exact(triangles, swap=swap, tolerance=DOCUMENTED_ANGLE)


# --- slivers and flat triangles ---------------------------------------------------------


def sliver_batch(seed: int, count: int) -> np.ndarray:
    """Triangles whose (y, z) projections are collinear up to 1e-20 .. 1e-8."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(-1, 1, size=(count, 3))
    slope = rng.uniform(-2, 2, size=count)
    t, w = rng.uniform(-1, 1, size=count), rng.uniform(-1, 1, size=count)
    e1, e2 = (
        rng.uniform(-1, 1, size=count) * 10 ** rng.uniform(-20, -8, size=count) for _ in range(2)
    )
    b = a + np.stack([rng.uniform(-1, 1, size=count), t, slope * t + e1], axis=1)
    c = a + np.stack([rng.uniform(-1, 1, size=count), w, slope * w + e2], axis=1)
    return np.stack([a, b, c], axis=1)


def full_sliver_batch(seed: int, count: int) -> np.ndarray:
    """Triangles that are nearly collinear in 3D: C = A + t (B - A) + tiny."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(-1e3, 1e3, size=(count, 3))
    b = a + rng.uniform(-10, 10, size=(count, 3))
    t = rng.uniform(-3, 3, size=(count, 1))
    tiny = rng.uniform(-1, 1, size=(count, 3)) * 10 ** rng.uniform(-30, -6, size=(count, 1))
    c = a + t * (b - a) + tiny
    return np.stack([a, b, c], axis=1)


@pytest.mark.parametrize("swap", [False, True])
def test_near_degenerate_slivers(swap: bool) -> None:
    triangles = np.concatenate([sliver_batch(1, 400), full_sliver_batch(2, 400), [SLIVER]])
    r, _ = compare_with_exact(triangles, swap=swap, tolerance=DOCUMENTED_ANGLE)
    assert r.exact.any()  # some slivers are too thin for float64 and go the exact way
    assert r.exact[-1] and not r.degenerate[-1]
    assert r.unit_normal[-1].tolist() == [0.0, 0.0, -1.0 if swap else 1.0]


def test_exactly_collinear_integer_triangles() -> None:
    rng = np.random.default_rng(3)
    count = 300
    a = rng.integers(-(2**20), 2**20, size=(count, 1, 3))
    d = rng.integers(-(2**10), 2**10, size=(count, 1, 3))
    steps = rng.integers(-100, 100, size=(count, 3, 1))
    steps[:, 0] = 0
    triangles = (a + steps * d).astype(np.float64)
    for swap in (False, True):
        r, exact = compare_with_exact(triangles, swap=swap)
        assert r.degenerate.all() and r.exact.all()
        assert not r.unit_normal.any() and not r.normal.any()
        assert not r.magnitude.any() and not r.area.any()
        assert all(e.degenerate for e in exact)


def test_exactly_collinear_points_that_naive_floats_call_a_triangle() -> None:
    # Points on y = 3x whose float cross product is nonzero (see test_triangle.py).
    xs = [
        float.fromhex(h)
        for h in ("0x1.8a7dd82c07cd0p-45", "0x1.09210a5d2f350p-57", "0x1.9ea77c65c1e50p-30")
    ]
    r, _ = compare_with_exact(np.array([[[x, 3 * x, 0.0] for x in xs]]))
    assert r.degenerate[0] and r.exact[0]


# --- exactness cases and extreme scales as batch rows -----------------------------------


def test_exactness_cases_as_rows() -> None:
    triangles = np.array([UNIT_RIGHT, SLIVER, TINY_ROW, HUGE_ROW, HUGE_EDGES])
    r, exact = compare_with_exact(triangles)
    assert r.exact.tolist() == [False, True, True, True, True]
    assert r.out_of_range.tolist() == [False, False, True, True, True]
    assert not r.degenerate.any()
    assert r.unit_normal[:4].tolist() == [[0.0, 0.0, 1.0]] * 4
    assert r.normal[1].tolist() == [0.0, 0.0, 2**-53 - 2**-105]
    assert r.magnitude[1] == 2**-53 - 2**-105 and r.area[1] == (2**-53 - 2**-105) / 2
    # Out-of-range values hold 0.0, never inf or a subnormal stand-in.
    for row in (2, 3):
        assert r.normal[row].tolist() == [0.0, 0.0, 0.0]
        assert r.magnitude[row] == r.area[row] == 0.0
    assert exact[4].unit_normal is not None
    assert r.unit_normal[4].tolist() == list(exact[4].unit_normal)
    assert r.unit_normal[4][0] == r.unit_normal[4][1] > 0 > r.unit_normal[4][2]


def test_mixed_scale_rows_in_one_batch() -> None:
    rows = [
        [[0, 0, 0], [1e-300, 0, 0], [0, 1e-300, 0]],  # n underflows
        [[0, 0, 0], [1e300, 0, 0], [0, 1e300, 0]],  # n overflows
        [[1e300, 0, 0], [0, 1e-300, 0], [0, 0, 1e-300]],  # both in one triangle
        [[0, 0, 0], [1e-160, 0, 0], [0, 1e-160, 0]],  # n = 1e-320: subnormal, still a double
        [[0, 0, 0], [1e-150, 0, 0], [0, 1e-150, 0]],  # n = 1e-300, normal range
        [[0, 0, 0], [1e150, 0, 0], [0, 1e150, 0]],  # n = 1e300
        [[-1e308, 0, 0], [1e308, 0, 0], [0, 1e-300, 0]],  # u_x overflows, n does not
        [[-1e308, 0, 0], [1e308, 0, 0], [0, 1, 0]],  # magnitude overflows, area does not
        UNIT_RIGHT,
        [[1e-310, 0, 0], [0, 1e-310, 0], [0, 0, 1e-310]],  # subnormal coordinates
    ]
    r, exact = compare_with_exact(np.array(rows, dtype=float))
    assert r.out_of_range.tolist() == [
        True,
        True,
        True,
        False,
        False,
        False,
        False,
        True,
        False,
        True,
    ]
    assert r.exact[3] and r.normal[3, 2] == exact[3].normal[2] == 1e-320
    assert r.unit_normal[0].tolist() == r.unit_normal[1].tolist() == [0.0, 0.0, 1.0]
    assert r.normal[4, 2] == exact[4].normal[2] and r.normal[5, 2] == exact[5].normal[2]
    assert r.normal[6].tolist() == [0.0, 0.0, 2e8]
    assert exact[6].u[0] is None  # the batch does not report edges, only n and below
    assert r.magnitude[7] == 0.0 and r.area[7] == 1e308
    expected = 1 / math.sqrt(3)
    assert np.allclose(r.unit_normal[9], expected, rtol=1e-15, atol=0)
    assert r.exact[9]  # products of subnormal coordinates are not trusted in float64
    assert not r.degenerate.any()


def test_scaled_copies_share_one_direction() -> None:
    base = np.random.default_rng(8).uniform(-1, 1, size=(50, 3, 3))
    scales = [2.0**k for k in (-1070, -600, -300, 0, 300, 600, 1000)]
    batch = np.concatenate([base * s for s in scales])
    r, _ = compare_with_exact(batch)
    units = r.unit_normal.reshape(len(scales), 50, 3)
    # Power-of-two scaling is exact and the float path scales it away first.
    kept = ~r.exact.reshape(len(scales), 50)
    for k in range(len(scales)):
        both = kept[k] & kept[3]
        assert np.array_equal(units[k][both], units[3][both])


# --- winding ----------------------------------------------------------------------------


def test_swap_winding_negates_every_row() -> None:
    triangles = np.concatenate(
        [
            np.random.default_rng(4).uniform(-1, 1, size=(200, 3, 3)),
            sliver_batch(5, 100),
            [UNIT_RIGHT, SLIVER, TINY_ROW, HUGE_ROW, HUGE_EDGES, [[1, 1, 1]] * 3],
        ]
    )
    r, _ = compare_with_exact(triangles)
    s, _ = compare_with_exact(triangles, swap=True)
    assert np.array_equal(s.normal, -r.normal)
    assert np.array_equal(s.unit_normal, -r.unit_normal)
    assert np.array_equal(s.magnitude, r.magnitude)
    assert np.array_equal(s.area, r.area)
    for mask in ("degenerate", "out_of_range", "exact"):
        assert np.array_equal(getattr(s, mask), getattr(r, mask)), mask


# --- input handling ---------------------------------------------------------------------


def test_empty_input() -> None:
    r = triangle_normals(np.empty((0, 3, 3)))
    assert_shapes(r, 0)
    assert r.normal.dtype == r.magnitude.dtype == np.float64
    r = triangle_normals(np.empty((0, 3, 3)), swap_winding=True)
    assert len(r) == 0


def test_nested_lists_and_integers_are_accepted() -> None:
    r = triangle_normals([[[1, 2, 3], [4, 6, 3], [1, 2, 8]]])
    assert r.normal.tolist() == [[20.0, -15.0, 0.0]]
    assert r.magnitude.tolist() == [25.0] and r.area.tolist() == [12.5]
    assert r.unit_normal.tolist() == [[0.8, -0.6, 0.0]]
    assert r.degenerate.tolist() == r.out_of_range.tolist() == [False]


@pytest.mark.parametrize(
    "shape", [(3, 3), (0,), (1, 3), (1, 3, 2), (1, 2, 3), (2, 3, 4), (1, 3, 3, 1), ()]
)
def test_wrong_shape_raises_value_error(shape: tuple[int, ...]) -> None:
    with pytest.raises(ValueError, match=r"shape \(n, 3, 3\)"):
        triangle_normals(np.zeros(shape))


def test_ragged_input_raises_value_error() -> None:
    with pytest.raises(ValueError, match="shape"):
        triangle_normals([[[0, 0, 0], [1, 0, 0], [0, 1]]])


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_input_raises_value_error_naming_the_row(bad: float) -> None:
    triangles = np.random.default_rng(0).uniform(-1, 1, size=(5, 3, 3))
    triangles[3, 2, 1] = bad
    with pytest.raises(ValueError, match=r"triangles\[3\] has a coordinate that is not a finite"):
        triangle_normals(triangles)
    with pytest.raises(ValueError, match=r"triangles\[3\]"):
        triangle_normals(triangles, swap_winding=True)


# --- found problems ---------------------------------------------------------------------

#: A row whose tiny x component float64 gets with the wrong sign. Exact: n_x = -1.78e-17;
#: float64 gives +1.1e-16 (rounding in u and v): the component is below its error bound, so
#: the batch must hand the row to the exact path.
SIGN_FLIP = [
    [-0.06639807266134024, -0.03412108803529845, -0.8363174473966897],
    [0.6328461840557804, 0.7784402355013502, -0.010298543686718854],
    [-0.688820252195693, 0.8740184098439048, 0.08686258926680712],
]


def test_sign_flip_row_goes_to_the_exact_path() -> None:
    r, exact = compare_with_exact(np.array([SIGN_FLIP]), tolerance=DOCUMENTED_ANGLE)
    assert r.exact[0]
    assert exact[0].unit_normal is not None and exact[0].unit_normal[0] < 0


def test_every_sign_matches_the_exact_path() -> None:
    r = triangle_normals(np.array([SIGN_FLIP]))
    e = triangle_normal(*SIGN_FLIP)
    assert e.unit_normal is not None
    assert np.array_equal(np.sign(r.unit_normal[0]), np.sign(e.unit_normal))
    assert np.array_equal(np.sign(r.normal[0]), np.sign(np.array(e.normal, dtype=float)))


def test_zero_components_have_the_exact_paths_sign() -> None:
    row = [[0.0, 0.0, 0.0], [1.0, -1.0, 0.0], [0.0, 5.0, 0.0]]
    r = triangle_normals(np.array([row]))
    e = triangle_normal(*row)
    assert e.normal == (0.0, 0.0, 5.0)
    assert np.signbit(r.normal[0]).tolist() == [math.copysign(1, x) < 0 for x in e.normal]
