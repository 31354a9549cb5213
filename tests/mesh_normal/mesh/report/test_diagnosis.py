"""mesh_normal.mesh.report.diagnosis: the problems read from a report, and their snippets."""

from __future__ import annotations

from typing import Any, get_args

import numpy as np
import pytest
from pydantic import TypeAdapter

from mesh_normal.files import read_mesh, write_mesh
from mesh_normal.mesh.report.analysis import analyse_mesh, build_report
from mesh_normal.mesh.report.diagnosis import CHECKS, Problem, ProblemCode, problems
from mesh_normal.mesh.report.models import FileNormals, MeshReport
from tests.meshes import CUBE_OBJ, CUBE_ONE_FLIPPED_OBJ, NESTED_CASES, Shell, box, built, turned
from tests.paths import DATA


def clean() -> MeshReport:
    data = CUBE_OBJ.encode()
    return build_report(analyse_mesh(read_mesh(data, "cube.obj"), "cube.obj", len(data)))


def changed(**update: Any) -> MeshReport:
    """The clean cube's report with some values changed, validated again."""
    return TypeAdapter(MeshReport).validate_python({**clean().to_dict(), **update, "problems": []})


def codes(report: MeshReport) -> list[str]:
    return [item.code for item in problems(report)]


def test_a_clean_report_has_no_problem() -> None:
    assert problems(clean()) == []


@pytest.mark.parametrize(
    ("update", "expected"),
    [
        ({"orientation": "inward"}, ["inward"]),
        ({"orientation": "mixed"}, ["mixed"]),
        ({"boundary_edges": 3, "watertight": False, "volume": None}, ["open"]),
        ({"nonmanifold_edges": 2}, ["nonmanifold"]),
        ({"nonorientable_components": 1}, ["nonorientable"]),
        ({"degenerate_faces": 2, "repeated_index_faces": 1}, ["degenerate"]),
        ({"unused_vertices": 1}, ["unused_vertices"]),
        ({"components": 2}, ["components"]),
        ({"area": None}, ["overflow"]),
        ({"volume": None}, ["overflow"]),
        ({"area": 0.0}, ["underflow"]),
    ],
)
def test_each_value_of_the_report_raises_its_problem(
    update: dict[str, Any], expected: list[str]
) -> None:
    assert codes(changed(**update)) == expected


def test_the_problems_come_most_serious_first() -> None:
    report = changed(unused_vertices=1, boundary_edges=3, watertight=False, orientation="inward")
    found = problems(report)
    assert [item.severity for item in found] == ["error", "warning", "info"]
    assert [item.code for item in found] == ["inward", "open", "unused_vertices"]


def test_winding_reads_the_fix() -> None:
    fix = {**clean().fix.to_dict(), "faces_flipped": 3, "flipped_face_indices": [0, 1, 2]}
    found = problems(changed(winding_consistent=False, volume=None, fix=fix))
    assert [item.code for item in found] == ["winding"]
    assert "flips 3 faces" in found[0].detail


def test_the_overflow_names_both_measures() -> None:
    [item] = problems(changed(area=None, volume=None))
    assert item.title == "The total area and volume are beyond the double range"


def test_an_area_that_underflows_is_said_so() -> None:
    # |B - A| * |C - A| = 1e-330: below the smallest double, though the face has a normal.
    data = b"v 0 0 0\nv 1e-160 0 0\nv 0 1e-170 0\nf 1 2 3\n"
    report = build_report(analyse_mesh(read_mesh(data, "tiny.obj"), "tiny.obj", len(data)))
    assert (report.area, report.degenerate_faces) == (0.0, 0)
    [item] = [item for item in problems(report) if item.code == "underflow"]
    assert item.title == "The total area is below the smallest double"
    assert "reported as 0.0" in item.detail
    # Faces that are flat are a different problem: their area is 0.0 in truth.
    flat = changed(area=0.0, degenerate_faces=12, repeated_index_faces=0)
    assert "underflow" not in codes(flat)


def test_file_normals_that_point_the_other_way() -> None:
    stored = FileNormals(
        kind="vertex",
        compared_with="our angle-weighted vertex normals",
        weighting="angle",
        crease_angle_degrees=None,
        stored=8,
        compared=8,
        unusable=0,
        agreeing=6,
        opposite=2,
        agreement_degrees=1.0,
        median_angle_degrees=0.0,
        max_angle_degrees=180.0,
    )
    [item] = problems(changed(file_normals=stored.to_dict()))
    assert (item.code, item.severity) == ("file_normals", "warning")
    assert item.title == "2 normals stored in the file point the other way"
    assert "Of 8 vertex normals in the file, 2 differ" in item.detail


