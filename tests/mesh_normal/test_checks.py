"""Tests for mesh_normal.checks: bad input is refused clearly, good input converted."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from mesh_normal.checks import check_mesh
from mesh_normal.corners import corner_normals
from mesh_normal.faces import face_normals
from mesh_normal.vertices import vertex_normals
from tests.mesh_normal._meshes import (
    TETRAHEDRON,
    TETRAHEDRON_FACES,
)


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
