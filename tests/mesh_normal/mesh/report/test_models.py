"""mesh_normal.mesh.report.models: the typed report, built from the analysis, and mn.analyse."""

from __future__ import annotations

import dataclasses
import io
import json
import math
from pathlib import Path
from typing import Any, get_args

import numpy as np
import pytest
from pydantic import TypeAdapter, ValidationError

import mesh_normal as mn
from mesh_normal.files import SUFFIXES, read_mesh, write_mesh
from mesh_normal.mesh.report.analysis import analyse, analyse_mesh, build_report
from mesh_normal.mesh.report.models import Bounds, FileInfo, MeshFormat, MeshReport, Weld
from tests.meshes import (
    CUBE_OBJ,
    CUBE_ONE_FLIPPED_OBJ,
    HUGE_TETRA_OBJ,
    OPEN_BOX_OBJ,
    TETRA_OBJ,
    stepped_sides_cube,
)

#: The report's keys, in the order the JSON has always had them.
KEYS = [
    "file",
    "vertices",
    "faces",
    "source_faces",
    "unused_vertices",
    "area",
    "volume",
    "watertight",
    "winding_consistent",
    "orientation",
    "degenerate_faces",
    "degenerate_face_indices",
    "repeated_index_faces",
    "boundary_edges",
    "nonmanifold_edges",
    "components",
    "nonorientable_components",
    "bounds",
    "fix",
    "file_normals",
    "object_count",
    "objects",
    "weld",
    "notes",
    "problems",
]

#: A tetrahedron with coordinates near 1e200: its area (1e400) and volume overflow.


def report_of(text: str, name: str = "mesh.obj") -> MeshReport:
    data = text.encode()
    return build_report(analyse_mesh(read_mesh(data, name), name, len(data)))


def strict_json(text: str | bytes) -> Any:
    """Parse JSON, failing on NaN, Infinity and -Infinity (which json.loads accepts)."""

    def refuse(constant: str) -> None:
        raise ValueError(f"{constant} in the JSON")

    return json.loads(text, parse_constant=refuse)


def test_cube_with_one_flipped_face() -> None:
    report = report_of(CUBE_ONE_FLIPPED_OBJ, "flipped.obj")
    assert report.file == FileInfo(
        name="flipped.obj", format="obj", bytes=len(CUBE_ONE_FLIPPED_OBJ)
    )
    assert (report.vertices, report.faces, report.source_faces) == (8, 12, 12)
    assert report.area == 6.0
    assert report.winding_consistent is False and report.watertight is True
    assert report.orientation == "mixed"
    assert report.volume is None
    assert report.fix.faces_flipped == 1 and report.fix.components_changed == 1
    assert report.fix.flipped_face_indices == [0]
    [part] = report.fix.components
    assert (part.component, part.faces, part.closed, part.orientable) == (0, 12, True, True)
    assert (part.method, part.faces_flipped, part.volume) == ("volume", 1, pytest.approx(1.0))
    assert report.bounds == Bounds(min=[0.0, 0.0, 0.0], max=[1.0, 1.0, 1.0])
    assert report.file_normals is None
    assert [(p.code, p.severity) for p in report.problems] == [("winding", "error")]


def test_clean_cube() -> None:
    report = report_of(CUBE_OBJ)
    assert report.orientation == "outward"
    assert report.volume == pytest.approx(1.0, rel=1e-15)
    assert report.fix.faces_flipped == 0 and report.fix.flipped_face_indices == []
    assert report.problems == []


def test_open_box_is_a_warning() -> None:
    report = report_of(OPEN_BOX_OBJ)
    assert (report.watertight, report.boundary_edges, report.volume) == (False, 4, None)
    assert [(p.code, p.severity) for p in report.problems] == [("open", "warning")]
    assert report.fix.components[0].method == "visibility"