def test_every_check_has_a_code() -> None:
    assert len(CHECKS) == len(get_args(ProblemCode))


def every_problem() -> list[Problem]:
    """One report that raises every problem that carries a Python snippet."""
    fix = {**clean().fix.to_dict(), "faces_flipped": 1, "flipped_face_indices": [0]}
    stored = {
        "kind": "face",
        "compared_with": "our face normals",
        "weighting": None,
        "crease_angle_degrees": None,
        "stored": 12,
        "compared": 12,
        "unusable": 0,
        "agreeing": 11,
        "opposite": 1,
        "agreement_degrees": 1.0,
        "median_angle_degrees": 0.0,
        "max_angle_degrees": 180.0,
    }
    found = [
        *problems(changed(winding_consistent=False, volume=None, fix=fix)),
        *problems(changed(orientation="inward")),
        *problems(changed(orientation="mixed")),
        *problems(changed(degenerate_faces=1)),
        *problems(changed(file_normals=stored)),
    ]
    assert [item.code for item in found] == [
        "winding",
        "inward",
        "mixed",
        "degenerate",
        "file_normals",
    ]
    return found


@pytest.mark.parametrize("item", every_problem(), ids=lambda item: item.code)
def test_the_python_snippets_use_the_public_api_and_run(item: Problem) -> None:
    assert item.python is not None
    assert "from mesh_normal" not in item.python
    if "mn." in item.python:
        assert item.python.startswith("import mesh_normal as mn\n")
    mesh = read_mesh(CUBE_ONE_FLIPPED_OBJ.encode(), "flipped.obj")
    given = {"vertices": mesh.vertices, "faces": mesh.faces}
    scope: dict[str, Any] = dict(given)
    exec(item.python, scope)  # the snippet as a reader would paste it
    made = {name for name, value in scope.items() if given.get(name) is not value}
    results = made - {"__builtins__", "mn", "fixed", "keep"}
    assert results, "the snippet assigns faces or normals"
    assert all(isinstance(scope[name], np.ndarray) for name in results)
    assert all(len(scope[name]) for name in results)


# --- naming the objects -----------------------------------------------------------------------


def two_objects(turned: str | None = None, drop: str | None = None) -> MeshReport:
    """tests/data/two_objects.obj (a cube and a tetrahedron on its corner), with the object
    ``turned`` wound inside out (every face reversed), or ``drop``'s first face left out."""
    lines, name, dropped = [], "", False
    for line in (DATA / "two_objects.obj").read_text().splitlines():
        if line.startswith("o "):
            name = line.split()[1]
        if line.startswith("f ") and name == turned:
            line = " ".join(["f", *line.split()[:0:-1]])
        if line.startswith("f ") and name == drop and not dropped:
            dropped = True
            continue
        lines.append(line)
    data = "\n".join(lines).encode()
    return build_report(analyse_mesh(read_mesh(data, "two.obj"), "two.obj", len(data)))


def detail(report: MeshReport, code: str) -> str:
    [item] = [item for item in report.problems if item.code == code]
    return item.detail


def test_the_inside_out_object_is_named() -> None:
    report = two_objects(turned="tetra")
    assert report.orientation == "mixed"
    assert "The object 'tetra' is wound inward: the fix flips its 4 faces." in detail(
        report, "mixed"
    )
    assert "'cube'" not in detail(report, "mixed")
    report = two_objects(turned="cube")
    assert "The object 'cube' is wound inward: the fix flips its 12 faces." in detail(
        report, "mixed"
    )
    assert "tetra" not in detail(report, "mixed")


def test_every_object_inward_names_them_all() -> None:
    data = (DATA / "two_objects.obj").read_text()
    turned = "\n".join(
        " ".join(["f", *line.split()[:0:-1]]) if line.startswith("f ") else line
        for line in data.splitlines()
    ).encode()
    report = build_report(analyse_mesh(read_mesh(turned, "t.obj"), "t.obj", len(turned)))
    assert report.orientation == "inward"
    assert (
        "The objects 'cube' (12 faces) and 'tetra' (4 faces) are wound inward: the fix flips "
        "their faces." in detail(report, "inward")
    )


def test_a_clean_file_with_objects_names_none() -> None:
    report = two_objects()
    assert all("'cube'" not in item.detail for item in report.problems)


