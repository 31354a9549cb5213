"""mn.show: a Plotly figure of a mesh (problem faces coloured, an up axis) or of a cloud; an
ImportError naming the extra without Plotly; imported only when called."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import plotly.graph_objects as go
import pytest
import trimesh

import mesh_normal as mn
from mesh_normal.notebook import show as show_module
from tests.mesh_normal.points import _clouds as clouds
from tests.meshes import CUBE_FACES, CUBE_VERTICES


def inward(faces: np.ndarray, rows: list[int]) -> np.ndarray:
    faces = faces.copy()
    faces[rows] = faces[rows][:, ::-1]
    return faces


def traces(figure: go.Figure) -> dict[str, go.BaseTraceType]:
    return {trace.name: trace for trace in figure.data}


def test_a_mesh_is_drawn_with_its_problem_faces_coloured() -> None:
    faces = inward(CUBE_FACES, [1, 6])[:-1]  # two faces flipped, one missing (a hole)
    figure = mn.show(trimesh.Trimesh(CUBE_VERTICES, faces, process=False))
    assert isinstance(figure, go.Figure)
    found = traces(figure)
    flipped = found["flipped by the fix: 2"]
    assert flipped.type == "mesh3d" and flipped.color == "#f76707" and len(flipped.i) == 2
    assert len(found["on a boundary edge: 3"].i) == 3 and len(found["no problem: 6"].i) == 6
    assert "flipped normals" in found and "normals" in found
    assert figure.layout.scene.camera.up.z == 1 and figure.layout.title.text.endswith("z up")


def test_degenerate_faces_are_dots() -> None:
    vertices = np.vstack([CUBE_VERTICES, [[0.5, 0.5, 0.5]]])
    faces = np.vstack([CUBE_FACES, [[8, 8, 0]]])
    dots = traces(mn.show((vertices, faces)))["no area (degenerate): 1"]
    assert dots.type == "scatter3d" and dots.mode == "markers"


def test_the_up_axis_is_the_files_or_chosen() -> None:
    gltf = mn.read_mesh("tests/data/fuze.obj")
    assert mn.show(gltf).layout.scene.camera.up.y == 1  # OBJ is drawn Y-up
    assert mn.show(gltf, up="x").layout.scene.camera.up.x == 1
    with pytest.raises(ValueError, match='up must be "x", "y" or "z", not \'w\''):
        mn.show(gltf, up="w")


def test_a_large_mesh_keeps_its_problem_faces(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(show_module, "SHOW_FACES", 6)
    found = traces(mn.show((CUBE_VERTICES, inward(CUBE_FACES, [1, 6]))))
    assert len(found["flipped by the fix: 2"].i) == 2
    assert sum(len(t.i) for t in found.values() if t.type == "mesh3d") <= 6


def test_a_cloud_is_drawn_coloured_by_its_normals() -> None:
    points, _ = clouds.sphere(200)
    figure = mn.show(points)
    dots = traces(figure)["points"]
    assert dots.mode == "markers" and len(dots.x) == 200
    assert all(color.startswith("rgb(") for color in dots.marker.color)
    assert "200 points" in figure.layout.title.text
    assert len(traces(mn.show(mn.read_points("tests/data/sphere.ply")))["points"].x) == 422


def test_anything_else_gets_a_sentence() -> None:
    with pytest.raises(TypeError, match=r"show takes a mesh .* or a point cloud .*, not int"):
        mn.show(7)


def test_without_plotly_the_error_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "plotly", None)
    monkeypatch.setitem(sys.modules, "plotly.graph_objects", None)
    with pytest.raises(ImportError, match=r"pip install mesh-normal\[show\]"):
        mn.show((CUBE_VERTICES, CUBE_FACES))


def test_plotly_is_imported_only_when_a_figure_is_asked_for() -> None:
    code = "import sys, mesh_normal as mn; mn.show; print('plotly' in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "False"