def test_the_json_keys_keep_their_names_and_order() -> None:
    report = report_of(CUBE_ONE_FLIPPED_OBJ)
    data = strict_json(report.to_json())
    assert list(data) == KEYS
    assert list(data["file"]) == ["name", "format", "bytes"]
    assert list(data["fix"]) == [
        "faces_flipped",
        "components_changed",
        "flipped_face_indices",
        "components",
    ]
    assert list(data["fix"]["components"][0]) == [
        "component",
        "faces",
        "closed",
        "orientable",
        "method",
        "faces_flipped",
        "volume",
        "depth",
        "inside",
        "touches",
    ]
    assert list(data["problems"][0]) == ["code", "severity", "title", "detail", "action", "python"]


def test_file_normals_of_an_stl() -> None:
    mesh = read_mesh(TETRA_OBJ.encode(), "t.obj")
    data = write_mesh(mesh.vertices, mesh.faces, "stl")
    stored = build_report(analyse_mesh(read_mesh(data, "t.stl"), "t.stl", len(data))).file_normals
    assert stored is not None
    data_keys = list(strict_json(stored.to_json()))
    assert data_keys == [
        "kind",
        "compared_with",
        "weighting",
        "crease_angle_degrees",
        "stored",
        "compared",
        "unusable",
        "agreeing",
        "opposite",
        "agreement_degrees",
        "median_angle_degrees",
        "max_angle_degrees",
    ]
    assert (stored.kind, stored.stored, stored.compared, stored.agreeing) == ("face", 4, 4, 4)
    assert stored.opposite == 0 and stored.unusable == 0
    assert stored.weighting is None and stored.crease_angle_degrees is None
    assert stored.max_angle_degrees is not None and stored.max_angle_degrees < 1e-4


def test_an_overflowing_area_is_null_never_nan() -> None:
    report = report_of(HUGE_TETRA_OBJ)
    assert report.area is None and report.volume is None
    assert "overflow" in [p.code for p in report.problems]
    data = strict_json(report.to_json())
    assert data["area"] is None and data["volume"] is None
    assert data["bounds"]["max"] == [1e200, 1e200, 1e200]


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan, np.float64(math.nan)])
def test_a_measure_that_is_not_finite_becomes_none(value: float) -> None:
    report = dataclasses.replace(report_of(CUBE_OBJ), area=value)
    assert report.area is None
    assert strict_json(report.to_json())["area"] is None
    assert report.to_dict()["area"] is None


def test_bounds_refuse_coordinates_that_are_not_finite() -> None:
    with pytest.raises(ValueError, match="finite"):
        Bounds(min=[0.0, 0.0, 0.0], max=[math.inf, 0.0, 0.0])
    with pytest.raises(ValueError, match="finite"):
        Weld(tolerance=math.nan, distance=0.0, joined_vertices=0)
    part = dataclasses.replace(report_of(CUBE_ONE_FLIPPED_OBJ).fix.components[0], volume=math.nan)
    assert part.volume is None  # a measure, not a finite number: null
    Bounds(min=[0.0, 0.0, 0.0], max=[1e308, 0.0, 0.0])  # finite, however large


def test_numpy_scalars_become_python_values() -> None:
    report = dataclasses.replace(
        report_of(CUBE_OBJ), vertices=np.int64(8), watertight=np.bool_(True), area=np.float64(6)
    )
    assert [type(value) for value in (report.vertices, report.watertight, report.area)] == [
        int,
        bool,
        float,
    ]
    assert strict_json(report.to_json())["vertices"] == 8


def test_the_schema_checks_what_a_report_holds() -> None:
    adapter = TypeAdapter(MeshReport)
    fields = report_of(CUBE_OBJ).to_dict()
    assert adapter.validate_python(fields) == report_of(CUBE_OBJ)
    for update in ({"orientation": "sideways"}, {"vertices": -1}, {"surplus": 1}):
        with pytest.raises(ValidationError):
            adapter.validate_python({**fields, **update})
    with pytest.raises(ValidationError):
        adapter.validate_python({**fields, "bounds": {"min": [0, 0, 0], "max": [0, 0]}})


def test_the_report_is_frozen() -> None:
    report = report_of(CUBE_OBJ)
    with pytest.raises(dataclasses.FrozenInstanceError):
        report.area = 1.0  # type: ignore[misc]


