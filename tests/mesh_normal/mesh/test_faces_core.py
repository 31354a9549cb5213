"""The compiled face kernels (``cpp/faces.cpp``) on their own: hand-computed cases, and bad
indices, shapes and types refused with a sentence instead of read out of bounds."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from mesh_normal import _core, face_geometry, face_normals, vertex_normals
from mesh_normal.mesh.bounds import column_bounds
from mesh_normal.mesh.checks import CheckedMesh
from mesh_normal.mesh.corners import corner_weights
from mesh_normal.mesh.report.stored_normals import unit_rows
from mesh_normal.tolerances import MESH_CANCELLED_SUM, MESH_DEGENERATE_SINE, MESH_RECOMPUTE_SINE
from tests.meshes import TETRA_FACES, TETRA_VERTICES

INDEX_LIMITS = [-1, 4, -(2**63), 2**63 - 1]


def test_the_core_uses_the_tolerances_of_the_library() -> None:
    assert _core.RECOMPUTE_SINE == MESH_RECOMPUTE_SINE
    assert _core.DEGENERATE_SINE == MESH_DEGENERATE_SINE
    assert _core.CANCELLED_SUM == MESH_CANCELLED_SUM


def unchecked(faces: np.ndarray) -> CheckedMesh:
    """A mesh made without the checks, as a caller could: its faces are not proven in range."""
    vertices = TETRA_VERTICES.astype(np.float64)
    return CheckedMesh(vertices, np.ascontiguousarray(faces, dtype=np.intp), vertices, 1.0, 1)


@pytest.mark.parametrize("bad", INDEX_LIMITS)
def test_every_kernel_refuses_an_index_out_of_range_with_the_checks_sentence(bad: int) -> None:
    faces = np.array(TETRA_FACES, dtype=np.intp)
    faces[2, 1] = bad
    mesh = unchecked(faces)
    sentence = re.escape("faces[2] ")
    with pytest.raises(ValueError, match=sentence):
        face_geometry(mesh)
    with pytest.raises(ValueError, match=sentence):
        face_normals(mesh)
    for weighting in ("uniform", "area", "angle", "max"):
        with pytest.raises(ValueError, match=sentence):
            vertex_normals(mesh, weighting=weighting)
    with pytest.raises(ValueError, match=sentence):
        face_normals(TETRA_VERTICES, faces)  # raw intp faces: checked as they are read


@pytest.mark.parametrize("bad", INDEX_LIMITS)
def test_the_kernels_report_a_bad_index_and_read_nothing_beyond(bad: int) -> None:
    points = np.ascontiguousarray(TETRA_VERTICES, dtype=np.float64)
    faces = np.array(TETRA_FACES, dtype=np.intp)
    faces[-1, 0] = bad
    m = len(faces)
    assert not _core.face_normals(
        points, 1.0, faces, 1, np.empty((m, 3)), np.empty(m), np.empty(m, bool)
    )
    assert not _core.face_geometry(
        points, 1.0, faces, np.empty((m, 3)), np.empty(m), np.empty(m, bool), np.empty(m, bool)
    )
    crosses, lengths, flags = np.ones((m, 3)), np.ones(m), np.zeros(m, bool)
    for code in range(4):
        for fused in (False, True):
            sums = np.zeros((len(points), 4))
            assert not _core.vertex_sums(
                code, points, 1.0, faces, crosses, lengths, flags, fused, sums
            )
        assert not _core.corner_weights(code, points, 1.0, faces, lengths, flags, np.empty((3, m)))


def test_the_kernels_refuse_arrays_of_the_wrong_length() -> None:
    points = np.ascontiguousarray(TETRA_VERTICES, dtype=np.float64)
    faces = np.array(TETRA_FACES, dtype=np.intp)
    short = len(faces) - 1
    with pytest.raises(ValueError, match="a row for each face"):
        _core.face_normals(
            points, 1.0, faces, 1, np.empty((short, 3)), np.empty(4), np.empty(4, bool)
        )
    with pytest.raises(ValueError, match="one for each face"):
        _core.face_geometry(
            points,
            1.0,
            faces,
            np.empty((4, 3)),
            np.empty(short),
            np.empty(4, bool),
            np.empty(4, bool),
        )
    with pytest.raises(ValueError, match="one for each face"):
        _core.unit_normals(np.ones((4, 3)), np.ones(4), np.zeros(short, bool), np.empty((4, 3)))
    with pytest.raises(ValueError, match="a row for each point"):
        _core.vertex_sums(
            1,
            points,
            1.0,
            faces,
            np.ones((4, 3)),
            np.ones(4),
            np.zeros(4, bool),
            False,
            np.zeros((3, 4)),
        )
    with pytest.raises(ValueError, match="a row for each face"):
        _core.vertex_sums(
            1,
            points,
            1.0,
            faces,
            np.ones((short, 3)),
            np.ones(4),
            np.zeros(4, bool),
            False,
            np.zeros((4, 4)),
        )
    with pytest.raises(ValueError, match="weighting code"):
        _core.vertex_sums(
            4,
            points,
            1.0,
            faces,
            np.ones((4, 3)),
            np.ones(4),
            np.zeros(4, bool),
            False,
            np.zeros((4, 4)),
        )
    with pytest.raises(ValueError, match="a column for each face"):
        _core.corner_weights(
            2, points, 1.0, faces, np.ones(4), np.zeros(4, bool), np.empty((3, short))
        )
    with pytest.raises(ValueError, match="one for each row"):
        _core.normalise_sums(np.zeros((4, 4)), np.empty(short, bool))
    with pytest.raises(ValueError, match="one for each row"):
        _core.unit_rows(np.ones((4, 3)), np.empty((short, 3)), np.empty(4, bool))
    with pytest.raises(ValueError, match="the same rows"):
        _core.half_angle_sides(
            np.ones((4, 3)), np.ones((3, 3)), True, np.empty(0, np.intp), np.empty(3), np.empty(3)
        )
    with pytest.raises(ValueError, match="more outputs than rows"):
        _core.half_angle_sides(
            np.ones((4, 3)), np.ones((4, 3)), True, np.empty(0, np.intp), np.empty(5), np.empty(5)
        )
    with pytest.raises(ValueError, match="one for each output"):
        _core.half_angle_sides(
            np.ones((4, 3)), np.ones((4, 3)), False, np.arange(2), np.empty(3), np.empty(3)
        )


@pytest.mark.parametrize("row", [-1, 4, 2**62])
def test_a_compared_row_out_of_range_is_refused(row: int) -> None:
    rows = np.array([0, row, 2], dtype=np.intp)
    with pytest.raises(IndexError, match="not a row of the normals"):
        _core.half_angle_sides(
            np.ones((4, 3)), np.ones((4, 3)), False, rows, np.empty(3), np.empty(3)
        )


def test_the_kernels_refuse_other_types_and_layouts_instead_of_copying() -> None:
    points = np.ascontiguousarray(TETRA_VERTICES, dtype=np.float64)
    faces = np.array(TETRA_FACES, dtype=np.intp)
    outputs = (np.empty((4, 3)), np.empty(4), np.empty(4, bool))
    for wrong_points, wrong_faces in (
        (points, faces.astype(np.int32)),
        (np.asfortranarray(points), faces),
        (points.astype(np.float32), faces),
        (points, np.asfortranarray(faces)),
    ):
        with pytest.raises(TypeError):
            _core.face_normals(wrong_points, 1.0, wrong_faces, 1, *outputs)
    frozen = np.empty((4, 3))
    frozen.flags.writeable = False
    with pytest.raises(TypeError):
        _core.face_normals(points, 1.0, faces, 1, frozen, outputs[1], outputs[2])


def test_bounds_of_hand_made_points_keep_the_first_zeros_sign() -> None:
    points = np.array([[-0.0, 1.0, 2.0], [0.0, -1.0, 5.0], [3.0, 0.5, -2.0]])
    low, high = column_bounds(points)
    assert low.tolist() == [-0.0, -1.0, -2.0] and high.tolist() == [3.0, 1.0, 5.0]
    assert math.copysign(1.0, low[0]) < 0
    low, high = column_bounds(points, np.array([[1, 1, 1]]))  # only the second row
    assert low.tolist() == high.tolist() == [0.0, -1.0, 5.0]
    strided = np.asfortranarray(points)  # any layout: taken as C-contiguous float64
    assert [a.tolist() for a in column_bounds(strided)] == [[-0.0, -1.0, -2.0], [3.0, 1.0, 5.0]]


def test_bounds_refuse_no_points_and_no_used_point() -> None:
    with pytest.raises(ValueError, match="no points to bound"):
        _core.column_bounds(np.empty((0, 3)), np.empty(3), np.empty(3))
    with pytest.raises(ValueError, match="no point is used"):
        _core.used_column_bounds(np.ones((4, 3)), np.zeros(4, bool), np.empty(3), np.empty(3))
    with pytest.raises(ValueError, match="one for each point"):
        _core.used_column_bounds(np.ones((4, 3)), np.ones(3, bool), np.empty(3), np.empty(3))


def test_stored_rows_are_scaled_without_overflow_or_underflow() -> None:
    stored = np.array(
        [
            [3.0, 4.0, 0.0],
            [0.0, 0.0, 0.0],
            [math.nan, 1.0, 0.0],
            [math.inf, 0.0, 0.0],
            [1e-320, 0.0, 0.0],
            [1e308, -1e308, 0.0],
        ]
    )
    unit, usable = unit_rows(stored)
    assert usable.tolist() == [True, False, False, False, True, True]
    assert unit[0].tolist() == [0.6, 0.8, 0.0]
    assert unit[4].tolist() == [1.0, 0.0, 0.0]
    half = math.sqrt(0.5)
    assert np.allclose(unit[5], [half, -half, 0.0], rtol=1e-15, atol=0)


def test_corner_weights_of_a_right_triangle_are_its_angles_and_areas() -> None:
    geometry = face_geometry([[0.0, 0, 0], [2, 0, 0], [0, 2, 0], [5, 5, 5]], [[0, 1, 2], [0, 0, 3]])
    angles = corner_weights(geometry, "angle")
    assert np.allclose(angles[:, 0], [math.pi / 2, math.pi / 4, math.pi / 4], rtol=1e-15, atol=0)
    assert (angles[:, 1] == 0.0).all()  # degenerate: weighs nothing
    area = corner_weights(geometry, "area")  # |cross| of the scaled points: 4 * 2**(-2 * 3)
    assert area[:, 0].tolist() == [geometry.lengths[0]] * 3 == [2.0**-4] * 3
    assert corner_weights(geometry, "uniform")[:, 0].tolist() == [1.0] * 3
