"""POST /api/points and /api/points/normals: reports, normals in each format, and errors."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.points.api import POINT_FILE_SUFFIXES
from mesh_normal.points import read_points
from tests.conftest import assert_error
from tests.mesh_normal.points._pcd import pcd_header

#: A 6 x 6 grid in the plane z = 0, 0.5 apart, as XYZ text.
GRID = np.array([[0.5 * i, 0.5 * j, 0.0] for j in range(6) for i in range(6)])
GRID_XYZ = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in GRID.tolist())


def post(client: TestClient, path: str, data: str | bytes, name: str = "plane.xyz", **params: str):  # type: ignore[no-untyped-def]
    body = data.encode() if isinstance(data, str) else data
    return client.post(path, params=params, files={"file": (name, body)})


def test_report_of_a_plane(client: TestClient) -> None:
    response = post(client, "/api/points", GRID_XYZ)
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["file"]["name"] == "plane.xyz" and report["file"]["format"] == "xyz"
    assert report["file"]["bytes"] == len(GRID_XYZ)
    assert report["points"] == 36 and report["counts"]["ok"] == 36
    assert report["spacing"]["median"] == 0.5
    assert report["neighbourhood"] == {"k": None, "radius": None}
    assert report["orientation"]["mode"] == "mst"
    assert report["diagnosis"] == ["Every point has a normal, oriented as asked."]


def test_raw_body_with_filename_and_options(client: TestClient) -> None:
    response = client.post(
        "/api/points",
        params={
            "filename": "plane.xyz",
            "k": "8",
            "radius": "0.8",
            "orient": "direction",
            "direction": "0,0,-1",
        },
        content=GRID_XYZ.encode(),
        headers={"content-type": "application/octet-stream"},
    )
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["neighbourhood"] == {"k": 8, "radius": 0.8}
    assert report["orientation"]["direction"] == [0.0, 0.0, -1.0]
    assert report["orientation"]["flipped"] == 36


def test_pcd_viewpoint_is_used(client: TestClient) -> None:
    body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in GRID.tolist())
    pcd = pcd_header("x y z", "4 4 4", "F F F", 36, viewpoint="1 1 -3 1 0 0 0") + body.encode()
    response = post(client, "/api/points/normals", pcd, "scan.pcd", orient="viewpoint")
    assert response.status_code == 200, response.text
    assert response.json()["normals"] == [[0.0, 0.0, -1.0]] * 36


def test_a_pcds_nan_rows_are_zero_rows_in_the_files_order(client: TestClient) -> None:
    """PCL marks missing points with NaN: the reader leaves them out, the normals keep a row
    for each of the file's rows (as the command line writes them), zero and counted."""
    rows = [f"{x!r} {y!r} {z!r}" for x, y, z in GRID.tolist()]
    rows.insert(7, "nan nan nan")
    pcd = pcd_header("x y z", "4 4 4", "F F F", 37) + ("\n".join(rows) + "\n").encode()
    response = post(client, "/api/points/normals", pcd, "scan.pcd", format="npy")
    assert response.status_code == 200, response.text
    normals = np.load(io.BytesIO(response.content))
    assert normals.shape == (37, 3)
    assert normals[7].tolist() == [0.0, 0.0, 0.0]
    np.testing.assert_allclose(np.abs(np.delete(normals, 7, axis=0)[:, 2]), 1.0)
    assert response.headers["x-points-without-normal"] == "1"


@pytest.mark.parametrize("file_format", ["json", "csv", "npy", "ply", "xyz"])
def test_normals_in_each_format(client: TestClient, file_format: str) -> None:
    # Two far points: isolated within the radius, so no normal; zeros and a header say so.
    cloud = GRID_XYZ + "50 50 50\n60 60 60\n"
    response = post(client, "/api/points/normals", cloud, radius="0.8", format=file_format)
    assert response.status_code == 200, response.text
    assert response.headers["x-points-without-normal"] == "2"
    assert f'filename="plane-normals.{file_format}"' in response.headers["content-disposition"]
    expected = np.vstack([np.tile([0.0, 0.0, 1.0], (36, 1)), np.zeros((2, 3))])
    if file_format == "json":
        body = response.json()
        assert body["shape"] == [38, 3] and body["missing_indices"] == [36, 37]
        np.testing.assert_array_equal(body["normals"], expected)
    elif file_format == "csv":
        table = np.loadtxt(io.StringIO(response.text), delimiter=",", skiprows=1)
        assert response.text.startswith("point,nx,ny,nz\n")
        np.testing.assert_array_equal(table[:, 0], np.arange(38))
        np.testing.assert_array_equal(table[:, 1:], expected)
    elif file_format == "npy":
        np.testing.assert_array_equal(np.load(io.BytesIO(response.content)), expected)
    else:
        back = read_points(response.content, f"back.{file_format}")
        np.testing.assert_array_equal(back.points[:36], GRID)
        assert back.normals is not None
        np.testing.assert_array_equal(back.normals, expected)


