"""The optional group fields of :class:`LoadedMesh`, as :func:`build` checks them."""

from __future__ import annotations

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
