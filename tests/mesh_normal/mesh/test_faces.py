"""Tests for mesh_normal.mesh.faces: face normals and areas, degenerate faces, precision."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.mesh.checks import checked_mesh
from mesh_normal.mesh.corners import CornerNormals, corner_normals
from mesh_normal.mesh.faces import FaceNormals, face_areas, face_normals, run_face_kernel
from mesh_normal.mesh.vertices import WEIGHTINGS, VertexNormals, vertex_normals
from mesh_normal.tolerances import MESH_DEGENERATE_SINE
from tests.mesh_normal._normals import assert_clean, assert_unit_or_zero, unit
from tests.meshes import SAMPLES, TETRA_FACES, TETRA_VERTICES, load

# --- face normals and areas -------------------------------------------------------------------


def test_tetrahedron_face_normals_and_areas() -> None:
    r = face_normals(TETRA_VERTICES, TETRA_FACES)
    assert isinstance(r, FaceNormals) and len(r) == 4
    expected = [[0, 0, -1], [0, -1, 0], [-1, 0, 0], unit(1, 1, 1)]
    assert np.allclose(r.normals, expected, atol=1e-16, rtol=0)
    assert np.allclose(r.areas, [0.5, 0.5, 0.5, math.sqrt(3) / 2], rtol=1e-15)
    assert not r.degenerate.any()
    assert np.array_equal(face_areas(TETRA_VERTICES, TETRA_FACES), r.areas)
    assert r.normals.flags.c_contiguous and r.normals.shape == (4, 3)


def test_cube_face_normals_point_out_of_their_side() -> None:
    vertices, faces = load("cube.obj")
    r = face_normals(vertices, faces)
    # Each triangle lies on one side of the unit cube around the origin; twice its centroid
    # rounds to that side's outward axis.
    outward = np.round(2 * vertices[faces].mean(axis=1))
    assert np.array_equal(r.normals, outward)
    assert np.array_equal(r.areas, np.full(12, 0.5))
    assert not np.signbit(r.normals[r.normals == 0]).any()  # no -0.0


def test_one_flipped_face_negates_only_that_normal() -> None:
    vertices, faces = load("cube.obj")
    flipped = faces.copy()
    flipped[5] = flipped[5, ::-1]
    before, after = face_normals(vertices, faces), face_normals(vertices, flipped)
    assert np.array_equal(after.normals[5], -before.normals[5])
    others = np.arange(12) != 5
    assert np.array_equal(after.normals[others], before.normals[others])
    smooth, bent = vertex_normals(vertices, faces), vertex_normals(vertices, flipped)
    changed = np.flatnonzero(~np.all(smooth.normals == bent.normals, axis=1))
    assert set(changed) <= set(faces[5])


@pytest.mark.parametrize("name", SAMPLES)
def test_swapping_two_corners_negates_every_normal_exactly(name: str) -> None:
    vertices, faces = load(name)
    forward = face_normals(vertices, faces)
    backward = face_normals(vertices, faces[:, [0, 2, 1]])
    assert np.array_equal(backward.normals, -forward.normals)
    assert np.array_equal(backward.areas, forward.areas)


@pytest.mark.parametrize("name", SAMPLES)
@pytest.mark.parametrize("weighting", WEIGHTINGS)
def test_reversing_every_face_negates_every_normal(name: str, weighting: str) -> None:
    vertices, faces = load(name)
    forward, backward = face_normals(vertices, faces), face_normals(vertices, faces[:, ::-1])
    assert np.allclose(backward.normals, -forward.normals, atol=1e-14, rtol=0)
    smooth = vertex_normals(vertices, faces, weighting)
    reverse = vertex_normals(vertices, faces[:, ::-1], weighting)
    assert np.allclose(reverse.normals, -smooth.normals, atol=1e-14, rtol=0)
    assert np.array_equal(reverse.missing, smooth.missing)


# Degenerate faces: 0-4 are degenerate, 5-7 are valid but would fool an absolute tolerance.
SLIVERS = np.array(
    [
        [0.0, 0.0, 0.0],  # 0
        [1.0, 0.0, 0.0],  # 1
        [0.5, 0.0, 0.0],  # 2: on the segment 0-1
        [0.5, 1e-14, 0.0],  # 3: 1e-14 off it (largest angle's sine about 4e-14)
        [0.0, 0.0, 0.0],  # 4: same point as 0, another index
        [0.5, 1e-9, 0.0],  # 5: 1e-9 off the segment: flat, yet a clear normal
        [1.0, 1e-13, 0.0],  # 6: a needle: 1e-13 angle at 0, right angle at 1
        [1e-7, 0.0, 0.0],  # 7
        [0.0, 1e-7, 0.0],  # 8
        [7.0, 7.0, 7.0],  # 9: used only by a degenerate face
        [9.0, 9.0, 9.0],  # 10: unused
    ]
)
SLIVER_FACES = np.array(
    [
        [0, 0, 1],  # repeated index
        [0, 1, 2],  # collinear
        [0, 1, 3],  # numerically collinear
        [4, 1, 0],  # coincident points
        [9, 9, 9],  # one point
        [0, 1, 5],  # flat sliver, above the bound
        [0, 1, 6],  # needle
        [0, 7, 8],  # right triangle with 1e-7 legs
    ]
)
SLIVER_DEGENERATE = [True, True, True, True, True, False, False, False]


def test_degenerate_faces_get_zero_rows_and_the_mask() -> None:
    r = face_normals(SLIVERS, SLIVER_FACES)
    assert r.degenerate.tolist() == SLIVER_DEGENERATE
    assert_clean(r.normals, r.areas)
    assert np.array_equal(r.normals[:5], np.zeros((5, 3)))
    assert np.array_equal(r.areas[:5], np.zeros(5))
    assert np.allclose(r.normals[5:], [[0, 0, 1]] * 3, atol=1e-12, rtol=0)
    assert np.allclose(r.areas[5:], [5e-10, 5e-14, 5e-15], rtol=1e-6)


def test_an_absolute_tolerance_gets_small_valid_faces_wrong() -> None:
    # trimesh calls the needle and the tiny right triangle degenerate (|n| <= 1e-12).
    _, valid = trimesh.triangles.normals(SLIVERS[SLIVER_FACES[5:]])
    assert valid.tolist() == [True, False, False]
    assert not face_normals(SLIVERS, SLIVER_FACES[5:]).degenerate.any()


def test_the_degenerate_bound_is_on_the_sine_of_the_largest_angle() -> None:
    # An isosceles sliver whose apex angle has the sine s, either side of the bound.
    for factor, degenerate in ((0.5, True), (2.0, False)):
        height = 0.5 * math.tan(factor * MESH_DEGENERATE_SINE / 2)  # apex near 180 degrees
        triangle = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, height, 0.0]]
        assert face_normals(triangle, [[0, 1, 2]]).degenerate.tolist() == [degenerate]


@pytest.mark.parametrize("weighting", WEIGHTINGS)
def test_degenerate_faces_never_give_nan_downstream(weighting: str) -> None:
    smooth = vertex_normals(SLIVERS, SLIVER_FACES, weighting)
    assert isinstance(smooth, VertexNormals) and len(smooth) == len(SLIVERS)
    assert_clean(smooth.normals)
    # Vertices 2, 3 and 4 are only in degenerate faces, 9 too; 10 is in none.
    assert smooth.missing.tolist() == [False, False, True, True, True] + [False] * 4 + [True] * 2
    assert np.array_equal(smooth.normals[9:], np.zeros((2, 3)))
    assert_unit_or_zero(smooth.normals, smooth.missing)
    corners = corner_normals(SLIVERS, SLIVER_FACES, 30.0, weighting)
    assert isinstance(corners, CornerNormals) and corners.normals.shape == (8, 3, 3)
    assert_clean(corners.normals)
    assert np.array_equal(corners.missing.any(axis=1), SLIVER_DEGENERATE)
    assert corners.missing[:5].all()
    assert_unit_or_zero(corners.normals, corners.missing)


@pytest.mark.parametrize("factor", [1e-3, 1e3, 2.0**-300, 2.0**300, 1e-200, 1e200])
def test_the_degenerate_verdict_does_not_depend_on_the_unit(factor: float) -> None:
    sphere, sphere_faces = load("sphere.ply")
    vertices = np.concatenate([SLIVERS, sphere])
    faces = np.concatenate([SLIVER_FACES, sphere_faces + len(SLIVERS)])
    base = face_normals(vertices, faces)
    scaled = face_normals(vertices * factor, faces)
    assert np.array_equal(scaled.degenerate, base.degenerate)
    assert np.allclose(scaled.normals, base.normals, atol=1e-12, rtol=0)
    with np.errstate(over="ignore"):  # 1e200: areas beyond the double range are infinite
        assert np.allclose(scaled.areas, base.areas * factor * factor, rtol=1e-12, atol=0)
    if math.frexp(factor)[0] == 0.5:  # a power of two: every step is exact, so the same bits
        assert np.array_equal(scaled.normals, base.normals)
    for weighting in WEIGHTINGS:
        a, b = (
            vertex_normals(vertices, faces, weighting),
            vertex_normals(vertices * factor, faces, weighting),
        )
        assert np.array_equal(a.missing, b.missing)
        assert np.allclose(a.normals, b.normals, atol=1e-12, rtol=0)


def test_areas_beyond_the_double_range_are_infinite_not_nan() -> None:
    huge = face_normals(TETRA_VERTICES * 1e300, TETRA_FACES)
    assert np.isinf(huge.areas).all()
    assert np.allclose(huge.normals, face_normals(TETRA_VERTICES, TETRA_FACES).normals)
    tiny = face_normals(TETRA_VERTICES * 1e-300, TETRA_FACES)
    assert np.array_equal(tiny.areas, np.zeros(4)) and not tiny.degenerate.any()


def random_rotation(quaternion: tuple[float, float, float, float]) -> np.ndarray:
    w, x, y, z = np.array(quaternion) / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


quaternions = st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1)


@settings(max_examples=25, deadline=None)
@given(quaternion=quaternions)
def test_rotating_the_mesh_rotates_its_normals(quaternion: tuple[float, ...]) -> None:
    rotation = random_rotation(quaternion)
    vertices, faces = load("nut.ply")
    turned = vertices @ rotation.T
    assert np.allclose(
        face_normals(turned, faces).normals,
        face_normals(vertices, faces).normals @ rotation.T,
        atol=1e-12,
        rtol=0,
    )
    for weighting in ("area", "angle"):
        assert np.allclose(
            vertex_normals(turned, faces, weighting).normals,
            vertex_normals(vertices, faces, weighting).normals @ rotation.T,
            atol=1e-12,
            rtol=0,
        )


small_meshes = st.integers(1, 12).flatmap(
    lambda n: st.tuples(
        st.lists(st.tuples(*[st.integers(-2, 2)] * 3), min_size=n, max_size=n),
        st.lists(st.tuples(*[st.integers(0, n - 1)] * 3), min_size=0, max_size=16),
        st.sampled_from([1.0, 1e-9, 3e7]),
    )
)


@settings(max_examples=200, deadline=None)
@given(mesh=small_meshes)
def test_small_integer_meshes_match_the_exact_cross_product(mesh: tuple) -> None:
    points, triangles, scale = mesh
    exact = np.array(points, dtype=np.int64)
    faces = np.array(triangles, dtype=np.int64).reshape(-1, 3)
    vertices = exact * scale
    r = face_normals(vertices, faces)
    e = exact[faces]
    cross = np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]).reshape(-1, 3)
    # Integer points in a small box: degenerate exactly when the exact cross product is zero.
    assert r.degenerate.tolist() == (cross == 0).all(axis=1).tolist()
    lengths = np.linalg.norm(cross, axis=1)
    expected = cross / np.where(lengths == 0, 1, lengths)[:, None]
    assert np.allclose(r.normals, expected, atol=1e-15, rtol=0)
    for weighting in WEIGHTINGS:
        smooth = vertex_normals(vertices, faces, weighting)
        assert_clean(smooth.normals)
        assert_unit_or_zero(smooth.normals, smooth.missing)
    corners = corner_normals(vertices, faces, 45.0)
    assert_clean(corners.normals)
    assert_unit_or_zero(corners.normals, corners.missing)


# --- vertex normals -----------------------------------------------------------------------------


def test_large_outputs_on_every_core_hold_the_same_normals() -> None:
    # Many faces, split between the threads: new arrays, given arrays and the geometry's.
    from mesh_normal.mesh.faces import face_geometry

    rng = np.random.default_rng(13)
    count = 280_000
    vertices = rng.normal(size=(count // 2, 3))
    faces = rng.integers(0, len(vertices), (count, 3))
    faces[::1000, 1] = faces[::1000, 0]  # some degenerate
    fresh = face_normals(vertices, faces)
    given = FaceNormals(np.full((count, 3), np.nan), np.full(count, np.nan), np.ones(count, bool))
    into = face_normals(vertices, faces, out=given)
    assert into is given
    geometry = face_normals(face_geometry(vertices, faces))
    for other in (into, geometry):
        assert np.array_equal(fresh.normals, other.normals)
        assert np.array_equal(fresh.areas, other.areas)
        assert np.array_equal(fresh.degenerate, other.degenerate)
    assert fresh.degenerate[::1000].all() and not fresh.degenerate.all()


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_the_face_kernel_writes_every_row_once_and_nothing_else(threads: int) -> None:
    # Split between 1, 2 or 3 threads, the last part short: every row written, the same bits
    # as the library's call, and nothing outside the rows.
    from mesh_normal import _core

    rng = np.random.default_rng(threads)
    count = 3 * 4096 + 77
    vertices = rng.normal(size=(count // 2, 3)) * 1e3
    faces = rng.integers(0, len(vertices), (count, 3))
    faces[::50, 2] = faces[::50, 0]
    expected = face_normals(vertices, faces)
    # Views into buffers a page longer each way: a write outside the rows shows there.
    pad = 4096
    normals_buffer = np.full((count + 2 * pad, 3), np.nan)
    areas_buffer = np.full(count + 2 * pad, np.nan)
    flags_buffer = np.zeros(count + 2 * pad, np.uint8)
    flags_buffer[pad + 1 : pad + count : 2] = 1
    normals, areas = normals_buffer[pad:-pad], areas_buffer[pad:-pad]
    degenerate = flags_buffer[pad:-pad].view(bool)
    into = FaceNormals(normals, areas, degenerate)
    before = _core.threads()
    _core.set_threads(threads)
    try:
        assert run_face_kernel(checked_mesh(vertices, faces), into)
    finally:
        _core.set_threads(before)
    assert np.isnan(normals_buffer[:pad]).all() and np.isnan(normals_buffer[-pad:]).all()
    assert np.isnan(areas_buffer[:pad]).all() and np.isnan(areas_buffer[-pad:]).all()
    assert not flags_buffer[:pad].any() and not flags_buffer[-pad:].any()
    assert np.array_equal(normals, expected.normals)
    assert np.array_equal(areas, expected.areas)
    assert np.array_equal(degenerate, expected.degenerate)


def test_a_geometrys_unit_normals_on_every_core_are_numpys() -> None:
    # All the faces' unit normals are one compiled pass on every core: the same bits as
    # NumPy's where, divide and + 0.0 (a list of rows), into a new array or into the crosses.
    from mesh_normal.mesh.faces import face_geometry

    rng = np.random.default_rng(21)
    count = 40_003
    vertices = rng.normal(size=(count, 3)) * 1e-3
    faces = rng.integers(0, count, (count, 3))
    faces[::97, 2] = faces[::97, 0]  # degenerate
    geometry = face_geometry(vertices, faces)
    compiled = geometry.unit_normals()
    numpys = geometry.unit_normals(np.arange(count))
    assert compiled.tobytes() == numpys.tobytes()
    assert not np.signbit(compiled[geometry.degenerate]).any()
    again = face_geometry(vertices, faces)
    assert again.unit_normals(out=again.crosses) is again.crosses
    assert again.crosses.tobytes() == numpys.tobytes()


def _moving_soup(faces: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Random points and faces, some of them degenerate (a repeated index)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(faces // 2 + 3, 3))
    indices = rng.integers(0, len(points), size=(faces, 3))
    indices[::9, 1] = indices[::9, 0]
    return points, indices


def _garbage(count: int) -> FaceNormals:
    """Arrays for ``out``, full of what a last frame could have left (NaN, True)."""
    return FaceNormals(
        np.full((count, 3), np.nan), np.full(count, -1.0), np.ones(count, dtype=bool)
    )


@pytest.mark.parametrize("faces", [4, 1000, 40_000])  # Python, and the compiled kernel
def test_face_normals_into_given_arrays_are_a_fresh_calls_bits(faces: int) -> None:
    points, indices = _moving_soup(faces)
    out = _garbage(faces)
    arrays = (out.normals, out.areas, out.degenerate)
    for frame in range(3):  # the points move, the arrays stay
        moved = points * (1.0 + frame) + frame
        expected = face_normals(moved, indices)
        result = face_normals(moved, indices, out=out)
        assert result is out
        assert all(
            a is b for a, b in zip((out.normals, out.areas, out.degenerate), arrays, strict=True)
        )
        assert out.normals.tobytes() == expected.normals.tobytes()
        assert out.areas.tobytes() == expected.areas.tobytes()
        assert out.degenerate.tobytes() == expected.degenerate.tobytes()
        assert out.degenerate.any() and not out.degenerate.all()


def test_face_normals_of_a_geometry_into_given_arrays_are_copies() -> None:
    from mesh_normal.mesh.faces import face_geometry

    points, indices = _moving_soup(500)
    geometry = face_geometry(points, indices)
    out = _garbage(500)
    result = face_normals(geometry, out=out)
    own = face_normals(geometry)
    assert result is out and out.normals is not own.normals
    assert out.normals.tobytes() == own.normals.tobytes()
    assert out.areas.tobytes() == own.areas.tobytes()
    assert out.degenerate.tobytes() == own.degenerate.tobytes()


def test_unfit_arrays_for_out_are_refused_with_the_array_named() -> None:
    points, indices = _moving_soup(20)
    good = _garbage(20)
    read_only = np.zeros(20)
    read_only.flags.writeable = False
    cases = {
        "out.normals": FaceNormals(np.zeros((21, 3)), good.areas, good.degenerate),
        "out.areas": FaceNormals(good.normals, np.zeros(20, dtype=np.float32), good.degenerate),
        "out.degenerate": FaceNormals(good.normals, good.areas, np.zeros(20, dtype=np.uint8)),
        "read-only": FaceNormals(good.normals, read_only, good.degenerate),
        "strided": FaceNormals(np.zeros((20, 6))[:, :3], good.areas, good.degenerate),
    }
    for words, out in cases.items():
        with pytest.raises(ValueError, match=words):
            face_normals(points, indices, out=out)
    with pytest.raises(TypeError, match="out must be a FaceNormals"):
        face_normals(points, indices, out=(good.normals, good.areas, good.degenerate))  # type: ignore[arg-type]
    # Into the points it reads, or two results into one array: refused, the input untouched.
    square = np.random.default_rng(1).normal(size=(20, 3))
    before = square.copy()
    with pytest.raises(ValueError, match="shares memory"):
        face_normals(square, indices % 20, out=FaceNormals(square, good.areas, good.degenerate))
    assert square.tobytes() == before.tobytes()
    with pytest.raises(ValueError, match="shares memory"):
        face_normals(
            points,
            indices,
            out=FaceNormals(good.normals, good.normals.reshape(-1)[:20], good.degenerate),
        )


def test_a_geometry_s_own_arrays_are_never_written_through_out() -> None:
    # A geometry's results are read-only views of its own arrays: given back as ``out`` for
    # another mesh they are refused, and so is ``out`` over any array of the geometry itself.
    from mesh_normal.mesh.faces import face_geometry

    points, indices = _moving_soup(50)
    geometry = face_geometry(points, indices)
    own = face_normals(geometry)
    before = geometry.normals.copy(), geometry.degenerate.copy(), geometry.crosses.copy()
    other = points[::-1].copy()
    with pytest.raises(ValueError, match=r"out\.normals must be a writable"):
        face_normals(other, indices, out=own)
    good = _garbage(50)
    for name, array in (("normals", geometry.crosses), ("degenerate", geometry.recomputed)):
        out = FaceNormals(
            array if name == "normals" else good.normals,
            good.areas,
            array if name == "degenerate" else good.degenerate,
        )
        with pytest.raises(ValueError, match=rf"out\.{name} shares memory"):
            face_normals(geometry, out=out)
    assert geometry.normals.tobytes() == before[0].tobytes()
    assert geometry.degenerate.tobytes() == before[1].tobytes()
    assert geometry.crosses.tobytes() == before[2].tobytes()
