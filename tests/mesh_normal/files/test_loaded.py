"""The optional group fields of :class:`LoadedMesh`, as :func:`build` checks them."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mesh_normal.files.loaded import build
from tests.meshes import TETRA_FACES, TETRA_VERTICES


def test_groups_are_frozen_beside_the_faces() -> None:
    mesh = build(
        "obj",
        TETRA_VERTICES,
        TETRA_FACES,
        source_faces=4,
        face_groups=np.array([0, 0, 1, 1]),
        group_names=["a", "b"],
    )
    assert mesh.group_names == ("a", "b")
    assert mesh.face_groups is not None and mesh.face_groups.dtype == np.intp
    with pytest.raises(ValueError, match="read-only"):
        mesh.face_groups[0] = 1
    plain = build("obj", TETRA_VERTICES, TETRA_FACES, source_faces=4)
    assert plain.face_groups is None and plain.group_names is None


@pytest.mark.parametrize(
    ("groups", "names"),
    [([0, 0, 1], ["a", "b"]), ([0, 0, 1, 2], ["a", "b"]), ([0, 0, 0, -1], ["a"]), (None, ["a"])],
)
def test_a_reader_giving_wrong_groups_fails_loudly(
    groups: list[int] | None, names: list[str]
) -> None:
    with pytest.raises(AssertionError):
        build(
            "obj",
            TETRA_VERTICES,
            TETRA_FACES,
            source_faces=4,
            face_groups=None if groups is None else np.array(groups),
            group_names=names,
        )


@pytest.mark.parametrize(
    ("plant", "words"),
    [
        ("nan", "The coordinates of vertex 70,001 (counting from 0) include nan"),
        ("inf", "The coordinates of vertex 70,001 (counting from 0) include -inf"),
        ("negative", "Face 80,001 (counting from 0) refers to vertex -1; vertex indices"),
        ("large", "Face 80,001 (counting from 0) refers to vertex 100,000 (counting from 0)"),
    ],
)
def test_a_large_meshs_checks_on_every_core_say_what_numpys_say(plant: str, words: str) -> None:
    # C-contiguous arrays take one compiled pass on every core (coordinate and index ranges),
    # others NumPy's: the first bad vertex or face, and the sentence, are the same.
    from mesh_normal.files.errors import MeshFileError

    rng = np.random.default_rng(3)
    vertices = rng.normal(size=(100_000, 3))
    faces = rng.integers(0, len(vertices), (100_000, 3))
    if plant in ("nan", "inf"):
        vertices[70_001, 1] = np.nan if plant == "nan" else -np.inf
        vertices[90_000, 2] = np.inf
    else:
        faces[80_001, 2] = -1 if plant == "negative" else 100_000
        faces[90_000, 0] = -5
    for order in (np.ascontiguousarray, np.asfortranarray):
        with pytest.raises(MeshFileError, match=re.escape(words)):
            build("ply", order(vertices), order(faces), source_faces=len(faces))
    fine = build(
        "ply", np.nan_to_num(vertices, posinf=0, neginf=0), faces % 100_000, source_faces=1
    )
    assert len(fine.faces) == 100_000
