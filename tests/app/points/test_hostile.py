"""Hostile point clouds through the API: each answered within seconds, a bomb with a
413 that names what expanded, a pile of coincident points with a report."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from app.config import Settings
from app.main import create_app
from tests.conftest import assert_error
from tests.mesh_normal.points._hostile import (
    HOSTILE_POINTS,
    coincident_xyz,
    las_count,
    las_points,
    lzf_bomb_pcd,
)
from tests.paths import ROOT

HOSTILE = ROOT / "tests" / "data" / "hostile"
#: Generous: unguarded, each case takes a minute or more, or gigabytes.
SECONDS = 10.0


@pytest.fixture(scope="module")
def local() -> Iterator[TestClient]:
    app = create_app(settings=Settings(in_process=True))
    with TestClient(app, raise_server_exceptions=False) as client:
        yield client


def post(client: TestClient, data: bytes, name: str, path: str = "/api/points"):  # type: ignore[no-untyped-def]
    began = time.monotonic()
    response = client.post(path, files={"file": (name, data)})
    assert time.monotonic() - began < SECONDS
    return response


def test_an_lzf_pcd_of_3_million_points_is_a_413(local: TestClient) -> None:
    response = post(local, lzf_bomb_pcd(3_000_000, 4, "F"), "bomb.pcd")
    assert_error(
        response, 413, "file", "expands too far", "the PCD file's LZF data, 3,000,000 points"
    )


def test_200_000_identical_points_are_reported(local: TestClient) -> None:
    data = coincident_xyz(200_000)
    assert len(data) == 1_200_000
    response = post(local, data, "same.xyz")
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["counts"]["duplicates"] == 200_000 and report["with_normal"] == 0
    assert "each gets the normal of its place" in report["diagnosis"][0]


def test_200_000_identical_points_get_zero_normals(local: TestClient) -> None:
    response = post(local, coincident_xyz(200_000), "same.xyz", "/api/points/normals?format=xyz")
    assert response.status_code == 200, response.text
    assert set(response.content.splitlines()) == {b"# x y z nx ny nz", b"0.0 0.0 0.0 0.0 0.0 0.0"}


def test_lying_las_headers(local: TestClient) -> None:
    short = post(local, las_count(las_points(), 1000), "short.las")
    assert_error(short, 400, "file", "says 1,000 points", "only 4")
    zero = post(local, las_points(scale=0.0), "zero.las")
    assert_error(zero, 400, "file", "x scale is 0")
    long = post(local, las_count(las_points(1000), 10), "long.las")
    assert long.status_code == 200, long.text
    assert long.json()["points"] == 10
    assert any("room for 1,000" in note for note in long.json()["file"]["notes"])


@pytest.mark.parametrize("name", sorted(HOSTILE_POINTS))
def test_the_stored_hostile_files(local: TestClient, name: str) -> None:
    _, status, words = HOSTILE_POINTS[name]
    response = post(local, (HOSTILE / name).read_bytes(), name)
    if status == 200:
        assert response.status_code == 200, response.text
        report = response.json()
        assert words in " ".join([*report["file"]["notes"], *report["diagnosis"]])
    else:
        assert_error(response, status, "file", words)