def test_orient_file_uses_the_stored_normals(client: TestClient) -> None:
    rows = "".join(f"{x!r} {y!r} {z!r} 0 0 -1\n" for x, y, z in GRID.tolist())
    text = "# x y z nx ny nz\n" + rows
    response = post(client, "/api/points", text, orient="file")
    assert response.status_code == 200, response.text
    stored = response.json()["stored_normals"]
    assert stored["compared"] == 36 and stored["same_side_fraction"] == 1.0


def test_a_mesh_file_is_read_as_its_vertices(client: TestClient) -> None:
    obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n"
    response = post(client, "/api/points", obj, "quad.obj")
    assert response.status_code == 200, response.text
    assert response.json()["file"]["source_kind"] == "mesh vertices"


@pytest.mark.parametrize(
    ("params", "field", "words"),
    [
        ({"k": "2"}, "k", ("k",)),
        ({"k": "many"}, "k", ("k",)),
        ({"radius": "0"}, "radius", ("radius",)),
        ({"radius": "inf"}, "radius", ("radius",)),
        ({"orient": "outward"}, "orient", ("orient",)),
        ({"orient": "viewpoint", "viewpoint": "1,2"}, "viewpoint", ("x,y,z",)),
        ({"orient": "viewpoint", "viewpoint": "1,2,nan"}, "viewpoint", ("x,y,z",)),
        ({"viewpoint": "1,2,3"}, "viewpoint", ("only used with orient=viewpoint",)),
        ({"orient": "direction"}, "direction", ("needed",)),
        ({"orient": "direction", "direction": "0,0,0"}, "direction", ("zero",)),
        ({"direction": "0,0,1"}, "direction", ("only used",)),
        ({"orient": "viewpoint"}, "viewpoint", ("the file has none",)),
        ({"orient": "file"}, "orient", ("normals stored in the file",)),
    ],
)
def test_bad_options_are_one_sentence(
    client: TestClient, params: dict[str, str], field: str, words: tuple[str, ...]
) -> None:
    assert_error(post(client, "/api/points", GRID_XYZ, **params), 422, field, *words)


def test_unknown_format_is_refused(client: TestClient) -> None:
    response = post(client, "/api/points/normals", GRID_XYZ, format="las")
    assert_error(response, 422, "format")


def test_broken_files_name_the_file(client: TestClient) -> None:
    assert_error(post(client, "/api/points", "ply\nformat nonsense\n", "a.ply"), 400, "file")
    assert_error(post(client, "/api/points", "0 0 0\n", "a.docx"), 415, "file", ".docx")
    assert_error(post(client, "/api/points", "0 0 0\n", "a.zip"), 415, "file", ".zip")
    assert_error(post(client, "/api/points", b"", "a.xyz"), 422, "file", "empty")
    assert_error(
        client.post("/api/points", content=b"", headers={"content-type": "text/plain"}),
        422,
        "file",
        "point cloud",
    )
    many = [("file", ("a.xyz", GRID_XYZ.encode())), ("file", ("b.xyz", GRID_XYZ.encode()))]
    assert_error(client.post("/api/points", files=many), 422, "file", "one point cloud")


def test_accepted_suffixes() -> None:
    for suffix in (".ply", ".xyz", ".pts", ".txt", ".csv", ".pcd", ".las", ".laz", ".stl", ".obj"):
        assert suffix in POINT_FILE_SUFFIXES
    assert ".zip" not in POINT_FILE_SUFFIXES  # the point reader opens no archive


def test_the_report_is_documented(client: TestClient) -> None:
    schema = client.get("/openapi.json").json()
    assert "PointReport" in json.dumps(schema["paths"]["/api/points"]["post"])
    assert "/api/points/normals" in schema["paths"]


def test_a_cloud_larger_than_the_small_body_limit_is_read(client: TestClient) -> None:
    # 20,000 points of a plane as text: over 64 KB, the limit of bodies that are not files.
    x, y = np.meshgrid(np.arange(200.0), np.arange(100.0))
    text = "".join(f"{a:g} {b:g} 0\n" for a, b in zip(x.ravel(), y.ravel(), strict=True))
    assert len(text) > 64 * 1024
    response = post(client, "/api/points", text, k="8")
    assert response.status_code == 200, response.text
    assert response.json()["counts"]["ok"] == 20_000


def test_beyond_the_upload_limit_is_a_413() -> None:
    from app.main import create_app

    with TestClient(create_app(upload_limit=1000), raise_server_exceptions=False) as small:
        response = post(small, "/api/points", GRID_XYZ * 10)
    assert_error(response, 413, None, "larger than")
