"""The point-cloud page (/points) without a browser: the form, the report, its JSON twin, errors."""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.points.figures import VIEW_NORMALS, VIEW_POINTS, voxel_sample
from mesh_normal.points.io.write import write_points
from tests.conftest import Page


def cylinder_xyz(rings: int = 8, around: int = 36) -> bytes:
    """Points of a cylinder of radius 1 and height 1.4 as XYZ text."""
    angles = np.linspace(0, 2 * np.pi, around, endpoint=False)
    rows = [(np.cos(a), np.sin(a), z) for z in np.linspace(0, 1.4, rings) for a in angles.tolist()]
    return "".join(f"{x:.9f} {y:.9f} {z:.9f}\n" for x, y, z in rows).encode()


def post(
    client: TestClient,
    data: bytes,
    name: str = "cylinder.xyz",
    status: int = 200,
    part: str | None = None,
    **fields: str,
) -> tuple[Any, Page]:
    response = client.post(
        "/points",
        params={"part": part} if part else None,
        files={"file": (name, data)},
        data=fields,
    )
    assert response.status_code == status, response.text[:800]
    assert response.headers["content-type"] == "text/html; charset=utf-8"
    return response, Page(response.text)


def json_block(html: Page, element_id: str):  # type: ignore[no-untyped-def]
    found = [content for attrs, content in html.scripts if attrs.get("id") == element_id]
    assert len(found) == 1, element_id
    return json.loads(found[0], parse_constant=lambda name: pytest.fail(f"{name} in the page"))


def test_form_posts_the_file_and_options_without_javascript(client: TestClient) -> None:
    response = client.get("/points")
    assert response.status_code == 200
    assert response.template.name == "points.html"
    assert response.context["report"] is None
    html = Page(response.text)
    form = html.one("form", id="points-form")
    assert (form["method"], form["action"], form["enctype"]) == (
        "post",
        "/points",
        "multipart/form-data",
    )
    field = html.one("input", id="points-file")
    assert (field["type"], field["name"]) == ("file", "file")
    assert ".xyz" in (field["accept"] or "") and ".pcd" in (field["accept"] or "")
    assert html.one("input", id="points-k")["name"] == "k"
    assert html.one("input", id="points-radius")["name"] == "radius"
    orient = html.one("select", id="points-orient")
    assert orient["name"] == "orient"
    options = [attrs.get("value") for tag, attrs in html.elements if tag == "option"]
    assert options == ["mst", "riemannian", "viewpoint", "direction", "file", "none"]
    assert html.one("progress", id="points-progress") is not None
    assert html.find("a", href="/points"), "the site's navigation links to the page"
    scripts = [attrs.get("src") or "" for attrs, _ in html.scripts]
    assert all(src.startswith("/static/") for src in scripts), scripts
    assert not any("gl3d" in src for src in scripts), "the 3D bundle loads only when needed"


def test_a_small_cloud_renders_the_report_and_its_json_twin(client: TestClient) -> None:
    data = cylinder_xyz()
    response, html = post(client, data, k="12")
    context = response.context
    report = context["report"]
    assert report.points == 8 * 36
    assert report.neighbourhood.k == 12
    assert "points-diagnosis" in response.text
    for sentence in report.diagnosis:
        assert sentence in response.text or sentence.replace("'", "&#39;") in response.text
    # The JSON twin is the API's answer to the same file and options, and the page links it.
    twin = json_block(html, "points-report")
    api = client.post("/api/points", params={"k": 12}, files={"file": ("cylinder.xyz", data)})
    assert twin == api.json()
    assert (
        response.headers["link"] == '</api/points?k=12>; rel="alternate"; type="application/json"'
    )
    assert html.one("link", rel="alternate")["href"] == "/api/points?k=12"
    assert html.one("a", id="points-json-link")["href"] == "/api/points?k=12"
    # The 3D view has every point (a small cloud) and, fewer than VIEW_NORMALS, a stroke for
    # each with a normal; the light's shading for each up axis, the camera for each too.
    view = json_block(html, "points-view-data")
    points, strokes = view["figure"]["data"]
    assert len(points["x"]) == report.points
    assert strokes["name"] == "normals" and len(strokes["x"]) == 3 * report.with_normal
    assert set(view["colors"]) == {"light", "curvature"}
    assert set(view["colors"]["light"]) == set(view["cameras"]) == {"x", "y", "z"}
    assert len(view["colors"]["curvature"]["color"]) == report.points
    assert view["up"] == "z" and points["marker"] == view["colors"]["light"]["z"]
    assert view["figure"]["layout"]["scene"]["camera"] == view["cameras"]["z"]
    up = html.one("select", id="points-up")
    assert up["aria-controls"] == "points-view"
    selected = [a.get("value") for t, a in html.elements if t == "option" and "selected" in a]
    assert "z" in selected
    assert html.one("input", id="points-strokes")["type"] == "checkbox"
    # Nothing was found: the diagnosis reads as a success, without a badge.
    diagnosis = html.one("div", id="points-diagnosis")
    assert diagnosis["class"] == "message ok" and diagnosis["data-verdict"] == "ok"
    assert json_block(html, "points-histogram-data")["data"][0]["type"] == "bar"
    buttons = {attrs.get("data-points-download") for tag, attrs in html.elements if tag == "button"}
    assert {"ply", "xyz", "csv", "npy", "json"} <= buttons


