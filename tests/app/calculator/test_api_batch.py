"""POST /api/normals: up to 100,000 triangles, in input order, agreeing with POST /api/normal."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from tests.conftest import assert_error
from tests.paths import ROOT

ITEM_KEYS = {"normal", "unit_normal", "magnitude", "area", "degenerate"}
JSON = {"content-type": "application/json"}
LIMIT = 100_000

#: Ordinary, swapped-sign, degenerate, sliver, tiny and huge triangles, in one batch.
MIXED = [
    [[1, 0, 0], [0, 2, 0], [0, 0, 3]],
    [[0, 0, 0], [0, 1, 0], [1, 0, 0]],
    [[0, 0, 0], [1, 1, 1], [2, 2, 2]],
    [[5, 5, 5], [5, 5, 5], [5, 5, 5]],
    [[0, 0, 0], [1 + 2**-52, 1, 0], [1, 1 - 2**-53, 0]],
    [[0, 0, 0], [1e-200, 0, 0], [0, 1e-200, 0]],
    [[0, 0, 0], [1e200, 0, 0], [0, 1e200, 0]],
    [[0.1, 0.2, 0.3], [-1.5, 2.25, 1e-3], [7e5, -3e-4, 12.5]],
    [[0, 0, 0], [0, 1 + 2**-52, 1], [1, 1, 1 - 2**-53]],  # n_x is 2**-53 - 2**-105, not 0
]


def post_batch(client, triangles, swap: bool = False):  # type: ignore[no-untyped-def]
    response = client.post("/api/normals", json={"triangles": triangles, "swap_winding": swap})
    assert response.status_code == 200, response.text
    assert "NaN" not in response.text and "Infinity" not in response.text
    return response.json()["results"]


def single(client, triangle, swap: bool = False):  # type: ignore[no-untyped-def]
    a, b, c = triangle
    response = client.post("/api/normal", json={"a": a, "b": b, "c": c, "swap_winding": swap})
    assert response.status_code == 200, response.text
    return response.json()


def assert_agrees(item: dict, exact: dict) -> None:
    """A batch row against the exact single-triangle answer (triangle_batch's precision)."""
    assert set(item) == ITEM_KEYS
    assert item["degenerate"] is exact["degenerate"]
    for key in ("magnitude", "area"):
        assert (item[key] is None) is (exact[key] is None)
    assert [x is None for x in item["normal"]] == [x is None for x in exact["normal"]]
    if exact["degenerate"]:
        assert item == {key: exact[key] for key in ITEM_KEYS}
        return
    if exact["magnitude"] is None:  # out of range: the batch takes the exact row as is
        assert item == {key: exact[key] for key in ITEM_KEYS}
        return
    assert math.isclose(item["magnitude"], exact["magnitude"], rel_tol=2**-26)
    assert math.isclose(item["area"], exact["area"], rel_tol=2**-26)
    for got, want in zip(item["normal"], exact["normal"], strict=True):
        assert abs(got - want) <= exact["magnitude"] * 2**-26
    for got, want in zip(item["unit_normal"], exact["unit_normal"], strict=True):
        assert abs(got - want) <= 3e-8


@pytest.mark.parametrize("swap", [False, True])
def test_batch_agrees_with_the_single_endpoint(client, swap: bool) -> None:  # type: ignore[no-untyped-def]
    results = post_batch(client, MIXED, swap)
    assert len(results) == len(MIXED)
    for item, triangle in zip(results, MIXED, strict=True):
        assert_agrees(item, single(client, triangle, swap))


@pytest.mark.parametrize("swap", [False, True])
def test_every_sign_matches_the_single_endpoint(client, swap: bool) -> None:  # type: ignore[no-untyped-def]
    """triangle_batch.py promises the sign of every component (zeros included) is the exact one."""
    results = post_batch(client, MIXED, swap)
    for item, triangle in zip(results, MIXED, strict=True):
        exact = single(client, triangle, swap)
        signs = [None if x is None else np.sign(x) for x in exact["normal"]]
        assert [None if x is None else np.sign(x) for x in item["normal"]] == signs, triangle


def test_batch_keeps_input_order(client) -> None:  # type: ignore[no-untyped-def]
    # Triangle i has normal (0, 0, i + 1): the order is visible in every row.
    triangles = [[[0, 0, 0], [1, 0, 0], [0, i + 1, 0]] for i in range(50)]
    results = post_batch(client, triangles)
    assert [item["normal"] for item in results] == [[0.0, 0.0, i + 1.0] for i in range(50)]
    assert [item["area"] for item in results] == [(i + 1) / 2 for i in range(50)]


def test_exact_rows_are_exact(client) -> None:  # type: ignore[no-untyped-def]
    results = post_batch(client, MIXED)
    sliver, tiny, huge = results[4], results[5], results[6]
    assert [float.hex(x) for x in sliver["normal"]] == [
        float.hex(0.0),
        float.hex(0.0),
        float.hex(2**-53 - 2**-105),
    ]
    assert sliver["unit_normal"] == [0.0, 0.0, 1.0]
    assert tiny == {
        "normal": [0.0, 0.0, None],
        "unit_normal": [0.0, 0.0, 1.0],
        "magnitude": None,
        "area": None,
        "degenerate": False,
    }
    assert huge == tiny
    assert results[2]["degenerate"] is True and results[2]["unit_normal"] is None
    assert results[3]["degenerate"] is True and results[3]["normal"] == [0.0, 0.0, 0.0]


def test_empty_batch(client) -> None:  # type: ignore[no-untyped-def]
    assert post_batch(client, []) == []


def full_batch(count: int) -> tuple[np.ndarray, bytes]:
    """``count`` small-integer triangles (a compact body) with some degenerate rows."""
    rng = np.random.default_rng(20240601)
    triangles = rng.integers(-9, 10, size=(count, 3, 3))
    triangles[::1000, 2] = triangles[::1000, 1]  # B == C: degenerate
    text = json.dumps({"triangles": triangles.tolist()}, separators=(",", ":"))
    return triangles, text.encode()


def test_exactly_the_limit_works(client) -> None:  # type: ignore[no-untyped-def]
    triangles, body = full_batch(LIMIT)
    response = client.post("/api/normals", content=body, headers=JSON)
    assert response.status_code == 200, response.text[:300]
    results = response.json()["results"]
    assert len(results) == LIMIT
    # Spot-check against numpy's cross product: small integers make it exact.
    u = triangles[:, 1] - triangles[:, 0]
    v = triangles[:, 2] - triangles[:, 0]
    normals = np.cross(u, v)
    degenerate = ~normals.any(axis=1)
    assert [item["degenerate"] for item in results] == degenerate.tolist()
    assert degenerate[::1000].all()
    for row in range(0, LIMIT, 997):
        assert results[row]["normal"] == normals[row].astype(float).tolist(), row
    assert results[-1]["normal"] == normals[-1].astype(float).tolist()


def test_one_over_the_limit_is_413(client) -> None:  # type: ignore[no-untyped-def]
    _, body = full_batch(LIMIT + 1)
    response = client.post("/api/normals", content=body, headers=JSON)
    assert_error(response, 413, "triangles", "100,000", "100,001")


#: A child that serves one 49 MB batch of 1.9 million triangles under an address-space limit of
#: 1 GB above what its imports took: parsing it whole (about 3.3 GB) cannot fit.
_HUGE_BATCH_CHILD = """
import resource, sys, warnings
warnings.simplefilter("ignore")
from fastapi.testclient import TestClient
from app.main import create_app
body = b'{"triangles": [' + b",".join([b"[[0,0,0],[1,0,0],[0,1,0]]"] * 1_900_000) + b"]}"
with TestClient(create_app(), raise_server_exceptions=False) as client:
    client.get("/api/normal?ax=0&ay=0&az=0&bx=1&by=0&bz=0&cx=0&cy=1&cz=0")
    size = int(open("/proc/self/statm").read().split()[0]) * resource.getpagesize()
    resource.setrlimit(resource.RLIMIT_AS, (size + 2**30, resource.RLIM_INFINITY))
    response = client.post(
        "/api/normals", content=body, headers={"content-type": "application/json"}
    )
print(len(body), response.status_code, response.json()["error"])
"""


def test_a_huge_batch_is_refused_before_it_is_parsed() -> None:
    done = subprocess.run(
        [sys.executable, "-c", _HUGE_BATCH_CHILD],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    size, status, sentence = done.stdout.strip().split(" ", 2)
    assert int(size) > 49_000_000 and status == "413", done.stdout
    assert "at most 100,000 triangles" in sentence and "1,900,000" in sentence


def test_brackets_in_a_string_are_not_triangles(client) -> None:  # type: ignore[no-untyped-def]
    body = json.dumps({"triangles": [MIXED[0]], "swap_winding": '\\"[' * (4 * LIMIT)})
    response = client.post("/api/normals", content=body, headers=JSON)
    assert_error(response, 422, "swap_winding")
