"""The mesh report's tools in Chromium (static/js/mesh_tools.js): "Download with normals", with
every face flipped or not, for a chosen file and for a sample the page fetches itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import Page, expect

from app.mesh.samples import CUBE_FACES, cube_points
from mesh_normal.files import read_mesh
from mesh_normal.mesh.topology import mesh_topology
from tests.browser.conftest import NewPage
from tests.browser.test_mesh_page import cube_file, open_mesh_page, wait_for_report
from tests.meshes import CUBE_ONE_FLIPPED_OBJ

pytestmark = pytest.mark.browser


def export(page: Page, file_format: str, normals: str, flip: bool) -> Path:
    page.select_option("#export-format", file_format)
    page.select_option("#export-normals", normals)
    page.locator("#export-flip").set_checked(flip)
    with page.expect_download() as info:
        page.get_by_role("button", name="Download with normals").click()
    return Path(info.value.path()), info.value.suggested_filename


def test_download_with_normals_flipped_or_kept(page: Page) -> None:
    open_mesh_page(page)
    page.set_input_files("#mesh-file", files=[cube_file()])
    wait_for_report(page)
    original = read_mesh(CUBE_ONE_FLIPPED_OBJ.encode(), "cube.obj")
    expect(page.locator("#export-form")).to_be_visible()
    expect(page.locator("#export-format")).to_have_value("obj")  # the file's own format

    path, name = export(page, "ply", "face", flip=True)
    assert name == "cube-export.ply"
    flipped = read_mesh(path.read_bytes(), name)
    assert flipped.faces.tolist() == original.faces[:, [0, 2, 1]].tolist()
    assert flipped.file_face_normals is not None and len(flipped.file_face_normals) == 12
    expect(page.locator("#mesh-download-status")).to_have_text(
        "Saved cube-export.ply with face normals, 12 faces flipped."
    )

    path, name = export(page, "obj", "vertex", flip=False)
    kept = read_mesh(path.read_bytes(), name)
    assert kept.faces.tolist() == original.faces.tolist()
    assert kept.file_vertex_normals is not None and kept.file_vertex_normals.shape == (8, 3)
    expect(page.locator("#mesh-download-status")).to_have_text(
        "Saved cube-export.obj with vertex normals."
    )

    # PLY holds no corner normals: the page says what the file leaves out.
    path, name = export(page, "ply", "corner", flip=False)
    expect(page.locator("#mesh-download-status")).to_contain_text("it leaves out corner normals")


def test_a_sample_page_exports_and_fixes_its_own_file(page: Page) -> None:
    response = page.goto("/mesh/sample/inside-out")
    assert response is not None and response.status == 200
    page.wait_for_load_state("load")
    expect(page.locator("#mesh-verdict")).to_contain_text("1 problem needs fixing")
    expect(page.locator("#export-form")).to_be_visible()

    # Flipping every face of the inside-out cube gives the clean cube back.
    path, name = export(page, "glb", "vertex", flip=True)
    assert name == "inside-out-export.glb"
    right = read_mesh(path.read_bytes(), name)
    assert right.faces.tolist() == [list(face) for face in CUBE_FACES]
    assert np.array_equal(right.vertices, cube_points())

    # mesh.js's own downloads find the sample's file in the file field too.
    page.select_option("#fix-format", "obj")
    with page.expect_download() as info:
        page.locator("#download-fix").click()
    fixed = read_mesh(Path(info.value.path()).read_bytes(), "fixed.obj")
    assert fixed.faces.tolist() == [list(face) for face in CUBE_FACES]
    assert mesh_topology(fixed.faces, len(fixed.vertices)).winding_consistent


def test_without_javascript_the_page_shows_only_what_works(new_page: NewPage) -> None:
    page = new_page(java_script_enabled=False, accept_downloads=True)
    response = page.goto("/mesh/sample/inside-out")
    assert response is not None and response.status == 200
    # The 3D card says once that it needs JavaScript, and shows nothing that would need it.
    card = page.locator(".mesh-view-card")
    # (Playwright's text matching skips <noscript>: its paragraph is found by tag.)
    expect(card.locator("noscript p")).to_be_visible()
    words = " ".join(card.inner_text().split())
    assert words == "3D view The 3D view needs JavaScript and WebGL."
    expect(card).not_to_contain_text("loads when it scrolls into sight")
    for hidden in ("#mesh-view", "#mesh-view-caption", ".mesh-legend", "#mesh-view-title .muted"):
        assert page.locator(hidden).count() >= 1, hidden
        for element in page.locator(hidden).all():  # the legends of both colourings
            expect(element).to_be_hidden()
    expect(page.locator("#mesh-histogram")).to_be_hidden()
    expect(page.locator("#mesh-histogram-caption")).to_be_visible()  # words, not a chart
    # No button that does nothing: the script's controls are all hidden.
    for hidden in ("#normals-form", "#fix-form", "#mesh-report-download", ".mesh-view-controls"):
        assert page.locator(hidden).count() >= 1, hidden
        for element in page.locator(hidden).all():  # the colour and the arrow controls
            expect(element).to_be_hidden()
    visible_buttons = page.locator("main button:visible")
    expect(visible_buttons).to_have_text(["Analyse", "Download with normals"])
    # What is shown works: the sample's export is a plain GET form, the fix a plain link.
    page.locator("#export-flip").check()
    page.select_option("#export-format", "ply")
    with page.expect_download() as info:
        page.get_by_role("button", name="Download with normals").click()
    assert info.value.suggested_filename == "inside-out-export.ply"
    right = read_mesh(Path(info.value.path()).read_bytes(), "right.ply")
    assert right.faces.tolist() == [list(face) for face in CUBE_FACES]
    assert right.file_vertex_normals is not None
    with page.expect_download() as info:
        page.get_by_role("link", name="the fixed mesh (OBJ)").click()
    fixed = read_mesh(Path(info.value.path()).read_bytes(), "fixed.obj")
    assert fixed.faces.tolist() == [list(face) for face in CUBE_FACES]


def test_without_javascript_an_upload_hides_the_tools(new_page: NewPage) -> None:
    page = new_page(java_script_enabled=False)
    page.goto("/mesh")
    page.set_input_files("#mesh-file", files=[cube_file()])
    with page.expect_navigation():
        page.get_by_role("button", name="Analyse").click()
    expect(page.locator("#mesh-report-title")).to_contain_text("cube.obj")
    # The server keeps nothing, so no form could send the file again: none is shown.
    expect(page.locator("#export-form")).to_be_hidden()
    expect(page.locator("main button:visible")).to_have_text(["Analyse"])
    note = page.locator("#mesh-downloads noscript p")
    expect(note).to_be_visible()
    assert "Downloads need JavaScript; without it" in note.inner_text()
