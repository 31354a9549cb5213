"""The reports in a notebook: HTML with the diagnosis first, the key figures, the problems;
every text escaped, nothing loaded from elsewhere."""

from __future__ import annotations

import re
from html import unescape

import numpy as np

import mesh_normal as mn
from mesh_normal.points import analyse_points
from tests.mesh_normal.points import _clouds as clouds
from tests.meshes import CUBE_FACES, CUBE_VERTICES, obj_text

CUBE_POINTS = "".join(f"v {x:g} {y:g} {z:g}\n" for x, y, z in CUBE_VERTICES.tolist())

HOSTILE_NAME = '<img src=x onerror="alert(1)">&cube.obj'


def inward_cube_report() -> mn.MeshReport:
    faces = CUBE_FACES.copy()
    faces[[1, 6]] = faces[[1, 6]][:, ::-1]
    return mn.analyse(obj_text(CUBE_POINTS, faces.tolist()).encode(), HOSTILE_NAME)


def text_of(html: str) -> str:
    return unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html)))


def test_a_mesh_report_shows_the_diagnosis_first_then_the_figures_then_the_problems() -> None:
    report = inward_cube_report()
    html = report._repr_html_()
    problem = report.problems[0]
    headline, table, listed = (
        html.index(problem.title),
        html.index("<table"),
        html.index(problem.detail),
    )
    assert headline < table < listed
    text = text_of(html)
    assert "Faces the fix flips 2" in text and "Watertight yes" in text
    assert "Winding consistent no" in text and "Error" in text
    for item in report.problems:
        assert item.title in html and item.action in html


def test_a_file_name_and_every_text_are_escaped() -> None:
    html = inward_cube_report()._repr_html_()
    assert (
        "<img" not in html and "&lt;img src=x onerror=&quot;alert(1)&quot;&gt;&amp;cube.obj" in html
    )


def test_the_html_loads_nothing_and_styles_inline() -> None:
    html = inward_cube_report()._repr_html_()
    assert not re.search(r"<(script|link|style)\b|https?:", html)
    assert html.startswith('<div style="') and html.count("<div") == html.count("</div>")


def test_a_mesh_without_problems_says_so() -> None:
    text = text_of(mn.analyse((CUBE_VERTICES, CUBE_FACES))._repr_html_())
    assert "OK No problems found" in text and "A mesh in memory" in text


def test_a_point_report_shows_its_diagnosis_and_figures() -> None:
    points, _ = clouds.sphere(300)
    points[0] = np.nan
    report = analyse_points(points, k=12).report
    html = report._repr_html_()
    text = text_of(html)
    assert text.index(report.diagnosis[0]) < text.index("Points 300")
    assert "With a normal 299" in text and "Without a normal 1" in text
    assert all(sentence in text for sentence in report.diagnosis)
    assert "A point cloud in memory" in text and "Warning" in text
