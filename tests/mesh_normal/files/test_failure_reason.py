"""A reader's own exception becomes our words: never Python's words about the reader."""

from __future__ import annotations

import json

import pytest

from mesh_normal.files.errors import MeshFileError, failure_reason
from mesh_normal.files.read import read_mesh

PRIMITIVE = {"attributes": {"POSITION": 0}}


def gltf(document: dict) -> bytes:  # type: ignore[type-arg]
    return json.dumps({"asset": {"version": "2.0"}, **document}).encode()


@pytest.mark.parametrize(
    ("data", "name", "words"),
    [
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n", "a.obj", "too large"),
        (gltf({"meshes": [{"primitives": [PRIMITIVE]}], "accessors": [None]}), "a.gltf", "null"),
        (gltf({"meshes": [None]}), "a.gltf", "wrong kind of value"),
        (gltf({"meshes": [{"primitives": [PRIMITIVE]}]}), "a.gltf", "entry that it does not"),
    ],
)
def test_library_internals_do_not_reach_the_sentence(data: bytes, name: str, words: str) -> None:
    with pytest.raises(MeshFileError) as raised:
        read_mesh(data, name)
    sentence = str(raised.value)
    assert sentence.startswith("The file could not be read as ") and sentence.endswith(".")
    assert words in sentence
    for internal in ("NoneType", "C long", "subscriptable", "attribute", "'accessors'"):
        assert internal not in sentence, sentence


def test_other_exceptions_keep_their_words() -> None:
    assert failure_reason(ValueError("Expecting value: line 1 column 1.")) == (
        "Expecting value: line 1 column 1"
    )
    assert failure_reason(ValueError("")) == "ValueError"
