"""Tests for mesh_normal.vertices: vertex normals and their weightings."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from mesh_normal.corners import corner_normals
from mesh_normal.faces import face_normals
from mesh_normal.vertices import WEIGHTINGS, vertex_normals
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


@pytest.mark.parametrize("count", [1, 2, 3, 4, 5, 17, 64, 1000, 4099])
@pytest.mark.parametrize("size", [1, 2, 3, 5, 64, 1024])
def test_normalising_on_every_core_gives_the_one_core_bits(count: int, size: int) -> None:
    # The rows packed into the sums' own memory, block by block in any order the workers
    # finish them: the bytes of the one-thread kernel, which reads each row before it writes.
    from mesh_normal.kernels import workers
    from mesh_normal.vertices import normalise_kernel, normalise_packed_kernel

    sums = _sums(count)
    one = sums.copy()
    normals = one.reshape(-1)[: 3 * count].reshape(count, 3)
    missing = np.empty(count, dtype=bool)
    normalise_kernel(one, normals, missing)
    if count > 7:
        assert missing.any() and not missing.all()

    every = sums.copy()
    packed = every.reshape(-1)[: 3 * count].reshape(count, 3)
    flags = np.empty(count, dtype=bool)
    read = np.zeros((count + size - 1) // size, dtype=np.int64)
    normalise_packed_kernel(every, packed, flags, read, size, *workers())
    assert packed.tobytes() == normals.tobytes()
    assert flags.tobytes() == missing.tobytes()
    assert (read == 1).all()  # every block read once


def test_many_vertices_are_normalised_on_every_core(monkeypatch: pytest.MonkeyPatch) -> None:
    # smooth() takes the packed kernel from PACK_FROM vertices on: the same normals and mask.
    from mesh_normal import vertices as vertices_module

    rng = np.random.default_rng(5)
    points = rng.normal(size=(3000, 3))
    faces = rng.integers(0, 3000, size=(9000, 3))
    expected = {w: vertex_normals(points, faces, w) for w in WEIGHTINGS}
    monkeypatch.setattr(vertices_module, "PACK_FROM", 10)
    monkeypatch.setattr(vertices_module, "PACK_BLOCK", 37)
    for weighting, reference in expected.items():
        result = vertex_normals(points, faces, weighting)
        assert result.normals.tobytes() == reference.normals.tobytes()
        assert result.missing.tobytes() == reference.missing.tobytes()
        assert result.normals.flags.c_contiguous and result.normals.shape == (3000, 3)


def test_each_block_waits_for_every_block_its_packed_rows_lie_over() -> None:
    # Byte by byte: the packed rows of a block (24 bytes each) lie over the sums rows (32 bytes
    # each) up to the last one the kernel waits for, and never over a later block's sums.
    from mesh_normal.vertices import last_block_under

    for size in (1, 2, 3, 5, 7, 37, 64):
        for block in range(40):
            first, stop = block * size, (block + 1) * size
            covered = {byte // 32 for byte in range(24 * first, 24 * stop)}
            assert last_block_under(stop, size) == max(covered) // size
            assert max(covered) // size <= block  # earlier blocks, or this one
            assert min(covered) // size <= block
