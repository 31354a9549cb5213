"""POST /api/mesh/fix keeps vertex colours where the format holds them and names the rest."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fastapi.testclient import TestClient

from mesh_normal.files import read_mesh, write_mesh
from tests.conftest import Page
from tests.meshes import TETRA_FACES, TETRA_OBJ, TETRA_VERTICES
from tests.paths import DATA

UCHAR = np.array([[255, 0, 3], [4, 5, 6], [7, 128, 9], [0, 254, 1]], dtype=np.uint8)
FLOAT = np.array(
    [[0.1, 0.2, 0.3, 1.0], [0.0, 0.5, 1.0, 0.25], [1 / 3, 2 / 3, 0.7, 0.0], [0.9, 0.8, 0.7, 0.6]],
    dtype=np.float32,
)
#: One face turned inside out, so that the fix has something to do.
FLIPPED = np.array([TETRA_FACES[0][::-1], *TETRA_FACES[1:]])


def fix(client: TestClient, data: bytes, name: str, fmt: str):  # type: ignore[no-untyped-def]
    response = client.post("/api/mesh/fix", params={"format": fmt}, files={"file": (name, data)})
    assert response.status_code == 200, response.text
    return response


@pytest.mark.parametrize("colors", [UCHAR, FLOAT], ids=["uchar", "float-rgba"])
def test_ply_colours_survive_the_fix_bit_for_bit(client: TestClient, colors: np.ndarray) -> None:
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=colors)
    response = fix(client, data, "c.ply", "ply")
    assert response.headers["x-faces-flipped"] == "1"
    assert "x-dropped" not in response.headers
    fixed = read_mesh(response.content, "fixed.ply")
    assert fixed.vertex_colors is not None and fixed.vertex_colors.dtype == colors.dtype
    assert fixed.vertex_colors.tobytes() == colors.tobytes()


def test_obj_colours_survive_the_fix(client: TestClient) -> None:
    colors = np.array([[0.1, 0.2, 0.3], [1.0, 0.0, 0.5], [1 / 3, 2 / 3, 1e-9], [0.0, 0.0, 0.0]])
    data = write_mesh(TETRA_VERTICES, FLIPPED, "obj", vertex_colors=colors)
    response = fix(client, data, "c.obj", "obj")
    assert "x-dropped" not in response.headers
    fixed = read_mesh(response.content, "fixed.obj")
    assert fixed.vertex_colors is not None
    assert fixed.vertex_colors.tobytes() == colors.tobytes()


def test_stl_output_names_the_dropped_colours(client: TestClient) -> None:
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=UCHAR)
    response = fix(client, data, "c.ply", "stl")
    assert response.headers["x-dropped"] == "vertex colours (STL holds none)"


def test_obj_output_names_the_dropped_alpha(client: TestClient) -> None:
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=FLOAT)
    response = fix(client, data, "c.ply", "obj")
    assert response.headers["x-dropped"] == (
        "vertex colour alpha (OBJ holds red, green and blue only)"
    )
    fixed = read_mesh(response.content, "fixed.obj")
    assert fixed.vertex_colors is not None
    np.testing.assert_array_equal(fixed.vertex_colors, FLOAT[:, :3].astype(np.float64))


@pytest.mark.parametrize("fmt", ["ply", "stl", "obj"])
def test_no_colours_no_header(client: TestClient, fmt: str) -> None:
    response = fix(client, TETRA_OBJ.encode(), "t.obj", fmt)
    assert "x-dropped" not in response.headers


def test_the_fix_documents_x_dropped(client: TestClient) -> None:
    route = client.get("/openapi.json").json()["paths"]["/api/mesh/fix"]["post"]
    assert "X-Dropped" in route["responses"]["200"]["description"]


def test_a_meshlab_files_colours_survive_the_fix(client: TestClient) -> None:
    data = (DATA / "colors_meshlab.ply").read_bytes()
    original = read_mesh(data, "colors_meshlab.ply")
    assert original.vertex_colors is not None
    fixed = read_mesh(fix(client, data, "colors_meshlab.ply", "ply").content, "fixed.ply")
    assert fixed.vertex_colors is not None
    assert fixed.vertex_colors.tobytes() == original.vertex_colors.tobytes()
    np.testing.assert_array_equal(fixed.vertices, original.vertices)
    dropped = fix(client, data, "colors_meshlab.ply", "stl").headers["x-dropped"]
    assert dropped == "vertex colours (STL holds none)"


@pytest.mark.parametrize(
    ("colors", "expected"),
    [
        (None, {"ply": "", "stl": "", "obj": "", "off": "", "glb": ""}),
        (
            UCHAR,
            {
                "ply": "",
                "stl": "STL leaves out vertex colours (STL holds none); PLY, OBJ, OFF and GLB "
                "keep everything.",
                "obj": "",
                "off": "",
                "glb": "",
            },
        ),
        (
            FLOAT,
            {
                "ply": "",
                "stl": "STL leaves out vertex colours (STL holds none); PLY, OFF and GLB keep "
                "everything.",
                "obj": "OBJ leaves out vertex colour alpha (OBJ holds red, green and blue only); "
                "PLY, OFF and GLB keep everything.",
                "off": "",
                "glb": "",
            },
        ),
    ],
    ids=["none", "rgb", "rgba"],
)
def test_the_page_says_before_the_download_what_each_format_leaves_out(
    client: TestClient, colors: np.ndarray | None, expected: dict[str, str]
) -> None:
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=colors)
    response = client.post("/mesh", files={"file": ("c.ply", data)})
    assert response.context["fix_dropped"] == expected  # type: ignore[attr-defined]
    page = Page(response.text)
    assert json.loads(page.text("mesh-fix-dropped")) == expected
    assert "hidden" in (page.one("p", id="fix-dropped")["class"] or "")  # PLY is chosen
    for fmt, sentence in expected.items():  # in the words of the header of that download
        header = fix(client, data, "c.ply", fmt).headers.get("x-dropped", "")
        assert (header in sentence) if header else not sentence


def test_ply_face_colours_survive_the_fix_and_are_named_elsewhere(client: TestClient) -> None:
    data = write_mesh(TETRA_VERTICES, FLIPPED, "ply", face_colors=UCHAR)
    response = fix(client, data, "f.ply", "ply")
    assert response.headers["x-faces-flipped"] == "1"
    assert "x-dropped" not in response.headers
    fixed = read_mesh(response.content, "fixed.ply")
    assert fixed.face_colors is not None and fixed.face_colors.tobytes() == UCHAR.tobytes()
    assert fix(client, data, "f.ply", "obj").headers["x-dropped"] == "face colours (OBJ holds none)"
    both = write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=UCHAR, face_colors=UCHAR)
    assert fix(client, both, "b.ply", "stl").headers["x-dropped"] == (
        "vertex colours (STL holds none); face colours (STL holds none)"
    )
