"""The mesh page (/mesh) without a browser: the form, the report and its JSON twin, errors.

The figure builders have their own tests: test_view.py, test_histogram.py, test_classes.py."""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient

from tests.conftest import Page
from tests.meshes import (
    CUBE_OBJ,
    CUBE_OBJ_FACES,
    CUBE_ONE_FLIPPED_OBJ,
    HUGE_TETRA_OBJ,
    OPEN_BOX_OBJ,
    obj_as_solids,
)


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
    response, html = post(client, CUBE_ONE_FLIPPED_OBJ)
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
    assert "curl -F file=@cube.obj /api/mesh" in html.text("mesh-curl")  # relative: no Host


def test_json_twin_equals_the_api(client: TestClient) -> None:
    api = client.post("/api/mesh", files={"file": ("cube.obj", CUBE_ONE_FLIPPED_OBJ.encode())})
    assert api.status_code == 200
    for part in (None, "report"):
        _, html = post(client, CUBE_ONE_FLIPPED_OBJ, part=part)
        assert json_block(html, "mesh-report") == api.json()


def test_json_twin_of_an_overflowing_mesh_is_the_api_with_nulls(client: TestClient) -> None:
    api = client.post("/api/mesh", files={"file": ("huge.obj", HUGE_TETRA_OBJ.encode())})
    _, html = post(client, HUGE_TETRA_OBJ, name="huge.obj", part="report")
    twin = json_block(html, "mesh-report")
    assert twin == api.json()
    assert twin["area"] is None and twin["volume"] is None
    assert "beyond the double range" in html.text("mesh-summary")


def test_fragment_is_the_report_alone(client: TestClient) -> None:
    response, html = post(client, CUBE_OBJ, part="report")
    assert "<html" not in response.text and "<form" in response.text  # the download forms
    assert not html.find("form", id="mesh-form")
    assert "No problems found" in html.text("mesh-verdict")
    view = json_block(html, "mesh-view-data")
    assert [trace["name"] for trace in view["data"]][:1] == ["faces"]
    assert json_block(html, "mesh-histogram-data")["data"][0]["type"] == "bar"


def test_open_box_shows_boundary_in_the_view(client: TestClient) -> None:
    _, html = post(client, OPEN_BOX_OBJ, part="report")
    assert "The mesh is open" in html.text("problem-open")
    names = [trace["name"] for trace in json_block(html, "mesh-view-data")["data"]]
    assert "boundary edges" in names


def test_curl_command_quotes_an_awkward_name(client: TestClient) -> None:
    _, html = post(client, CUBE_OBJ, name="my cube's.obj")
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


# --- the objects of a file with groups ---------------------------------------------------------


def test_objects_table_names_the_inward_object(client: TestClient) -> None:
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    inward = [face[::-1] for face in CUBE_OBJ_FACES]
    _, html = post(client, two_cubes(inward, "turned"), part="report")
    assert html.one("table", class_="mesh-object-table")
    assert "2 objects in the file" in html.text("mesh-objects")
    assert html.text("mesh-object-0") == "left 12 6 yes outward 0"
    assert html.text("mesh-object-1") == "turned 12 6 yes inward 12"
    assert len(html.find("tr", id="mesh-object-2")) == 0


def test_objects_table_lists_stl_solids(client: TestClient) -> None:
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    text = two_cubes([face[::-1] for face in CUBE_OBJ_FACES], "turned")
    _, html = post(client, obj_as_solids(text), "two.stl", part="report")
    assert "2 objects in the file" in html.text("mesh-objects")
    assert html.text("mesh-object-0") == "left 12 6 yes outward 0"
    assert html.text("mesh-object-1") == "turned 12 6 yes inward 12"


def test_the_page_says_before_the_download_that_the_objects_are_left_out(
    client: TestClient,
) -> None:
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    response, html = post(client, obj_as_solids(two_cubes()), "two.stl", part="report")
    expected = {  # OBJ keeps them, as o statements
        name: f"{title} leaves out the division into 2 objects (the {title} written is one "
        "mesh); OBJ keeps everything."
        for name, title in (("ply", "PLY"), ("stl", "STL"), ("off", "OFF"), ("glb", "GLB"))
    }
    expected["obj"] = ""
    assert response.context["fix_dropped"] == expected  # type: ignore[attr-defined]
    assert html.text("fix-dropped") == expected["stl"]  # the upload's format is chosen
    for text in (CUBE_OBJ, "o only\n" + CUBE_OBJ):  # one object is the mesh itself
        response, _ = post(client, text, part="report")
        assert not any(response.context["fix_dropped"].values())  # type: ignore[attr-defined]


def test_objects_table_is_hidden_for_one_object_or_none(client: TestClient) -> None:
    for text in (CUBE_OBJ, "o only\n" + CUBE_OBJ):
        response, html = post(client, text, part="report")
        assert "mesh-objects" not in response.text
        assert not html.find("table")


def test_objects_table_says_when_it_lists_only_the_first(client: TestClient) -> None:
    from tests.mesh_normal.mesh.report.test_objects import many_triangles

    _, html = post(client, many_triangles(105), part="report")
    assert "105 objects in the file; the first 100 are listed" in html.text("mesh-objects")
    assert html.find("tr", id="mesh-object-99") and not html.find("tr", id="mesh-object-100")


# --- the weld tolerance -----------------------------------------------------------------------


def stepped_ply() -> bytes:
    """The cube of six sides a float32 step apart, as a float64 PLY."""
    from mesh_normal.files import write_mesh
    from tests.meshes import stepped_sides_cube

    return write_mesh(*stepped_sides_cube(), "ply")


