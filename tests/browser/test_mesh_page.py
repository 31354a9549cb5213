"""The mesh page in Chromium: upload with progress, the report, the 3D view and histogram, the
downloads (the page sends its file again), drag and drop, the phone layout and a screenshot."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import Page, expect

from mesh_normal import vertex_normals
from mesh_normal.files import read_mesh, write_mesh
from mesh_normal.mesh.topology import mesh_topology
from tests.browser.conftest import ConsoleWatch, NewPage
from tests.meshes import CUBE_ONE_FLIPPED_OBJ, stepped_sides_cube
from tests.paths import DATA, ROOT

pytestmark = pytest.mark.browser

DOCS = ROOT / "docs"
SCREENSHOT_LIMIT = 400 * 1024

#: Records whether the progress bar showed while the page uploaded (it may be brief).
WATCH_PROGRESS = """() => {
    window.__progressShown = false;
    const row = document.getElementById('mesh-progress-row');
    new MutationObserver(() => {
        if (!row.classList.contains('hidden')) window.__progressShown = true;
    }).observe(row, {attributes: true});
}"""

DROP = """([name, text]) => {
    const data = new DataTransfer();
    data.items.add(new File([text], name, {type: 'text/plain'}));
    const zone = document.getElementById('mesh-dropzone');
    for (const type of ['dragenter', 'dragover', 'drop']) {
        zone.dispatchEvent(new DragEvent(type, {dataTransfer: data, bubbles: true,
                                                cancelable: true}));
    }
}"""


def cube_file(name: str = "cube.obj") -> dict[str, object]:
    return {"name": name, "mimeType": "text/plain", "buffer": CUBE_ONE_FLIPPED_OBJ.encode()}


def open_mesh_page(page: Page) -> None:
    response = page.goto("/mesh")
    assert response is not None and response.status == 200
    page.wait_for_load_state("load")
    page.evaluate(WATCH_PROGRESS)


def wait_for_report(page: Page) -> None:
    page.locator("#mesh-report-title").wait_for()
    page.locator("#mesh-histogram[data-drawn] .main-svg").first.wait_for()


def wait_for_view(page: Page) -> None:
    page.locator("#mesh-view").scroll_into_view_if_needed()
    page.locator("#mesh-view[data-drawn]").wait_for(timeout=20_000)
    expect(page.locator("#mesh-view canvas").first).to_be_attached()


def test_choosing_a_file_uploads_it_and_shows_the_diagnosis(page: Page) -> None:
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    assert page.evaluate("() => window.__progressShown") is True
    expect(page.locator("#mesh-progress-row")).to_be_hidden()
    expect(page.locator("#mesh-status")).to_contain_text("1 problem found")
    expect(page.locator("#mesh-report-title")).to_be_focused()
    winding = page.locator("#problem-winding")
    expect(winding).to_contain_text("Faces are wound against their neighbours")
    expect(winding.locator(".mesh-indices")).to_have_text("Faces the fix flips (0-based): 0.")
    expect(page.locator("#mesh-view-caption")).to_contain_text("Showing all 12 faces")
    wait_for_view(page)
    colors = page.evaluate("""() => document.getElementById('mesh-view').data
        .find((t) => t.type === 'mesh3d').facecolor""")
    assert colors.count("#f76707") == 1 and len(colors) == 12
    # The server writes the curl command's address relative; the page puts its own in front.
    origin = page.evaluate("location.origin")
    expect(page.locator("#mesh-curl")).to_have_text(f"curl -F file=@cube.obj {origin}/api/mesh")


def test_downloads_send_the_file_again(page: Page) -> None:
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    mesh = read_mesh(CUBE_ONE_FLIPPED_OBJ.encode(), "cube.obj")

    page.select_option("#normals-kind", "vertex")
    page.select_option("#normals-format", "npy")
    with page.expect_download() as info:
        page.get_by_role("button", name="Download normals").click()
    download = info.value
    assert download.suggested_filename == "cube-vertex-normals.npy"
    normals = np.load(io.BytesIO(Path(download.path()).read_bytes()))
    expected = vertex_normals(mesh.vertices, mesh.faces, "angle").normals
    assert normals.shape == (8, 3) and np.array_equal(normals, expected)
    expect(page.locator("#mesh-download-status")).to_have_text("Saved cube-vertex-normals.npy.")

    page.select_option("#fix-format", "obj")
    with page.expect_download() as info:
        page.locator("#download-fix").click()
    download = info.value
    assert download.suggested_filename == "cube-fixed.obj"
    fixed = read_mesh(Path(download.path()).read_bytes(), "fixed.obj")
    assert np.array_equal(fixed.vertices, mesh.vertices)
    assert mesh_topology(fixed.faces, len(fixed.vertices)).winding_consistent

    with page.expect_download() as info:
        page.locator("#problem-winding button[data-mesh-download=fix]").click()
    assert info.value.suggested_filename == "cube-fixed.obj"

    with page.expect_download() as info:
        page.get_by_role("button", name="Download report (JSON)").click()
    assert info.value.suggested_filename == "cube-report.json"


def test_a_weld_analyses_again_and_goes_with_the_fix(page: Page) -> None:
    vertices, faces = stepped_sides_cube()
    data = write_mesh(vertices, faces[:, ::-1], "ply")  # six sides a step apart, inward
    open_mesh_page(page)
    page.set_input_files(
        "#mesh-file", files=[{"name": "s.ply", "mimeType": "text/plain", "buffer": data}]
    )
    wait_for_report(page)
    expect(page.locator("#problem-open")).to_be_visible()
    expect(page.locator("#mesh-weld-used")).to_have_count(0)
    page.locator(".mesh-options summary").click()
    page.fill("#mesh-weld", "0.5")
    page.locator("#mesh-weld").dispatch_event("change")
    expect(page.locator("#mesh-status")).to_contain_text("from 0 to 0.01")
    page.fill("#mesh-weld", "1e-6")
    page.locator("#mesh-weld").dispatch_event("change")  # the held file is analysed again
    expect(page.locator("#mesh-weld-used")).to_contain_text("joined 40 vertices")
    expect(page.locator("#problem-inward")).to_be_visible()
    with page.expect_download() as info:
        page.locator("#problem-inward button[data-mesh-download=fix]").click()
    fixed = read_mesh(Path(info.value.path()).read_bytes(), "fixed.ply")
    # Every face turned (A, C, B), as the report said: the file's own winding again.
    assert np.array_equal(fixed.faces, faces[:, ::-1][:, [0, 2, 1]])


def test_a_bad_crease_angle_and_a_broken_file_are_said_inline(
    page: Page, console: ConsoleWatch
) -> None:
    console.allow(r"status of 400 \(Bad Request\) \(http://[^)]*/mesh\?part=report\)$")
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    page.select_option("#normals-kind", "corner")
    page.fill("#normals-crease", "200")
    page.get_by_role("button", name="Download normals").click()
    expect(page.locator("#mesh-download-status")).to_contain_text("from 0 to 180")

    page.set_input_files(
        "#mesh-file",
        files=[{"name": "broken.obj", "mimeType": "text/plain", "buffer": b"f 1 2 3\n"}],
    )
    expect(page.locator("#mesh-error [data-error]")).to_be_visible()
    expect(page.locator("#mesh-status")).to_have_class("mesh-status message error")
    expect(page.locator("#mesh-report-title")).to_have_count(0)


def test_dropping_a_file_uploads_it(page: Page) -> None:
    open_mesh_page(page)
    page.evaluate(DROP, ["dropped.obj", CUBE_ONE_FLIPPED_OBJ])
    wait_for_report(page)
    expect(page.locator(".mesh-filename")).to_have_text("dropped.obj")
    assert (
        page.evaluate("() => document.getElementById('mesh-file').files[0].name") == "dropped.obj"
    )


def problem_mesh() -> bytes:
    """The ant from tests/data with a patch of faces flipped and, elsewhere, a small hole."""
    ant = read_mesh((DATA / "ant.ply").read_bytes(), "ant.ply")
    faces = ant.faces.copy()
    centroids = ant.vertices[faces].mean(axis=1)
    distance = np.linalg.norm(centroids - centroids[40], axis=1)
    patch = np.argsort(distance)[:30]
    faces[patch] = faces[patch, ::-1]
    far = np.argsort(np.linalg.norm(centroids - centroids[np.argmax(distance)], axis=1))
    keep = np.ones(len(faces), dtype=bool)
    keep[far[:4]] = False
    return write_mesh(ant.vertices, faces[keep], "obj")


def test_phone_layout_and_desktop_screenshot(new_page: NewPage) -> None:
    page = new_page(viewport={"width": 360, "height": 740}, is_mobile=True, has_touch=True)
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    wait_for_view(page)
    widths = page.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")
    assert widths[0] <= widths[1], widths

    page = new_page(viewport={"width": 1280, "height": 1000})
    open_mesh_page(page)
    page.set_input_files(
        "#mesh-file",
        files=[{"name": "ant.obj", "mimeType": "text/plain", "buffer": problem_mesh()}],
    )
    wait_for_report(page)
    wait_for_view(page)
    page.evaluate("() => window.scrollTo(0, 0)")
    page.wait_for_timeout(300)
    path = DOCS / "mesh-page.png"
    page.screenshot(path=path, animations="disabled", caret="hide", scale="css")
    assert path.stat().st_size < SCREENSHOT_LIMIT, path.stat().st_size


CAMERA_UP = """() => {
    const up = document.getElementById('mesh-view')._fullLayout.scene.camera.up;
    return [up.x, up.y, up.z];
}"""


def test_a_y_up_gltf_stands_up_and_the_up_axis_switches(page: Page) -> None:
    import trimesh

    from tests.meshes import CUBE_FACES, CUBE_VERTICES

    glb = trimesh.Trimesh(CUBE_VERTICES, CUBE_FACES, process=False).export(file_type="glb")
    open_mesh_page(page)
    page.set_input_files(
        "#mesh-file", files=[{"name": "cube.glb", "mimeType": "model/gltf-binary", "buffer": glb}]
    )
    page.locator("#mesh-report-title").wait_for(timeout=40_000)  # the first glTF imports trimesh
    wait_for_report(page)
    expect(page.locator("#mesh-up")).to_be_visible()  # shown by the script
    expect(page.locator("#mesh-up")).to_have_value("y")
    expect(page.locator("#mesh-up-help")).to_contain_text("glTF is Y-up by its specification")
    expect(page.locator("#download-fix")).to_be_visible()
    page.locator("#mesh-view").scroll_into_view_if_needed()
    page.locator("#mesh-view[data-drawn]").wait_for(timeout=20_000)
    assert page.evaluate(CAMERA_UP) == [0, 1, 0]
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.select_option("#mesh-up", "z")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    assert page.evaluate(CAMERA_UP) == [0, 0, 1]


VISIBLE = """() => Object.fromEntries(document.getElementById('mesh-view')._fullData
    .map((t) => [t.name, t.visible === true]))"""

#: For each face of the front copy, how much farther its centroid is from the cube's centre
#: than the face's own: the copy is moved along the face's normal.
FRONT_MOVED = """() => {
    const data = document.getElementById('mesh-view').data;
    const faces = data.find((t) => t.name === 'faces');
    const front = data.find((t) => t.name === 'front faces');
    const d = (x, y, z) => Math.hypot(x - 0.5, y - 0.5, z - 0.5);
    return faces.i.map((_, f) => {
        const c = [faces.i[f], faces.j[f], faces.k[f]];
        const mean = (t, axis, at) => at.reduce((s, v) => s + t[axis][v], 0) / 3;
        const own = d(mean(faces, 'x', c), mean(faces, 'y', c), mean(faces, 'z', c));
        const copy = [3 * f, 3 * f + 1, 3 * f + 2];
        return d(mean(front, 'x', copy), mean(front, 'y', copy), mean(front, 'z', copy)) - own;
    });
}"""


def test_the_face_orientation_mode_shows_front_blue_and_back_red(page: Page) -> None:
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    wait_for_view(page)
    expect(page.locator("#mesh-mode")).to_have_value("problems")
    shown = page.evaluate(VISIBLE)
    assert shown["faces"] and not shown["front faces"] and not shown["back faces"]
    expect(page.locator("#mesh-orientation-legend")).to_be_hidden()
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    requests: list[str] = []
    page.on("request", lambda request: requests.append(request.url))
    page.select_option("#mesh-mode", "orientation")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    shown = page.evaluate(VISIBLE)
    assert not shown["faces"] and shown["front faces"] and shown["back faces"]
    assert shown["normals"], "the arrows stay"
    assert requests == [], "the switch draws what the page has"
    expect(page.locator("#mesh-orientation-legend")).to_be_visible()
    expect(page.locator("#mesh-problem-legend")).to_be_hidden()
    colors = page.evaluate("""() => document.getElementById('mesh-view').data
        .filter((t) => t.name.endsWith(' faces')).map((t) => [t.name, t.color])""")
    assert colors == [["front faces", "#2f6fed"], ["back faces", "#e0312f"]]
    # Face 0 of the cube is wound inward: its front copy moves in, the eleven others out.
    moved = page.evaluate(FRONT_MOVED)
    assert moved[0] < 0 and all(m > 0 for m in moved[1:]), moved
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.select_option("#mesh-mode", "problems")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    shown = page.evaluate(VISIBLE)
    assert shown["faces"] and not shown["front faces"]
    expect(page.locator("#mesh-problem-legend")).to_be_visible()


ARROWS = """() => document.getElementById('mesh-view').data
    .filter((t) => t.type === 'cone').map((t) => [t.name, t.u.length, t.x[0], t.u[0]])"""


def test_the_arrow_controls_choose_kind_count_and_length(page: Page) -> None:
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    wait_for_view(page)
    expect(page.locator("#mesh-arrow-count")).to_have_value("12")
    # As drawn by the report: 11 face arrows and the flipped one in orange.
    assert sorted((name, n) for name, n, *_ in page.evaluate(ARROWS)) == [
        ("flipped normals", 1), ("normals", 11)]  # fmt: skip
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.select_option("#mesh-arrow-kind", "vertex")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    assert [(name, n) for name, n, *_ in page.evaluate(ARROWS)] == [("normals", 8)]
    expect(page.locator("#mesh-view-arrows")).to_have_text(
        " Arrows: the unit normals of 8 vertices."
    )
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.fill("#mesh-arrow-count", "3")
    page.locator("#mesh-arrow-count").dispatch_event("change")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    ((_, count, _, head),) = page.evaluate(ARROWS)
    assert count == 3
    # The cube's diagonal is √3; the head is 0.3 of the 0.04-diagonal arrow, along the
    # normal (1/√3 on each axis for a cube's corner).
    assert abs(abs(head) - 0.3 * 0.04 * 3**0.5 / 3**0.5) < 1e-6
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.fill("#mesh-arrow-length", "0.1")
    page.locator("#mesh-arrow-length").dispatch_event("change")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    ((_, _, _, head),) = page.evaluate(ARROWS)
    assert abs(abs(head) - 0.3 * 0.1) < 1e-6


SURFACE = """() => {
    const t = document.getElementById('mesh-view').data.find((t) => t.name === 'faces');
    return [t.x.length, t.i.length, t.flatshading];
}"""


def move_crease(page: Page, angle: int) -> None:
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.locator("#mesh-crease").fill(str(angle))  # a range input: sets it and fires input
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )


def test_the_smooth_by_angle_slider_splits_the_surface_and_goes_with_the_export(
    page: Page,
) -> None:
    response = page.goto("/mesh/sample/cube")
    assert response is not None and response.status == 200
    wait_for_view(page)
    slider = page.locator("#mesh-crease")
    expect(slider).to_be_visible()
    expect(slider).to_have_value("30")
    # The cube's 8 corners, each split in 3 at 30°: one copy for each side it is on.
    assert page.evaluate(SURFACE) == [24, 12, False]
    move_crease(page, 180)
    expect(page.locator("#mesh-crease-text")).to_have_text("180°: every edge smooth")
    assert page.evaluate(SURFACE) == [8, 12, False]
    move_crease(page, 0)
    expect(page.locator("#mesh-crease-text")).to_have_text("0°: every face flat")
    assert page.evaluate(SURFACE) == [24, 12, False]
    move_crease(page, 100)  # above the cube's 90°: smooth again
    expect(page.locator("#mesh-crease-text")).to_have_text(
        "100°: edges between faces more than 100° apart stay sharp"
    )
    assert page.evaluate(SURFACE)[0] == 8
    # Corner arrows follow: at 100° a cube's corner takes its three sides, area-weighted.
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.select_option("#mesh-arrow-kind", "corner")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    expect(page.locator("#mesh-view-arrows")).to_contain_text(", smooth by angle 100°.")
    heads = page.evaluate("""() => document.getElementById('mesh-view').data
        .filter((t) => t.type === 'cone').flatMap((t) => t.u.map((u, r) => [u, t.v[r], t.w[r]]))""")
    assert heads
    for head in heads:
        length = sum(c * c for c in head) ** 0.5
        # Each corner of a cube vertex sees its 3 sides, 1 or 2 triangles each: never one axis.
        assert max(abs(c) for c in head) < 0.99 * length
    move_crease(page, 0)
    heads = page.evaluate("""() => document.getElementById('mesh-view').data
        .filter((t) => t.type === 'cone').flatMap((t) => t.u.map((u, r) => [u, t.v[r], t.w[r]]))""")
    for head in heads:  # flat: each corner's normal is its face's, along one axis
        length = sum(c * c for c in head) ** 0.5
        assert max(abs(c) for c in head) > 0.9999 * length
    # The export of corner normals says and sends the slider's angle.
    expect(page.locator("#export-crease")).to_be_hidden()
    page.select_option("#export-normals", "corner")
    expect(page.locator("#export-crease")).to_have_text("at 0°, the 3D view's smoothing angle")
    with page.expect_request(lambda request: "/api/mesh/export" in request.url) as sent:
        page.click("#download-export")
    assert "crease_angle=0" in sent.value.url and "normals=corner" in sent.value.url


CAMERA = """() => {
    const camera = document.getElementById('mesh-view')._fullLayout.scene.camera;
    return {center: [camera.center.x, camera.center.y, camera.center.z],
            eye: [camera.eye.x, camera.eye.y, camera.eye.z]};
}"""


def test_the_view_steps_through_the_problem_places_and_back(page: Page) -> None:
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])  # one face flipped
    wait_for_report(page)
    wait_for_view(page)
    spots = page.evaluate(
        "() => JSON.parse(document.getElementById('mesh-view-spots').textContent)"
    )
    assert len(spots) == 1
    whole = page.evaluate(CAMERA)
    assert whole["center"] == [0, 0, 0]
    expect(page.locator("#mesh-whole")).to_be_hidden()
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.click("#mesh-next-problem")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    near = page.evaluate(CAMERA)
    assert near["center"] == pytest.approx([spots[0]["center"][a] for a in "xyz"], abs=1e-6)
    assert np.linalg.norm(np.subtract(near["eye"], near["center"])) < np.linalg.norm(whole["eye"])
    expect(page.locator("#mesh-spot-text")).to_contain_text(
        f"Problem place 1 of 1: face {spots[0]['face']}"
    )
    drawn = page.get_attribute("#mesh-view", "data-drawn")
    page.click("#mesh-whole")
    page.wait_for_function(
        "d => document.getElementById('mesh-view').dataset.drawn !== d", arg=drawn
    )
    assert page.evaluate(CAMERA) == whole
    expect(page.locator("#mesh-whole")).to_be_hidden()


def test_a_mesh_without_problems_has_no_problem_places(page: Page) -> None:
    from tests.meshes import CUBE_FACES, CUBE_VERTICES

    open_mesh_page(page)
    good = write_mesh(CUBE_VERTICES, CUBE_FACES, "obj")
    page.set_input_files(
        "#mesh-file", files=[{"name": "good.obj", "mimeType": "text/plain", "buffer": good}]
    )
    wait_for_report(page)
    wait_for_view(page)
    expect(page.locator("#mesh-spot-controls")).to_be_hidden()


def test_on_a_phone_the_camera_steps_back_to_frame_the_mesh(new_page: NewPage) -> None:
    page = new_page(viewport={"width": 360, "height": 740})
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    wait_for_view(page)
    camera = page.evaluate(CAMERA)
    cameras = page.evaluate(
        "() => JSON.parse(document.getElementById('mesh-view-cameras').textContent)"
    )
    up = page.input_value("#mesh-up")
    framed = np.linalg.norm([cameras[up]["eye"][a] for a in "xyz"])
    assert np.linalg.norm(camera["eye"]) > 1.05 * framed  # the canvas is taller than wide
