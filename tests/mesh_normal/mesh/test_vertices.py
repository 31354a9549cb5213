"""Tests for mesh_normal.mesh.vertices: vertex normals and their weightings."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from mesh_normal.mesh.corners import corner_normals
from mesh_normal.mesh.faces import face_normals
from mesh_normal.mesh.vertices import WEIGHTINGS, vertex_normals
from tests.mesh_normal._normals import unit
from tests.meshes import SAMPLES, TETRA_FACES, TETRA_VERTICES, load, octahedron


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
        r = vertex_normals(TETRA_VERTICES, TETRA_FACES, weighting)
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
    vertices = TETRA_VERTICES[:3]
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


def _sums(count: int, seed: int = 0) -> np.ndarray:
    """Vertex sums as the kernels leave them: some cancel against their weight, some are
    zero (a vertex in no face), the rest any direction."""
    rng = np.random.default_rng(seed)
    sums = rng.normal(size=(count, 4))
    sums[:, 3] = np.abs(sums[:, 3]) + 1.0
    sums[::7, :3] *= 1e-18  # cancelled: shorter than MESH_CANCELLED_SUM of the weight
    sums[::11] = 0.0
    sums[::13, :3] = -0.0
    return sums


@pytest.mark.parametrize("count", [0, 1, 2, 3, 4, 5, 17, 64, 1000, 4099, 20_011])
@pytest.mark.parametrize("threads", [1, 2, 3])
def test_normalising_packs_the_documented_unit_rows_into_the_sums_memory(
    count: int, threads: int
) -> None:
    # Each row over its length, zero where it cancels against its weight (and 0.0, never
    # -0.0), packed as (n, 3) into the first 3 n doubles of the sums themselves, on any number
    # of threads.
    from mesh_normal import _core
    from mesh_normal.mesh.vertices import normalised
    from mesh_normal.tolerances import MESH_CANCELLED_SUM

    sums = _sums(count)
    x, y, z, total = sums.T
    square = x * x + y * y + z * z
    cancel = MESH_CANCELLED_SUM * total
    missing = square <= cancel * cancel
    length = np.where(missing, np.inf, np.sqrt(square))
    expected = sums[:, :3] / length[:, None] + 0.0
    if count > 13:
        assert missing.any() and not missing.all()
    before = _core.threads()
    _core.set_threads(threads)
    try:
        normals, flags = normalised(sums)
    finally:
        _core.set_threads(before)
    assert normals.shape == (count, 3) and normals.flags.c_contiguous
    assert count == 0 or np.shares_memory(normals, sums)
    assert normals.tobytes() == expected.tobytes()
    assert flags.tobytes() == missing.tobytes()