def test_the_form_offers_an_optional_weld(client: TestClient) -> None:
    html = Page(client.get("/mesh").text)
    field = html.one("input", id="mesh-weld")
    assert (field["name"], field["type"], field["min"], field["max"]) == (
        "weld",
        "number",
        "0",
        "0.01",
    )
    assert field.get("required") is None and field["value"] == ""
    assert "bounding-box diagonal" in html.text("mesh-weld-help")
    assert html.find("label", for_="mesh-weld")


def test_a_weld_shows_in_the_results_and_goes_to_the_fix(client: TestClient) -> None:
    response = client.post("/mesh", files={"file": ("s.ply", stepped_ply())}, data={"weld": "1e-6"})
    assert response.status_code == 200, response.text[:800]
    report = response.context["report"]  # type: ignore[attr-defined]
    assert report.watertight and report.weld.joined_vertices == 40
    html = Page(response.text)
    assert "joined 40 vertices beyond identical coordinates" in html.text("mesh-weld-used")
    assert html.one("div", id="mesh-report-view")["data-weld"] == "1e-06"  # the fix sends it
    assert html.one("input", id="mesh-weld")["value"] == "1e-06"  # the form keeps it
    assert "-F weld=1e-06" in html.text("mesh-curl")
    assert json_block(html, "mesh-report")["weld"]["tolerance"] == 1e-6
    _, plain = post(client, stepped_ply(), "s.ply", part="report")
    assert not plain.find("p", id="mesh-weld-used")
    assert plain.one("div", id="mesh-report-view").get("data-weld") is None


def test_a_bad_weld_is_a_422_page(client: TestClient) -> None:
    response = client.post(
        "/mesh", files={"file": ("c.obj", CUBE_OBJ.encode())}, data={"weld": "1"}
    )
    assert response.status_code == 422
    assert "weld must be a number from 0 to 0.01" in response.text


def test_boundary_faces_of_separate_sides_are_marked(client: TestClient) -> None:
    """The view names faces by position, like the edges: copies of a corner count too."""
    from mesh_normal.files import write_mesh
    from tests.meshes import separate_sides_cube

    vertices, faces = separate_sides_cube()  # 6 sides of 18 faces; drop the first
    response, html = post(client, write_mesh(vertices, faces[18:], "ply"), "open.ply", "report")
    assert "The mesh is open: 12 boundary edges" in html.text("problem-open")
    # One face of the four neighbouring sides along each of the hole's 12 edges, though the
    # points there are named by other sides' copies.
    assert response.context["figures"]["view"]["counts"]["boundary"] == 12


@pytest.mark.parametrize(
    "text",
    [
        "v 0 0 0\nv 5e-324 0 0\nv 0 5e-324 0\nf 1 2 3\n",  # subnormal: the area underflows
        "v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nf 1 2 3\n",  # huge: the area overflows
        "v 0 0 0\nv 1e300 0 0\nv 0 1e-300 0\nv 5e-324 5e-324 5e-324\nf 1 2 3\nf 1 2 4\n",
    ],
    ids=["subnormal", "huge", "mixed"],
)
def test_extreme_coordinates_draw_a_page_like_the_api(client: TestClient, text: str) -> None:
    api = client.post("/api/mesh", files={"file": ("t.obj", text.encode())})
    assert api.status_code == 200, api.text
    _, html = post(client, text, "t.obj")
    assert json_block(html, "mesh-report") == api.json()
    view = json_block(html, "mesh-view-data")
    json.dumps(view, allow_nan=False)
    assert view["data"], "something is drawn"


def test_view_of_an_obj_is_y_up_with_a_switch(client: TestClient) -> None:
    _, html = post(client, CUBE_OBJ, part="report")
    camera = json_block(html, "mesh-view-data")["layout"]["scene"]["camera"]
    assert camera["up"] == {"x": 0, "y": 1, "z": 0}
    assert set(json_block(html, "mesh-view-cameras")) == {"x", "y", "z"}
    selected = [o.get("value") for o in html.find("option") if "selected" in o]
    assert "y" in selected
    assert "OBJ files are drawn Y-up" in html.text("mesh-up-help")


def test_without_javascript_only_what_works_is_shown(client: TestClient) -> None:
    """Controls the script drives are hidden in the HTML; the script unhides them."""
    _, html = post(client, CUBE_ONE_FLIPPED_OBJ)
    for element_id in ("normals-form", "fix-form", "export-form", "mesh-report-download"):
        (element,) = [
            e for e in html.find("form") + html.find("button") if e.get("id") == element_id
        ]
        assert "hidden" in element and "data-needs-js" in element
    for button in html.find("button", class_="small copy"):
        assert "hidden" in button
    assert "loads when it scrolls into sight" not in html.text("mesh-view")


def test_without_javascript_the_advice_names_what_works(client: TestClient) -> None:
    """The fixed-mesh button needs the script: without it, the advice names the command."""
    response, _ = post(client, CUBE_ONE_FLIPPED_OBJ)
    text = response.text
    with_script = (
        '<p class="problem-action" data-needs-js hidden><b>What to do:</b> '
        "Download the fixed mesh, or call orient() in your own code.</p>"
    )
    without = (
        '<noscript><p class="problem-action"><b>What to do:</b> '
        "Fix the file with the command mesh-normal fix, or call orient() in your own code."
        "</p></noscript>"
    )
    assert with_script in text and without in text
    assert text.count("What to do:") == 2  # one sentence for each reader, nothing else


def test_a_samples_advice_is_left_as_it_is(client: TestClient) -> None:
    """A sample's page has a plain link to its fixed mesh: the advice stays as it is."""
    text = client.get("/mesh/sample/inside-out").text
    assert (
        '<p class="problem-action"><b>What to do:</b> Download the fixed mesh (every face reversed)'
        in text
    )
    assert "Fix the file with the command mesh-normal fix" not in text
