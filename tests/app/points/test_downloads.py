"""The streamed normals: the blocks join into one valid file, whatever the block size."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from app.points.downloads import normals_blocks

NORMALS = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.1, 0.2, 0.3]])
MISSING = np.array([False, True, False, False])


@pytest.mark.parametrize("rows", [1, 2, 3, 4, 100])
def test_json_blocks_join_into_one_document(rows: int) -> None:
    text = b"".join(normals_blocks(NORMALS, MISSING, "mst", "json", rows))
    body = json.loads(text)
    assert body == {
        "orient": "mst",
        "shape": [4, 3],
        "missing": 1,
        "missing_indices": [1],
        "normals": NORMALS.tolist(),
    }


@pytest.mark.parametrize("rows", [1, 3, 100])
def test_csv_blocks_round_trip(rows: int) -> None:
    text = b"".join(normals_blocks(NORMALS, MISSING, "mst", "csv", rows)).decode()
    assert text.startswith("point,nx,ny,nz\n0,0,0,1\n1,0,0,0\n")
    table = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, 1:], NORMALS)  # 17 digits: exact


def test_npy_is_float64_in_order() -> None:
    data = b"".join(normals_blocks(NORMALS, MISSING, "mst", "npy"))
    back = np.load(io.BytesIO(data))
    assert back.dtype == np.float64
    np.testing.assert_array_equal(back, NORMALS)


def test_an_empty_cloud_is_still_valid_json() -> None:
    empty = np.zeros((0, 3))
    body = json.loads(b"".join(normals_blocks(empty, np.zeros(0, bool), "none", "json")))
    assert body["normals"] == [] and body["shape"] == [0, 3]
