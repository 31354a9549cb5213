"""Tests for mesh_normal.faces, mesh_normal.vertices and mesh_normal.topology: normals of meshes."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal import topology
from mesh_normal import vertices as mesh_normals
from mesh_normal.faces import FaceNormals, check_mesh, face_areas, face_normals, take_rows
from mesh_normal.tolerances import MESH_DEGENERATE_SINE
from mesh_normal.topology import vertex_corners
from mesh_normal.vertices import (
    WEIGHTINGS,
    CornerNormals,
    VertexNormals,
    corner_normals,
    vertex_normals,
)
from tests.paths import DATA

SAMPLES = ("sphere.ply", "nut.ply", "ant.ply", "cube.obj")

TETRAHEDRON = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
TETRAHEDRON_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def load(name: str) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.load(DATA / name, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)


def unit(*xyz: float) -> np.ndarray:
    vector = np.array(xyz, dtype=np.float64)
    return vector / np.linalg.norm(vector)


def octahedron() -> tuple[np.ndarray, np.ndarray]:
    vertices = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
    )
    faces = []
    for x in (0, 1):
        for y in (2, 3):
            for z in (4, 5):
                corner = [x, y, z]
                if np.linalg.det(vertices[corner]) < 0:  # outward: positive orientation
                    corner = [x, z, y]
                faces.append(corner)
    return vertices, np.array(faces)


def assert_clean(*arrays: np.ndarray) -> None:
    for array in arrays:
        assert array.dtype == np.float64
        assert np.isfinite(array).all()


def assert_unit_or_zero(normals: np.ndarray, zero: np.ndarray) -> None:
    lengths = np.linalg.norm(normals, axis=-1)
    assert np.all(lengths[zero] == 0.0)
    assert np.allclose(lengths[~zero], 1.0, atol=4e-16, rtol=0)


# --- face normals and areas -------------------------------------------------------------------


def test_tetrahedron_face_normals_and_areas() -> None:
    r = face_normals(TETRAHEDRON, TETRAHEDRON_FACES)
    assert isinstance(r, FaceNormals) and len(r) == 4
    expected = [[0, 0, -1], [0, -1, 0], [-1, 0, 0], unit(1, 1, 1)]
    assert np.allclose(r.normals, expected, atol=1e-16, rtol=0)
    assert np.allclose(r.areas, [0.5, 0.5, 0.5, math.sqrt(3) / 2], rtol=1e-15)
    assert not r.degenerate.any()
    assert np.array_equal(face_areas(TETRAHEDRON, TETRAHEDRON_FACES), r.areas)
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
    huge = face_normals(TETRAHEDRON * 1e300, TETRAHEDRON_FACES)
    assert np.isinf(huge.areas).all()
    assert np.allclose(huge.normals, face_normals(TETRAHEDRON, TETRAHEDRON_FACES).normals)
    tiny = face_normals(TETRAHEDRON * 1e-300, TETRAHEDRON_FACES)
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


def test_tetrahedron_vertex_normals_by_hand() -> None:
    quarter, third = math.pi / 4, math.pi / 3
    slanted = unit(1, 1, 1)
    # Vertex 0: three right angles on the -x, -y, -z faces.
    # Vertex 1: 45 degrees on the -z and -y faces, 60 degrees on the slanted face.
    expected = {
        "angle": [unit(-1, -1, -1), unit(*(quarter * np.array([0, -1, -1]) + third * slanted))],
        "uniform": [unit(-1, -1, -1), unit(*(np.array([0, -1, -1]) + slanted))],
        "area": [
            unit(-1, -1, -1),
            unit(*(0.5 * np.array([0, -1, -1]) + 0.5 * np.sqrt(3) * slanted)),
        ],
        # sin(90)/(1*1) at vertex 0; sin(45)/(1*sqrt2) = 1/2 and sin(60)/(sqrt2*sqrt2) at 1.
        "max": [
            unit(-1, -1, -1),
            unit(*(0.5 * np.array([0, -1, -1]) + math.sin(third) / 2 * slanted)),
        ],
    }
    for weighting, (first, second) in expected.items():
        r = vertex_normals(TETRAHEDRON, TETRAHEDRON_FACES, weighting)
        assert np.allclose(r.normals[:2], [first, second], atol=1e-15, rtol=0), weighting
        assert not r.missing.any()


def test_each_weighting_on_a_hand_case() -> None:
    # Three faces around the origin: a right angle between legs 2 and 1 (+z, area 1), a right
    # angle between legs 3 and 2 (+y, area 3), a 135-degree angle between legs 1 and sqrt 2
    # (+z, area 1/2).
    vertices = np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0], [0, 0, 3], [-1, -1, 0]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 4]])
    assert np.allclose(face_normals(vertices, faces).normals, [[0, 0, 1], [0, 1, 0], [0, 0, 1]])
    expected = {
        "uniform": unit(0, 1, 2),
        "area": unit(0, 3, 1 + 0.5),
        "angle": unit(0, math.pi / 2, math.pi / 2 + 3 * math.pi / 4),
        # Nelson Max: sin(angle) / (|e1| |e2|): 1/(2*1), 1/(3*2), sin(135)/(1*sqrt 2) = 1/2.
        "max": unit(0, 1 / 6, 1 / 2 + 1 / 2),
    }
    for weighting, normal in expected.items():
        got = vertex_normals(vertices, faces, weighting).normals[0]
        assert np.allclose(got, normal, atol=1e-15, rtol=0), weighting


@pytest.mark.parametrize("shape", ["tetrahedron", "octahedron"])
def test_all_weightings_agree_on_a_regular_solid(shape: str) -> None:
    if shape == "octahedron":
        vertices, faces = octahedron()
    else:
        vertices = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
        faces = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    assert (face_normals(vertices, faces).normals @ np.ones(3) != 0).any()
    radial = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    for weighting in WEIGHTINGS:
        r = vertex_normals(vertices, faces, weighting)
        assert np.allclose(r.normals, radial, atol=1e-15, rtol=0), weighting


def test_angle_and_max_weighting_ignore_how_the_cube_is_triangulated() -> None:
    vertices, faces = load("cube.obj")
    diagonal = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    for weighting in ("angle", "max"):
        assert np.allclose(
            vertex_normals(vertices, faces, weighting).normals, diagonal, atol=1e-15, rtol=0
        )
    # A corner with two triangles of one side counts that side twice by faces or area.
    assert not np.allclose(vertex_normals(vertices, faces, "uniform").normals, diagonal)


def test_a_sheet_folded_flat_onto_itself_has_no_vertex_normals() -> None:
    vertices = TETRAHEDRON[:3]
    faces = np.array([[0, 1, 2], [0, 2, 1]])
    for weighting in WEIGHTINGS:
        r = vertex_normals(vertices, faces, weighting)
        assert r.missing.all() and np.array_equal(r.normals, np.zeros((3, 3)))
    folded = corner_normals(vertices, faces, 180.0)
    assert folded.missing.all() and not folded.normals.any()
    sharp = corner_normals(vertices, faces, 30.0)
    assert not sharp.missing.any()
    assert np.array_equal(sharp.normals, [[[0, 0, 1]] * 3, [[0, 0, -1]] * 3])


# --- against trimesh ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", SAMPLES)
def test_face_normals_match_trimesh(name: str) -> None:
    vertices, faces = load(name)
    theirs = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    ours = face_normals(vertices, faces)
    nonzero = np.any(theirs.face_normals != 0, axis=1)
    assert np.array_equal(~ours.degenerate, nonzero)
    assert np.allclose(ours.normals[nonzero], theirs.face_normals[nonzero], atol=1e-12, rtol=0)
    assert np.allclose(ours.areas, theirs.area_faces, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", SAMPLES)
def test_vertex_normals_match_trimesh(name: str) -> None:
    vertices, faces = load(name)
    theirs = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    # trimesh's vertex_normals weigh by corner angle (geometry.weighted_vertex_normals); its
    # mean_vertex_normals sum what they are given: unit normals (uniform) or crosses (area).
    angle = theirs.vertex_normals
    uniform = trimesh.util.unitize(
        trimesh.geometry.mean_vertex_normals(len(vertices), faces, theirs.face_normals)
    )
    area = trimesh.util.unitize(
        trimesh.geometry.mean_vertex_normals(len(vertices), faces, theirs.triangles_cross)
    )
    for weighting, expected in (("angle", angle), ("uniform", uniform), ("area", area)):
        ours = vertex_normals(vertices, faces, weighting)
        assert not ours.missing.any()
        assert np.allclose(ours.normals, expected, atol=1e-12, rtol=0), weighting


# --- corner normals -----------------------------------------------------------------------------


def test_cube_corners_take_the_face_normal_below_90_degrees() -> None:
    vertices, faces = load("cube.obj")
    flat = face_normals(vertices, faces).normals
    for crease in (0.0, 30.0, 89.0):
        r = corner_normals(vertices, faces, crease)
        assert np.array_equal(r.normals, np.repeat(flat[:, None], 3, axis=1)), crease
        assert not r.missing.any()


def test_cube_corners_take_the_vertex_normal_from_90_degrees() -> None:
    vertices, faces = load("cube.obj")
    smooth = vertex_normals(vertices, faces).normals[faces]
    for crease in (90.0, 120.0, 180):
        r = corner_normals(vertices, faces, crease)
        assert np.allclose(r.normals, smooth, atol=1e-15, rtol=0), crease


def test_a_roof_is_smooth_below_its_crease_and_sharp_above() -> None:
    # Two faces sharing the ridge 0-1, their normals 20 degrees apart.
    tilt = math.radians(10)
    vertices = np.array(
        [
            [0, 0, 0],
            [1, 0, 0],
            [0, -math.cos(tilt), -math.sin(tilt)],
            [0, math.cos(tilt), -math.sin(tilt)],
        ]
    )
    faces = np.array([[0, 2, 1], [0, 1, 3]])
    flat = face_normals(vertices, faces).normals
    assert math.isclose(math.degrees(math.acos(flat[0] @ flat[1])), 20.0)
    smooth = corner_normals(vertices, faces, 25.0).normals
    assert np.allclose(smooth[0, 0], [0, 0, 1]) and np.allclose(smooth[1, 0], [0, 0, 1])
    assert np.allclose(smooth[0, 1], flat[0], atol=1e-15, rtol=0)  # vertex 2: only face 0
    sharp = corner_normals(vertices, faces, 15.0).normals
    assert np.allclose(sharp, np.repeat(flat[:, None], 3, axis=1), atol=1e-15, rtol=0)


def reference_corner_normals(
    vertices: np.ndarray, faces: np.ndarray, crease: float
) -> tuple[np.ndarray, float]:
    """Angle-weighted corner normals by the documented rule, one corner at a time.

    Also returns how close any pair of faces at a vertex came to the crease (in cosine).
    """
    normals = face_normals(vertices, faces).normals
    angles = np.zeros(faces.shape)
    for f, corner in enumerate(faces):
        for k in range(3):
            p = vertices[corner[(k + 1) % 3]] - vertices[corner[k]]
            q = vertices[corner[(k + 2) % 3]] - vertices[corner[k]]
            angles[f, k] = math.atan2(np.linalg.norm(np.cross(p, q)), p @ q)
    bound = math.cos(math.radians(crease))
    result = np.zeros((len(faces), 3, 3))
    margin = math.inf
    for f, corner in enumerate(faces):
        for k, v in enumerate(corner):
            total = np.zeros(3)
            for g, j in zip(*np.nonzero(faces == v), strict=True):
                cosine = normals[f] @ normals[g]
                margin = min(margin, abs(cosine - bound))
                if cosine >= bound:
                    total += angles[g, j] * normals[g]
            result[f, k] = total / np.linalg.norm(total)
    return result, margin


@pytest.mark.parametrize("crease", [5.0, 20.0, 40.0, 75.0])
def test_corner_normals_follow_the_documented_rule(crease: float) -> None:
    vertices, faces = load("nut.ply")  # flat sides, chamfers and sharp rims
    expected, margin = reference_corner_normals(vertices, faces, crease)
    assert margin > 1e-9  # no pair sits on the crease, so rounding cannot decide
    r = corner_normals(vertices, faces, crease)
    assert not r.missing.any()
    assert np.allclose(r.normals, expected, atol=1e-12, rtol=0)


@pytest.mark.parametrize("chunk", [40, 4])
def test_corner_normals_in_small_chunks_are_the_same(
    chunk: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    vertices, faces = load("ant.ply")
    whole = corner_normals(vertices, faces, 5.0)
    # 40 pairs: one valence-6 vertex at a time, and valence 7 and up a few rows at a time;
    # 4 pairs: every vertex in blocks of corners.
    monkeypatch.setattr(mesh_normals, "MESH_PAIR_CHUNK", chunk)
    split = corner_normals(vertices, faces, 5.0)
    assert np.allclose(split.normals, whole.normals, atol=1e-15, rtol=0)
    assert np.array_equal(split.missing, whole.missing)


def test_smooth_sample_corners_are_their_vertex_normals() -> None:
    vertices, faces = load("sphere.ply")
    r = corner_normals(vertices, faces, 60.0, "area")
    assert np.allclose(
        r.normals, vertex_normals(vertices, faces, "area").normals[faces], atol=1e-15, rtol=0
    )


# --- grouping and gathering ---------------------------------------------------------------------


@pytest.mark.parametrize("limit", [topology.KEY_LIMIT, 0])
def test_vertex_corners_group_corners_in_order(limit: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(topology, "KEY_LIMIT", limit)  # 0: the stable argsort fallback
    faces = np.array([[2, 0, 1], [1, 2, 4], [4, 2, 0]])
    groups = vertex_corners(faces, 6)
    assert groups.order.tolist() == [1, 8, 2, 3, 0, 4, 7, 5, 6]
    assert groups.starts.tolist() == [0, 2, 4, 7, 7, 9, 9]
    assert groups.counts.tolist() == [2, 2, 3, 0, 2, 0]
    subset = vertex_corners(faces, 6, np.array([0, 4, 5, 8]))
    assert subset.order.tolist() == [8, 0, 4, 5]
    assert subset.counts.tolist() == [1, 0, 2, 0, 1, 0]


def test_take_rows_is_fancy_indexing() -> None:
    array = np.arange(30, dtype=np.float64).reshape(10, 3)
    index = np.array([[3, 0], [9, 3]])
    assert np.array_equal(take_rows(array, index), array[index])


# --- input checking -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("vertices", "faces", "words"),
    [
        (np.zeros((3, 2)), [[0, 1, 2]], "vertices must have shape (n, 3), not (3, 2)"),
        (np.zeros(9), [[0, 1, 2]], "vertices must have shape (n, 3), not (9,)"),
        (np.zeros((3, 3), dtype=bool), [[0, 1, 2]], "vertices must hold real numbers, not bool"),
        (np.zeros((3, 3), dtype=complex), [[0, 1, 2]], "real numbers, not complex128"),
        ([["a", "b", "c"]] * 3, [[0, 1, 2]], "vertices must hold real numbers"),
        (
            [[0, 0, 0], [1, 0, np.nan], [0, 1, 0]],
            [[0, 1, 2]],
            "vertices[1] has a coordinate that is not a finite number",
        ),
        ([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]], [[0, 1, 2]], "vertices[2]"),
        (TETRAHEDRON, [[0.0, 1.0, 2.0]], "faces must hold integer vertex indices, not float64"),
        (TETRAHEDRON, [[0, 1, 2, 3]], "faces must have shape (m, 3), not (1, 4)"),
        (TETRAHEDRON, [0, 1, 2], "faces must have shape (m, 3), not (3,)"),
        (TETRAHEDRON, [[0, 1, 2], [3, -1, 2]], "faces[1] has a negative vertex index, -1"),
        (
            TETRAHEDRON,
            [[0, 1, 2], [0, 1, 3], [0, 4, 1]],
            "faces[2] refers to vertex 4, but there are only 4 vertices (indices 0 to 3)",
        ),
        (np.empty((0, 3)), [[0, 1, 2]], "faces[0] refers to vertex 0, but there are no vertices"),
        (TETRAHEDRON, np.array([[0, 1, 2**40]], dtype=np.uint64), "refers to vertex 1099511627776"),
    ],
)
def test_bad_input_is_refused_with_a_clear_message(
    vertices: object, faces: object, words: str
) -> None:
    for call in (face_normals, vertex_normals, corner_normals, check_mesh):
        with pytest.raises(ValueError, match=re.escape(words)) as error:
            call(vertices, faces)  # type: ignore[operator]
        assert str(error.value).endswith(".")


def test_unknown_weighting_and_bad_crease_angles_are_refused() -> None:
    with pytest.raises(ValueError, match="weighting must be one of uniform, area, angle, max"):
        vertex_normals(TETRAHEDRON, TETRAHEDRON_FACES, "mean")  # type: ignore[arg-type]
    for crease in (-1.0, 180.5, math.nan, math.inf):
        with pytest.raises(ValueError, match="between 0 and 180 degrees"):
            corner_normals(TETRAHEDRON, TETRAHEDRON_FACES, crease)
    for crease in (True, "30", None):
        with pytest.raises(ValueError, match="crease_angle must be a number of degrees"):
            corner_normals(TETRAHEDRON, TETRAHEDRON_FACES, crease)  # type: ignore[arg-type]


def test_inputs_are_converted_and_not_modified() -> None:
    vertices = TETRAHEDRON.astype(np.float32)
    faces = TETRAHEDRON_FACES.astype(np.uint16)
    before = vertices.copy(), faces.copy()
    points, indices = check_mesh(vertices, faces)
    assert points.dtype == np.float64 and indices.dtype == np.intp
    assert np.allclose(
        face_normals(vertices, faces).normals, face_normals(TETRAHEDRON, TETRAHEDRON_FACES).normals
    )
    assert vertex_normals(vertices.tolist(), faces.tolist()).normals.shape == (4, 3)
    assert np.array_equal(vertices, before[0]) and np.array_equal(faces, before[1])
    fortran = np.asfortranarray(TETRAHEDRON)
    assert np.array_equal(
        face_normals(fortran, np.asfortranarray(TETRAHEDRON_FACES)).normals,
        face_normals(TETRAHEDRON, TETRAHEDRON_FACES).normals,
    )


def test_an_empty_mesh_gives_empty_results() -> None:
    r = face_normals(np.empty((0, 3)), [])
    assert r.normals.shape == (0, 3) and r.areas.shape == r.degenerate.shape == (0,)
    smooth = vertex_normals(TETRAHEDRON, np.empty((0, 3), dtype=int))
    assert smooth.missing.all() and not smooth.normals.any()
    corners = corner_normals(TETRAHEDRON, np.empty((0, 3), dtype=int))
    assert corners.normals.shape == (0, 3, 3) and corners.missing.shape == (0, 3)
