"""app/mesh/classes.py: each face's worst problem."""

from __future__ import annotations

import numpy as np

from app.mesh.classes import (
    BOUNDARY,
    CLASSES,
    COLORS,
    DEGENERATE,
    FLIPPED,
    NONMANIFOLD,
    OK,
    face_classes,
    faces_on_edges,
)


def test_classes_take_the_worst_problem() -> None:
    faces = np.array([[0, 1, 2], [0, 2, 3], [1, 2, 4], [2, 3, 4], [0, 0, 1]])
    degenerate = np.array([False, False, False, False, True])
    flipped = np.array([False, True, False, False, True])
    boundary = np.array([[0, 1], [3, 4]])  # faces 0, 3 (and 4 by its edge 0-1)
    nonmanifold = np.array([[4, 2]])  # faces 2, 3
    classes = face_classes(faces, 5, degenerate, flipped, boundary, nonmanifold)
    assert classes.tolist() == [BOUNDARY, FLIPPED, NONMANIFOLD, NONMANIFOLD, DEGENERATE]


def test_an_edge_finds_its_faces_whichever_way_it_is_written() -> None:
    faces = np.array([[0, 1, 2], [2, 3, 0]])
    assert faces_on_edges(faces, 4, np.array([[1, 0]])).tolist() == [True, False]
    assert faces_on_edges(faces, 4, np.array([[0, 2]])).tolist() == [True, True]
    assert faces_on_edges(faces, 4, np.zeros((0, 2), int)).tolist() == [False, False]


def test_every_class_has_its_own_colour_worst_first() -> None:
    assert [item.code for item in CLASSES] == [DEGENERATE, FLIPPED, NONMANIFOLD, BOUNDARY, OK]
    assert len(set(COLORS.values())) == len(CLASSES)


def test_legend_of_flipped_faces_uses_the_diagnosis_words() -> None:
    """The fix flips faces against their neighbours and whole parts wound inward alike."""
    (flipped,) = [item for item in CLASSES if item.code == FLIPPED]
    assert "wound against its neighbours" in flipped.label
    assert "wound inward" in flipped.label  # the diagnosis: "The winding ... is wound inward"
