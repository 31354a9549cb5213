"""The mesh page (/mesh) without a browser: the form, the report and its JSON twin, errors, and
the figure builders of app/mesh_view.py."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.mesh import view as mesh_view
from app.mesh.view import (
    BOUNDARY,
    COLORS,
    DEGENERATE,
    FLIPPED,
    NONMANIFOLD,
    OK,
    area_histogram,
    build_view,
    face_classes,
    histogram_figure,
    select_faces,
    view_space,
)
from tests.app.mesh.test_api import CUBE, CUBE_ONE_FLIPPED, OPEN_BOX
from tests.conftest import Page


def post(
    client: TestClient,
    text: str | bytes,
    name: str = "cube.obj",
    part: str | None = None,
    status: int = 200,
):  # type: ignore[no-untyped-def]
    data = text.encode() if isinstance(text, str) else text
    response = client.post(
        "/mesh", params={"part": part} if part else None, files={"file": (name, data)}
    )
    assert response.status_code == status, response.text[:800]
    assert response.headers["content-type"] == "text/html; charset=utf-8"
    return response, Page(response.text)


def json_block(html: Page, element_id: str):  # type: ignore[no-untyped-def]
    found = [content for attrs, content in html.scripts if attrs.get("id") == element_id]
    assert len(found) == 1, element_id
    return json.loads(found[0], parse_constant=lambda name: pytest.fail(f"{name} in the page"))


# --- The page ---------------------------------------------------------------------------------


def test_form_posts_the_file_without_javascript(client: TestClient) -> None:
    response = client.get("/mesh")
    assert response.status_code == 200
    html = Page(response.text)
    form = html.one("form", id="mesh-form")
    assert (form["method"], form["action"], form["enctype"]) == (
        "post",
        "/mesh",
        "multipart/form-data",
    )
    field = html.one("input", id="mesh-file")
    assert (field["type"], field["name"]) == ("file", "file")
    assert ".obj" in (field["accept"] or "") and ".stl" in (field["accept"] or "")
    assert html.find("label", for_="mesh-file")
    assert html.one("progress", id="mesh-progress") is not None
    assert html.one("p", id="mesh-status")["aria-live"] == "polite"
    assert not html.find("script", type="application/json", id="mesh-report")
    assert html.find("a", href="/mesh"), "the site's navigation links to the page"
    scripts = [attrs.get("src") or "" for attrs, _ in html.scripts]
    assert all(src.startswith("/static/") for src in scripts), scripts
    assert not any("gl3d" in src for src in scripts), "the 3D bundle loads only when needed"


def test_report_names_the_flipped_face_and_offers_the_fix(client: TestClient) -> None:
    response, html = post(client, CUBE_ONE_FLIPPED)
    assert response.template.name == "mesh.html"  # type: ignore[attr-defined]
    report = response.context["report"]  # type: ignore[attr-defined]
    assert [p.code for p in report.problems] == ["winding"]
    assert report.fix.flipped_face_indices == [0]
    winding = html.text("problem-winding")
    assert "wound against their neighbours" in winding
    assert "Faces the fix flips (0-based): 0." in winding
    assert "orient(vertices, faces)" in winding
    assert html.find("button", **{"data-mesh-download": "fix"})
    assert "1 problem needs fixing" in html.text("mesh-verdict")
    assert "curl -F file=@cube.obj http://testserver/api/mesh" in html.text("mesh-curl")


def test_json_twin_equals_the_api(client: TestClient) -> None:
    api = client.post("/api/mesh", files={"file": ("cube.obj", CUBE_ONE_FLIPPED.encode())})
    assert api.status_code == 200
    for part in (None, "report"):
        _, html = post(client, CUBE_ONE_FLIPPED, part=part)
        assert json_block(html, "mesh-report") == api.json()


def test_json_twin_of_an_overflowing_mesh_is_the_api_with_nulls(client: TestClient) -> None:
    huge = "v 0 0 0\nv 1e200 0 0\nv 0 1e200 0\nv 0 0 1e200\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    api = client.post("/api/mesh", files={"file": ("huge.obj", huge.encode())})
    _, html = post(client, huge, name="huge.obj", part="report")
    twin = json_block(html, "mesh-report")
    assert twin == api.json()
    assert twin["area"] is None and twin["volume"] is None
    assert "beyond the double range" in html.text("mesh-summary")


def test_fragment_is_the_report_alone(client: TestClient) -> None:
    response, html = post(client, CUBE, part="report")
    assert "<html" not in response.text and "<form" in response.text  # the download forms
    assert not html.find("form", id="mesh-form")
    assert "No problems found" in html.text("mesh-verdict")
    view = json_block(html, "mesh-view-data")
    assert [trace["name"] for trace in view["data"]][:1] == ["faces"]
    assert json_block(html, "mesh-histogram-data")["data"][0]["type"] == "bar"


def test_open_box_shows_boundary_in_the_view(client: TestClient) -> None:
    _, html = post(client, OPEN_BOX, part="report")
    assert "The mesh is open" in html.text("problem-open")
    names = [trace["name"] for trace in json_block(html, "mesh-view-data")["data"]]
    assert "boundary edges" in names


def test_curl_command_quotes_an_awkward_name(client: TestClient) -> None:
    _, html = post(client, CUBE, name="my cube's.obj")
    assert html.text("mesh-curl").startswith("curl -F 'file=@my cube'\"'\"'s.obj' ")


@pytest.mark.parametrize(
    ("data", "name", "status", "words"),
    [
        (b"this is not a mesh", "broken.obj", None, ""),
        (bytes(range(256)), "thing.xyz", 415, "not supported"),
        (b"", "empty.obj", 422, "empty"),
    ],
)
def test_a_file_it_cannot_read_is_a_4xx_page(
    client: TestClient, data: bytes, name: str, status: int | None, words: str
) -> None:
    for part in (None, "report"):
        response = client.post(
            "/mesh", params={"part": part} if part else None, files={"file": (name, data)}
        )
        assert 400 <= response.status_code < 500, response.text[:500]
        if status is not None:
            assert response.status_code == status
        assert response.headers["content-type"] == "text/html; charset=utf-8"
        html = Page(response.text)
        assert words in html.text("mesh-error")
        assert ("<form" in response.text) == (part is None), "the full page offers the form again"


def test_a_post_without_a_file_is_a_422_page(client: TestClient) -> None:
    response = client.post("/mesh", data={"other": "x"})
    assert response.status_code == 422
    assert "file is missing" in Page(response.text).text("mesh-error")


# --- Figure builders --------------------------------------------------------------------------


def test_classes_take_the_worst_problem() -> None:
    faces = np.array([[0, 1, 2], [0, 2, 3], [1, 2, 4], [2, 3, 4], [0, 0, 1]])
    degenerate = np.array([False, False, False, False, True])
    flipped = np.array([False, True, False, False, True])
    boundary = np.array([[0, 1], [3, 4]])  # faces 0, 3 (and 4 by its edge 0-1)
    nonmanifold = np.array([[4, 2]])  # faces 2, 3
    classes = face_classes(faces, 5, degenerate, flipped, boundary, nonmanifold)
    assert classes.tolist() == [BOUNDARY, FLIPPED, NONMANIFOLD, NONMANIFOLD, DEGENERATE]


def test_decimation_keeps_every_problem_face_and_is_deterministic() -> None:
    classes = np.full(100_000, OK, dtype=np.int8)
    problems = np.arange(5, 100_000, 97)
    classes[problems] = FLIPPED
    shown = select_faces(classes)
    assert len(shown) == mesh_view.DISPLAY_FACES
    assert np.isin(problems, shown).all()
    assert (np.diff(shown) > 0).all()
    assert np.array_equal(shown, select_faces(classes))


def test_decimation_caps_the_problem_faces() -> None:
    classes = np.full(50_000, FLIPPED, dtype=np.int8)
    classes[:10_000] = OK
    shown = select_faces(classes)
    assert len(shown) == mesh_view.DISPLAY_FACES
    assert np.count_nonzero(classes[shown] != OK) == mesh_view.PROBLEM_FACES
    assert len(select_faces(classes[:500])) == 500


def grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    """A flat size x size grid of squares, two triangles each, wound counter-clockwise."""
    x, y = np.meshgrid(np.arange(size + 1.0), np.arange(size + 1.0))
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    corner = (np.arange(size)[:, None] * (size + 1) + np.arange(size)).ravel()
    faces = np.concatenate(
        [
            np.column_stack([corner, corner + 1, corner + size + 2]),
            np.column_stack([corner, corner + size + 2, corner + size + 1]),
        ]
    )
    return vertices, faces


def test_view_colours_faces_and_caps_a_large_mesh() -> None:
    vertices, faces = grid(120)  # 28,800 faces
    normals = np.tile([0.0, 0.0, 1.0], (len(faces), 1))
    classes = np.full(len(faces), OK, dtype=np.int8)
    classes[[3, 7]] = FLIPPED
    classes[11] = DEGENERATE
    view = build_view(
        vertices, faces, normals, classes, np.zeros((0, 2), int), np.zeros((0, 2), int)
    )
    assert (view["shown_faces"], view["total_faces"]) == (mesh_view.DISPLAY_FACES, len(faces))
    traces = {trace["name"]: trace for trace in view["figure"]["data"]}
    mesh = traces["faces"]
    assert len(mesh["i"]) == len(mesh["facecolor"]) == mesh_view.DISPLAY_FACES - 1
    assert mesh["facecolor"].count(COLORS[FLIPPED]) == 2
    assert set(mesh["facecolor"]) == {COLORS[OK], COLORS[FLIPPED]}
    assert traces["degenerate"]["x"] and len(traces["degenerate"]["x"]) == 1
    assert view["arrows"] == mesh_view.ARROW_FACES
    flipped_heads = traces["flipped normals"]  # the cone trace comes after the shafts
    assert flipped_heads["type"] == "cone" and len(flipped_heads["u"]) == 2
    assert view["counts"] == {
        "degenerate": 1,
        "flipped": 2,
        "nonmanifold": 0,
        "boundary": 0,
        "ok": len(faces) - 3,
    }
    cones = [t for t in view["figure"]["data"] if t["type"] == "cone"]
    assert all(w > 0 for t in cones for w in t["w"]), "arrows point along the normals"
    json.dumps(view, allow_nan=False)  # plain JSON: no NaN, no NumPy types


def test_view_draws_huge_and_far_meshes_in_float32_range() -> None:
    for vertices in (
        np.array([[1e300, -1e300, 0], [-1e300, 1e300, 1e300], [0, 0, -1e300]]),
        np.array([[1e6, 1e6, 0], [1e6 + 1e-3, 1e6, 0], [1e6, 1e6 + 1e-3, 0]]),
    ):
        space = view_space(vertices)
        assert space.transformed
        assert np.abs(space.points).max() < 2.0**21
        assert len(np.unique(space.points.astype(np.float32), axis=0)) == 3, "shape kept"
        view = build_view(
            vertices,
            np.array([[0, 1, 2]]),
            np.array([[0.0, 0.0, 1.0]]),
            np.array([OK], dtype=np.int8),
            np.zeros((0, 2), int),
            np.zeros((0, 2), int),
        )
        assert view["note"] and "the file's" in view["note"]
        json.dumps(view, allow_nan=False)
    assert not view_space(np.eye(3)).transformed


def test_histogram_bins_add_up_to_the_faces() -> None:
    rng = np.random.default_rng(1)
    areas = 10.0 ** rng.uniform(-6, 2, 5000)
    degenerate = np.zeros(5000, dtype=bool)
    degenerate[:17] = True
    areas[:17] = 0.0
    areas[17] = np.inf
    histogram = area_histogram(areas, degenerate)
    assert histogram["log"] is True
    assert histogram["zero_area"] == 17 and histogram["beyond_range"] == 1
    assert sum(histogram["counts"]) + 17 + 1 == 5000
    assert len(histogram["edges"]) == len(histogram["counts"]) + 1
    figure = histogram_figure(histogram)
    zero = figure["data"][1]
    assert zero["y"] == [17] and zero["marker"]["color"] == COLORS[DEGENERATE]
    assert figure["layout"]["xaxis"]["ticktext"][0] == "zero"
    json.dumps(figure, allow_nan=False)


def test_histogram_is_linear_for_a_narrow_range_and_handles_equal_areas() -> None:
    linear = area_histogram(np.linspace(1.0, 2.0, 400), np.zeros(400, dtype=bool))
    assert linear["log"] is False and sum(linear["counts"]) == 400
    equal = area_histogram(np.full(12, 0.5), np.zeros(12, dtype=bool))
    assert equal["counts"] == [12] and equal["edges"][0] < 0.5 < equal["edges"][1]
    empty = area_histogram(np.zeros(3), np.ones(3, dtype=bool))
    assert empty["counts"] == [] and empty["zero_area"] == 3