def test_the_fragment_is_the_report_alone(client: TestClient) -> None:
    response, html = post(client, cylinder_xyz(), part="report")
    assert "<html" not in response.text
    assert json_block(html, "points-report")["points"] == 8 * 36


def test_options_reach_the_report_and_the_twin_query(client: TestClient) -> None:
    response, html = post(
        client, cylinder_xyz(), orient="direction", direction="0,0,1", viewpoint="1,2,3"
    )
    report = response.context["report"]
    assert report.orientation.mode == "direction"
    assert report.orientation.direction == [0.0, 0.0, 1.0]
    assert (
        html.one("div", id="points-report-view")["data-query"]
        == "orient=direction&direction=0%2C0%2C1"
    )


def test_a_broken_file_shows_the_sentence_with_a_4xx(client: TestClient) -> None:
    response, html = post(client, b"ply\nformat nonsense\n", name="broken.ply", status=400)
    assert response.context["error"] is not None
    assert html.one("section", id="points-error")
    assert "could not be analysed" in response.text
    assert not html.find("script", type="application/json", id="points-report")


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"k": "2"}, "k must be a whole number from 3 to 1000"),
        ({"k": "many"}, "k must be a whole number"),
        ({"radius": "-1"}, "radius must be a positive number"),
        ({"orient": "sideways"}, "orient must be one of"),
        ({"orient": "direction"}, "direction is needed"),
        ({"orient": "viewpoint", "viewpoint": "1,2"}, "viewpoint must be three finite numbers"),
    ],
)
def test_bad_options_are_a_422_page(client: TestClient, fields: dict[str, str], words: str) -> None:
    response, _ = post(client, cylinder_xyz(), status=422, **fields)
    assert words in response.text
    assert response.context["error"].status_code == 422


def test_a_post_without_a_file_is_a_422_page(client: TestClient) -> None:
    response = client.post("/points", data={"k": "30"}, files={"other": ("a.txt", b"x")})
    assert response.status_code == 422
    assert "file is missing" in response.text


def test_voxel_sample_spreads_over_a_cloud_with_a_dense_patch() -> None:
    rng = np.random.default_rng(7)
    sparse = rng.uniform(0, 1, (3000, 3))
    dense = rng.uniform(0, 0.05, (30000, 3))  # a tiny corner holds 10x the points
    points = np.concatenate([dense, sparse])
    chosen = voxel_sample(points, limit=2000)
    assert len(chosen) <= 2000 and len(chosen) > 1000
    assert np.all(np.diff(chosen) > 0)
    # Under a tenth of the sample sits in the dense corner, which holds 91 % of the points.
    assert np.mean(chosen < len(dense)) < 0.1


def test_voxel_sample_skips_points_that_are_not_finite() -> None:
    points = np.array([[0.0, 0, 0], [np.nan, 0, 0], [1, 1, 1]])
    assert voxel_sample(points, limit=10).tolist() == [0, 2]


def test_stored_normals_get_the_angle_histogram_and_a_sentence(client: TestClient) -> None:
    angles = np.linspace(0, 2 * np.pi, 36, endpoint=False)
    points = np.array(
        [(np.cos(a), np.sin(a), z) for z in np.linspace(0, 1.4, 8) for a in angles.tolist()]
    )
    stored = points * [1.0, 1.0, 0.0]  # the cylinder's outward normals
    data = write_points(points, stored, "ply")
    response, html = post(client, data, name="cylinder.ply")
    context = response.context
    assert context["histogram"]["what"] == "angle to the stored normals (degrees)"
    assert context["histogram"]["count"] == len(points)
    stored_text = html.text("points-stored")
    assert f"{len(points)} of {len(points)} agree with ours" in stored_text


def test_a_large_cloud_is_drawn_as_a_capped_even_sample(client: TestClient) -> None:
    rng = np.random.default_rng(3)
    points = rng.uniform(0, 1, (24_000, 3)) * [1.0, 1.0, 0.01]  # a thin slab
    data = "".join(f"{x:.7f} {y:.7f} {z:.7f}\n" for x, y, z in points.tolist()).encode()
    response, html = post(client, data, name="slab.xyz", k="10")
    view = response.context["view"]
    assert view["total"] == 24_000
    assert view["shown"] <= VIEW_POINTS and view["strokes"] <= VIEW_NORMALS
    assert "an even sample" in html.text("points-view-caption")
    figure = json_block(html, "points-view-data")["figure"]
    assert len(figure["data"][0]["x"]) == view["shown"]
    assert len(figure["data"][1]["x"]) == 3 * view["strokes"]


@pytest.mark.parametrize(
    ("fields", "shown"),
    [
        ({}, "Neighbourhood chosen per point"),
        ({"k": "12"}, "Neighbourhood k = 12"),
        ({"radius": "0.5"}, "Neighbourhood within 0.5"),
        ({"k": "12", "radius": "0.5"}, "Neighbourhood k = 12, within 0.5"),
    ],
)
def test_the_report_says_which_neighbourhood(
    client: TestClient, fields: dict[str, str], shown: str
) -> None:
    response, _ = post(client, cylinder_xyz(), **fields)
    assert shown in " ".join(re.sub(r"<[^>]+>", " ", response.text).split())