def test_the_format_literal_lists_every_readable_format() -> None:
    assert set(get_args(MeshFormat)) == set(SUFFIXES.values())


def _described(schema: dict[str, Any]) -> list[str]:
    """The properties of the schema and its definitions that have no description."""
    parts = {"MeshReport": schema, **schema.get("$defs", {})}
    return [
        f"{name}.{key}"
        for name, part in parts.items()
        for key, field in part["properties"].items()
        if not field.get("description")
    ]


def test_every_field_has_a_description() -> None:
    schema = TypeAdapter(MeshReport).json_schema()
    assert _described(schema) == []
    assert len(schema["$defs"]) == 8  # every nested part was looked at


# --- mn.analyse: the report from a path, bytes, a file object or a mesh already read ----------


def test_mn_analyse_is_the_report_from_a_path(tmp_path: Path) -> None:
    path = tmp_path / "flipped.obj"
    path.write_text(CUBE_ONE_FLIPPED_OBJ)
    report = mn.analyse(path)
    assert isinstance(report, MeshReport)
    assert report == report_of(CUBE_ONE_FLIPPED_OBJ, "flipped.obj")
    assert mn.analyse(str(path)) == report
    assert mn.analyse(path, filename="other.obj").file.name == "other.obj"


def test_mn_analyse_takes_bytes_a_file_object_or_a_loaded_mesh(tmp_path: Path) -> None:
    data = CUBE_OBJ.encode()
    assert mn.analyse(data, "cube.obj") == report_of(CUBE_OBJ, "cube.obj")
    assert mn.analyse(io.BytesIO(data), "cube.obj") == report_of(CUBE_OBJ, "cube.obj")
    path = tmp_path / "cube.obj"
    path.write_bytes(data)
    with path.open("rb") as stream:
        assert mn.analyse(stream).file.name == "cube.obj"
    from_mesh = mn.analyse(read_mesh(data, "cube.obj"))
    assert from_mesh.file == FileInfo(name=None, format="obj", bytes=0)
    assert from_mesh == dataclasses.replace(report_of(CUBE_OBJ), file=from_mesh.file)


def test_mn_analyse_is_the_report_and_the_arrays_stay_available() -> None:
    assert mn.analyse is analyse
    assert mn.MeshReport is MeshReport
    assert "MeshAnalysis" not in mn.__all__  # nothing public returns one
    analysis = analyse_mesh(read_mesh(CUBE_OBJ.encode(), "cube.obj"))
    assert analysis.faces.normals.shape == (12, 3)


def test_an_unreadable_source_raises_the_file_error(tmp_path: Path) -> None:
    with pytest.raises(mn.MeshFileError):
        mn.analyse(b"not a mesh at all", "broken.obj")
    with pytest.raises(FileNotFoundError):
        mn.analyse(tmp_path / "missing.obj")
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    with (tmp_path / "cube.obj").open() as text, pytest.raises(TypeError, match="binary mode"):
        mn.analyse(text)  # type: ignore[arg-type]


# --- the weld tolerance -----------------------------------------------------------------------


def stepped_cube(shift: float = 0.0, scale: float = 1.0, inward: bool = False) -> mn.LoadedMesh:
    """The cube of six sides a float32 step apart (tests.meshes), moved and scaled."""
    vertices, faces = stepped_sides_cube()
    return mn.LoadedMesh(vertices * scale + shift, faces[:, ::-1] if inward else faces, "ply", 108)


def test_without_a_weld_the_stepped_cube_is_six_open_sides() -> None:
    report = mn.analyse(stepped_cube())
    assert report.weld is None
    assert (report.watertight, report.components, report.boundary_edges) == (False, 6, 72)
    # Six open sides; each sees the others on its inner side: outward by visibility.
    assert report.volume is None and report.orientation == "outward"
    assert [c.method for c in report.fix.components] == ["visibility"] * 6
    assert [p.code for p in report.problems] == ["open", "components"]
    assert "weld" in report.problems[0].action  # the open mesh suggests one