def test_an_object_with_some_faces_flipped_is_named_with_its_count() -> None:
    from tests.mesh_normal.mesh.report.test_objects import two_cubes
    from tests.meshes import CUBE_OBJ_FACES

    text = two_cubes([CUBE_OBJ_FACES[0][::-1], *CUBE_OBJ_FACES[1:]], "lid").encode()
    report = build_report(analyse_mesh(read_mesh(text, "c.obj"), "c.obj", len(text)))
    assert "The fix flips some faces of the object 'lid' (1 of 12)." in detail(report, "winding")


def test_many_inward_objects_are_named_up_to_three_then_counted() -> None:
    from tests.mesh_normal.mesh.report.test_objects import cube_points, faces
    from tests.meshes import CUBE_OBJ_FACES

    inward = [face[::-1] for face in CUBE_OBJ_FACES]
    text = "".join(
        f"o box{i}\n" + cube_points(3 * i) + faces(inward if i else CUBE_OBJ_FACES, 8 * i)
        for i in range(6)
    ).encode()
    report = build_report(analyse_mesh(read_mesh(text, "b.obj"), "b.obj", len(text)))
    assert (
        "The objects 'box1' (12 faces), 'box2' (12 faces), 'box3' (12 faces) and 2 more are "
        "wound inward" in detail(report, "mixed")
    )


def test_an_open_object_is_named() -> None:
    report = two_objects(drop="tetra")
    assert "The object 'tetra' is not closed on its own." in detail(report, "open")
    assert "'cube'" not in detail(report, "open")


def test_the_snippets_repeat_the_weld() -> None:
    flipped = changed(
        orientation="mixed", weld={"tolerance": 1e-6, "distance": 1.7e-6, "joined_vertices": 3}
    )
    [item] = problems(flipped)
    assert item.python is not None and "mn.orient(vertices, faces, weld=1e-06)" in item.python
    assert "weld=" not in (problems(changed(orientation="mixed"))[0].python or "")


def nested_report(shells: list[tuple[Shell, bool]], wrong: list[int]) -> MeshReport:
    """The report on the shells (see tests/mesh_normal/mesh/test_nesting.py) as a PLY file,
    the ``wrong`` ones turned the other way."""
    vertices, faces, labels = built(*shells)
    data = write_mesh(vertices, turned(faces, labels, wrong), "ply")
    return build_report(analyse_mesh(read_mesh(data, "nested.ply"), "nested.ply", len(data)))


def test_a_cavity_is_named_in_plain_words() -> None:
    shells = list(NESTED_CASES["hollow ball"][0])
    right = nested_report(shells, [])
    assert codes(right) == ["components", "cavities"]
    [item] = [item for item in problems(right) if item.code == "cavities"]
    assert item.title == "The mesh has 1 cavity"
    assert item.detail.startswith(
        "Part 1 is a cavity inside part 0; its faces point into the cavity, as they should."
    )
    assert item.action.startswith("Nothing to do.")
    assert [(p.depth, p.inside, p.touches) for p in right.fix.components] == [
        (0, None, None),
        (1, 0, None),
    ]
    assert right.volume is not None and right.fix.components[1].volume is not None
    assert right.fix.components[1].volume < 0  # the volumes are the material's
    wrong = nested_report(shells, [1])
    assert codes(wrong) == ["mixed", "components", "cavities"]
    [item] = [item for item in problems(wrong) if item.code == "cavities"]
    assert item.detail.startswith(
        "Part 1 is a cavity inside part 0; its faces point the other way: the fix turns them "
        "to point into the cavity."
    )
    assert wrong.fix.faces_flipped == wrong.fix.components[1].faces
    [mixed] = [item for item in problems(wrong) if item.code == "mixed"]
    assert "not all of them face away from the material" in mixed.detail
    assert mixed.action.endswith(
        "face away from the material (out, or into their cavity) on its own."
    )


def test_a_body_in_a_cavity_and_more_parts_are_named() -> None:
    report = nested_report(list(NESTED_CASES["three levels of hollow balls"][0]), [])
    [item] = [item for item in problems(report) if item.code == "cavities"]
    assert item.title == "The mesh has 3 cavities"
    assert "Part 2 is a body in the cavity part 1; its faces point out of it, as they should." in (
        item.detail
    )
    assert "2 more parts lie inside others." in item.detail


def test_a_part_that_touches_another_is_said_so() -> None:
    report = nested_report([(box(2.0), False), (box(1.0, (0.0, 0.0, -0.5)), True)], [])
    assert codes(report) == ["touching", "components"]
    [item] = [item for item in problems(report) if item.code == "touching"]
    assert item.title == "1 closed part touches another"
    assert item.detail.startswith("Part 1 touches part 0.")
    assert report.fix.components[1].method == "none"
