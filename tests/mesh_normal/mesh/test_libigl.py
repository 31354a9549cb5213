"""Differential tests against libigl (a test-only dependency) on the sample meshes.

Where libigl is right (faces with area) we agree with it to rounding; where it is not (a face
without area) it gives uninitialised rows or NaN, and we give zero rows and a mask.
"""

from __future__ import annotations

import numpy as np
import pytest

from mesh_normal import face_normals, vertex_normals
from tests.meshes import SAMPLES, load

igl = pytest.importorskip("igl")

WEIGHTINGS = {"uniform": "UNIFORM", "area": "AREA", "angle": "ANGLE"}


def _igl_faces(faces: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(faces, dtype=np.int64)


@pytest.mark.parametrize("name", SAMPLES)
def test_face_normals_match_libigl(name: str) -> None:
    vertices, faces = load(name)
    ours = face_normals(vertices, faces)
    assert not ours.degenerate.any()
    theirs = np.asarray(igl.per_face_normals(vertices, _igl_faces(faces)))
    assert np.allclose(ours.normals, theirs, atol=1e-12, rtol=0)


@pytest.mark.parametrize("name", SAMPLES)
@pytest.mark.parametrize("weighting", sorted(WEIGHTINGS))
def test_vertex_normals_match_libigl(name: str, weighting: str) -> None:
    vertices, faces = load(name)
    kind = getattr(igl, f"PER_VERTEX_NORMALS_WEIGHTING_TYPE_{WEIGHTINGS[weighting]}")
    theirs = np.asarray(igl.per_vertex_normals(vertices, _igl_faces(faces), kind))
    ours = vertex_normals(vertices, faces, weighting)
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    assert np.array_equal(ours.missing, ~used)
    assert np.allclose(ours.normals[used], theirs[used], atol=1e-12, rtol=0), weighting


def test_where_libigl_gives_nan_we_give_a_zero_row_and_the_mask() -> None:
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [3, 0, 0]])
    faces = np.array([[0, 1, 2], [1, 3, 4]])  # the second face is collinear
    kind = igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA
    theirs = np.asarray(igl.per_vertex_normals(vertices, _igl_faces(faces), kind))
    ours = vertex_normals(vertices, faces, "area")
    assert np.isnan(theirs[3:]).all()  # libigl: 0 / 0 at vertices only the sliver touches
    assert ours.missing.tolist() == [False, False, False, True, True]
    assert not np.isnan(ours.normals).any() and not ours.normals[3:].any()
    assert np.allclose(ours.normals[:3], theirs[:3], atol=1e-15, rtol=0)
