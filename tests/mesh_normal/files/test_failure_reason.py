"""A reader's own exception becomes our words: never Python's words about the reader."""

from __future__ import annotations

import json
import zipfile

import pytest

from mesh_normal.files.errors import MeshFileError, failure_reason
from mesh_normal.files.read import read_mesh
from mesh_normal.points.io.read import read_points

PRIMITIVE = {"attributes": {"POSITION": 0}}


def gltf(document: dict) -> bytes:  # type: ignore[type-arg]
    return json.dumps({"asset": {"version": "2.0"}, **document}).encode()


@pytest.mark.parametrize(
    ("data", "name", "words"),
    [
        (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999999999999999\n", "a.off", "too large"),
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


STRUCTURE = "its structure is not what the format requires"


@pytest.mark.parametrize(
    ("error", "reason"),
    [
        (AssertionError(), STRUCTURE),
        (AssertionError("byteStride should be positive"), STRUCTURE),
        (ValueError(""), STRUCTURE),
        (ValueError("ValueError"), STRUCTURE),
        (
            ValueError(f"Bad entry {zipfile.ZipInfo('a.obj')!r}."),
            "Bad entry an entry",
        ),
    ],
)
def test_assertions_empty_messages_and_reprs_become_words(error: Exception, reason: str) -> None:
    assert failure_reason(error) == reason


def test_pythons_hint_for_too_many_digits_becomes_words() -> None:
    with pytest.raises(ValueError, match="digits") as raised:
        int("7" * 5000)
    assert failure_reason(raised.value) == "a number in it has too many digits"


DIGITS = "7" * 5000
PLY_FACE = (
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n"
)


@pytest.mark.parametrize(
    ("text", "name", "sentence"),
    [
        (
            f"OFF\n{DIGITS} 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
            "a.off",
            "Line 2: the OFF counts line must start with the number of vertices and of faces.",
        ),
        (f"{PLY_FACE}{DIGITS} 0 1 2\n", "a.ply", "where a list length should be."),
        (f"{PLY_FACE}3 0 1 {DIGITS}\n", "a.ply", "a face index too large to name a vertex."),
        (
            json.dumps({"asset": {"version": "2.0"}})[:-1] + f', "count": {DIGITS}}}',
            "a.gltf",
            "The glTF JSON could not be parsed: a number in it has too many digits.",
        ),
    ],
)
def test_a_number_of_thousands_of_digits_is_named(text: str, name: str, sentence: str) -> None:
    with pytest.raises(MeshFileError) as raised:
        read_mesh(text.encode(), name)
    assert str(raised.value).endswith(sentence)
    assert "set_int_max_str_digits" not in str(raised.value)


def test_a_point_cloud_number_of_thousands_of_digits_is_worded() -> None:
    pcd = (
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        f"WIDTH 3\nHEIGHT 1\nPOINTS {DIGITS}\nDATA ascii\n0 0 0\n1 0 0\n0 1 0\n"
    )
    with pytest.raises(MeshFileError) as raised:
        read_points(pcd.encode(), "a.pcd")
    assert "set_int_max_str_digits" not in str(raised.value)
    assert "too many digits" in str(raised.value)