def test_a_weld_makes_the_stepped_cube_one_closed_outward_shell() -> None:
    vertices, _ = stepped_sides_cube()
    report = mn.analyse(stepped_cube(), weld=1e-6)
    assert (report.watertight, report.components, report.boundary_edges) == (True, 1, 0)
    assert report.winding_consistent and report.orientation == "outward"
    assert report.volume == pytest.approx(1.0, rel=1e-6)
    assert report.problems == [] and report.fix.faces_flipped == 0
    assert report.weld is not None and report.weld.tolerance == 1e-6
    diagonal = math.dist(vertices.min(axis=0), vertices.max(axis=0))
    assert report.weld.distance == pytest.approx(1e-6 * diagonal, rel=1e-12)
    # 96 vertices, none identical, become the cube's 56 points: 40 joined.
    assert report.weld.joined_vertices == 40
    assert report.vertices == 96  # the vertices are kept
    inward = mn.analyse(stepped_cube(inward=True), weld=1e-6)
    assert inward.orientation == "inward" and inward.fix.faces_flipped == 108
    assert [p.code for p in inward.problems] == ["inward"]


@pytest.mark.parametrize(("shift", "scale"), [(1e4, 1.0), (1e8, 1.0), (0.0, 1e3), (-1e4, 1e-3)])
def test_the_weld_is_relative_to_the_mesh(shift: float, scale: float) -> None:
    report = mn.analyse(stepped_cube(shift, scale), weld=1e-6)
    assert (report.watertight, report.components, report.orientation) == (True, 1, "outward")
    assert report.fix.faces_flipped == 0
    inward = mn.analyse(stepped_cube(shift, scale, inward=True), weld=1e-6)
    assert inward.orientation == "inward" and inward.fix.faces_flipped == 108
    assert report.weld is not None and report.weld.distance is not None
    original = mn.analyse(stepped_cube(), weld=1e-6).weld
    assert original is not None and original.distance is not None
    assert report.weld.distance == pytest.approx(original.distance * scale, rel=1e-6)
    # Far out, float64 rounding may already merge a few copies near zero: fewer to join.
    assert 0 < report.weld.joined_vertices <= 40
    if shift == 0.0:
        assert report.weld.joined_vertices == 40


def test_a_weld_of_zero_is_shown_and_joins_nothing() -> None:
    report = mn.analyse(stepped_cube(), weld=0.0)
    assert report.weld is not None
    assert (report.weld.tolerance, report.weld.distance, report.weld.joined_vertices) == (0, 0, 0)
    assert dataclasses.replace(report, weld=None) == mn.analyse(stepped_cube())


@pytest.mark.parametrize("weld", [-1e-6, 0.0101, 1.0, math.nan, math.inf, "1e-6", True])
def test_a_weld_out_of_range_is_a_value_error_naming_it(weld: Any) -> None:
    with pytest.raises(ValueError, match=r"^weld must be a number from 0 to 0\.01 .*\.$"):
        mn.analyse(CUBE_OBJ.encode(), "cube.obj", weld=weld)


def test_the_weld_in_the_json() -> None:
    data = strict_json(mn.analyse(stepped_cube(), weld=1e-6).to_json())
    assert list(data["weld"]) == ["tolerance", "distance", "joined_vertices"]
    assert data["weld"]["joined_vertices"] == 40
    assert strict_json(mn.analyse(stepped_cube()).to_json())["weld"] is None


def test_a_weld_over_a_box_beyond_the_double_range_joins_nothing_wrongly() -> None:
    # The box's extent (4e308) overflows; the distance does not, and nothing far apart joins.
    vertices = np.array([[-1e308, 0, 0], [1e308, 0, 0], [0, 1e308, 0], [0, 0, 1e308]])
    mesh = mn.LoadedMesh(vertices, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]), "ply", 4)
    report = mn.analyse(mesh, weld=0.01)
    assert report.weld is not None and report.weld.joined_vertices == 0
    assert report.weld.distance == pytest.approx(0.01 * math.sqrt(4 + 1 + 1) * 1e308)
    assert report.watertight
