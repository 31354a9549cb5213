"""mesh_normal/files/normals.py: a file of normals written a block at a time is the file of the
whole array, byte for byte, for every kind and format."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mesh_normal.files import LoadedMesh, read_mesh
from mesh_normal.files.normals import (
    FORMATS,
    KINDS,
    NormalsFormat,
    NormalsKind,
    compute_normals,
    normals_blocks,
    normals_file,
    normals_to_write,
)
from tests.paths import DATA


def nut() -> LoadedMesh:
    """Flat sides, chamfers and sharp rims: creased corners and smooth ones."""
    return read_mesh((DATA / "nut.ply").read_bytes(), "nut.ply")


@pytest.mark.parametrize("file_format", FORMATS)
@pytest.mark.parametrize("kind", KINDS)
def test_normals_written_in_blocks_are_the_whole_file(
    kind: NormalsKind, file_format: NormalsFormat
) -> None:
    mesh = nut()
    values, missing = compute_normals(mesh, kind, "angle", 20.0)
    whole = normals_file(values, missing, kind, "angle", 20.0, file_format)
    source, mask = normals_to_write(mesh, kind, "angle", 20.0)
    assert np.array_equal(mask, missing)
    # 7 rows a block: every block boundary falls inside the mesh, the last block short.
    assert len(values) % 7
    pieces = list(normals_blocks(source, mask, kind, "angle", 20.0, file_format, rows=7))
    assert len(pieces) > len(values) // 7
    assert b"".join(pieces) == whole


def test_corner_normals_made_in_blocks_are_the_array() -> None:
    mesh = nut()
    values, _ = compute_normals(mesh, "corner", "angle", 20.0)
    source, mask = normals_to_write(mesh, "corner", "angle", 20.0)
    text = b"".join(normals_blocks(source, mask, "corner", "angle", 20.0, "json", rows=5))
    found = json.loads(text)
    assert found["shape"] == [len(mesh.faces), 3, 3]
    assert np.array_equal(np.array(found["normals"]), values)
