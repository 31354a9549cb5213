"""mesh_normal.mesh.corners (and vertex_corners of mesh_normal.mesh.topology): corner normals."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from mesh_normal.mesh import corners, topology
from mesh_normal.mesh.corners import corner_blocks, corner_normals, take_rows
from mesh_normal.mesh.faces import face_normals
from mesh_normal.mesh.topology import vertex_corners
from mesh_normal.mesh.vertices import vertex_normals
from tests.meshes import load


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
    monkeypatch.setattr(corners, "MESH_PAIR_CHUNK", chunk)
    split = corner_normals(vertices, faces, 5.0)
    assert np.allclose(split.normals, whole.normals, atol=1e-15, rtol=0)
    assert np.array_equal(split.missing, whole.missing)


@pytest.mark.parametrize("rows", [1, 7, 4096])
def test_corner_blocks_give_the_same_bits_however_split(rows: int) -> None:
    vertices, faces = load("nut.ply")  # creased and smooth vertices both
    whole = corner_normals(vertices, faces, 20.0)
    blocks = corner_blocks(vertices, faces, 20.0, rows=rows)
    assert len(blocks.creased) and len(blocks.creased) < faces.size
    edges = [0, 1, *range(5, len(faces), rows), len(faces)]
    joined = np.concatenate([blocks.block(a, b) for a, b in itertools.pairwise(edges)])
    assert joined.tobytes() == whole.normals.tobytes()
    assert np.array_equal(blocks.missing, whole.missing)


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
