"""The mesh page in Chromium with several files (a .gltf and its .bin) and with a mesh whose
colours the chosen format of the fixed mesh cannot hold: the page says so before and at download."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

from mesh_normal.files import read_mesh
from tests.paths import DATA

pytestmark = pytest.mark.browser

GLTF = DATA / "gltf"


def data_file(path: Path) -> dict[str, object]:
    return {"name": path.name, "mimeType": "application/octet-stream", "buffer": path.read_bytes()}


def open_report(page: Page, *paths: Path) -> None:
    response = page.goto("/mesh")
    assert response is not None and response.status == 200
    page.wait_for_load_state("load")
    page.set_input_files("#mesh-file", files=[data_file(path) for path in paths])
    page.locator("#mesh-report-title").wait_for()


def test_a_gltf_with_its_bin_chosen_together(page: Page, tmp_path: Path) -> None:
    open_report(page, GLTF / "Box0.bin", GLTF / "Box.gltf")
    expect(page.locator(".mesh-filename")).to_have_text("Box.gltf")
    expect(page.locator("#mesh-files")).to_have_text("Files: Box0.bin (read) · Box.gltf (read)")
    expect(page.locator("#mesh-status")).to_contain_text("Report ready for Box.gltf")
    expect(page.locator("#mesh-curl")).to_contain_text("-F file=@Box0.bin -F file=@Box.gltf")
    page.screenshot(path=tmp_path / "several.png", animations="disabled")
    with page.expect_download() as info:
        page.locator("#download-fix").click()  # the page sends both files again
    assert info.value.suggested_filename == "Box-fixed.ply"
    assert len(read_mesh(Path(info.value.path()).read_bytes(), "fixed.ply").faces) == 12
    expect(page.locator("#mesh-download-status")).to_have_text("Saved Box-fixed.ply.")


def test_the_page_says_what_the_fixed_mesh_leaves_out(page: Page, tmp_path: Path) -> None:
    open_report(page, DATA / "colors_blender.ply")
    dropped = page.locator("#fix-dropped")
    expect(dropped).to_be_hidden()  # PLY, the upload's format, keeps the colours
    page.select_option("#fix-format", "stl")
    expect(dropped).to_be_visible()
    expect(dropped).to_have_text(  # the formats that keep the colours, PLY and OBJ among them
        re.compile(
            r"^STL leaves out vertex colours \(STL holds none\); "
            r"(?=.*PLY)(?=.*OBJ).* keep everything\.$"
        )
    )
    with page.expect_download() as info:
        page.locator("#download-fix").click()
    assert info.value.suggested_filename == "colors_blender-fixed.stl"
    status = page.locator("#mesh-download-status")
    expect(status).to_have_text(
        "Saved colors_blender-fixed.stl, which leaves out vertex colours (STL holds none)."
    )
    expect(status).to_have_class("message small warn")
    page.locator("#mesh-downloads").screenshot(path=tmp_path / "dropped.png", animations="disabled")
    page.select_option("#fix-format", "obj")
    expect(dropped).to_be_hidden()


DROP_FILES = """(files) => {
    const data = new DataTransfer();
    for (const [name, bytes] of files) data.items.add(new File([new Uint8Array(bytes)], name));
    const zone = document.getElementById('mesh-dropzone');
    for (const type of ['dragenter', 'dragover', 'drop']) {
        zone.dispatchEvent(new DragEvent(type, {dataTransfer: data, bubbles: true,
                                                cancelable: true}));
    }
}"""


def test_dropping_an_obj_with_its_mtl(page: Page) -> None:
    response = page.goto("/mesh")
    assert response is not None and response.status == 200
    page.wait_for_load_state("load")
    obj = b"mtllib model.mtl\n" + (DATA / "cube.obj").read_bytes()
    page.evaluate(DROP_FILES, [["model.obj", list(obj)], ["model.mtl", list(b"newmtl a\n")]])
    page.locator("#mesh-report-title").wait_for()
    expect(page.locator(".mesh-filename")).to_have_text("model.obj")
    expect(page.locator("#mesh-files")).to_have_text(
        "Files: model.obj (read) · model.mtl (not needed)"
    )
    assert page.evaluate("() => document.getElementById('mesh-file').files.length") == 2
