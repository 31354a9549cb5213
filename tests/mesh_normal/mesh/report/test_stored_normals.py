"""Stored normals compared like with like: vertex normals with vertex normals, corner normals
with corner normals, and the summary's worst angle never below its median.

Each case writes normals we computed into a file the way exporters do (6 decimals), reads it
back and checks that the report finds them agreeing, and with which of our normals.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

import mesh_normal as mn
from mesh_normal.files import LoadedMesh, read_mesh, write_mesh
from mesh_normal.mesh.corners import corner_normals
from mesh_normal.mesh.report.analysis import analyse_mesh, build_report
from mesh_normal.mesh.report.models import FileNormals, MeshReport
from mesh_normal.mesh.report.stored_normals import (
    TRIED_CREASES,
    TRIED_WEIGHTINGS,
    Candidate,
    angles_between,
    unit_rows,
)
from mesh_normal.mesh.vertices import Weighting, vertex_normals
from tests.paths import DATA

Floats = NDArray[np.float64]
Ints = NDArray[np.intp]


def blob(seed: int = 0) -> tuple[Floats, Ints]:
    """A closed, irregular, smooth-ish surface: a noisy subdivided octahedron on an ellipsoid.

    Irregular triangles make the four weightings differ by far more than 6 decimals.
    """
    points = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    triangles = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5)]
    triangles.append((0, 3, 5))
    vertices = np.asarray(points, dtype=np.float64)
    faces = np.asarray(triangles, dtype=np.intp)
    for _ in range(3):
        vertices, faces = _subdivide(vertices, faces)
    vertices /= np.linalg.norm(vertices, axis=1)[:, None]
    rng = np.random.default_rng(seed)
    vertices = vertices * [1.0, 0.7, 1.3] + rng.normal(0.0, 0.03, vertices.shape)
    return vertices, faces


def _subdivide(vertices: Floats, faces: Ints) -> tuple[Floats, Ints]:
    middles: dict[tuple[int, int], int] = {}
    points = vertices.tolist()

    def middle(a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in middles:
            middles[key] = len(points)
            points.append(((vertices[a] + vertices[b]) / 2).tolist())
        return middles[key]

    result = []
    for a, b, c in faces.tolist():
        ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
        result += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return np.asarray(points), np.asarray(result, dtype=np.intp)


def prism(sides: int = 8, seed: int = 1) -> tuple[Floats, Ints]:
    """A closed noisy prism: 45-degree edges between sides (for 8), 90 at the caps."""
    angles = np.arange(sides) * 2 * math.pi / sides
    ring = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    bottom = np.column_stack([ring, np.zeros(sides)])
    top = np.column_stack([ring, np.full(sides, 2.0)])
    centres = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
    rng = np.random.default_rng(seed)
    vertices = np.vstack([bottom, top, centres]) + rng.normal(0.0, 0.01, (2 * sides + 2, 3))
    faces = []
    for i in range(sides):
        j = (i + 1) % sides
        faces += [(i, j, sides + j), (i, sides + j, sides + i)]  # the side, outward
        faces += [(2 * sides, j, i), (2 * sides + 1, sides + i, sides + j)]  # the caps
    return vertices, np.asarray(faces, dtype=np.intp)


def six(value: float) -> str:
    return f"{value:.6f}"


def ply_text(vertices: Floats, faces: Ints, normals: Floats) -> bytes:
    header = (
        f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    rows = "".join(
        " ".join(map(six, [*point, *normal])) + "\n"
        for point, normal in zip(vertices.tolist(), normals.tolist(), strict=True)
    )
    return (header + rows + "".join(f"3 {a} {b} {c}\n" for a, b, c in faces.tolist())).encode()


def obj_vertex_normals(
    vertices: Floats, faces: Ints, normals: Floats, spare: bool = False
) -> bytes:
    """OBJ whose vn follow v (``f a//a``); ``spare`` adds a vertex no face uses."""
    points = np.vstack([vertices, [[9.0, 9.0, 9.0]]]) if spare else vertices
    spared = np.vstack([normals, [[0.0, 0.0, 1.0]]]) if spare else normals
    lines = ["v " + " ".join(map(six, point)) for point in points.tolist()]
    lines += ["vn " + " ".join(map(six, normal)) for normal in spared.tolist()]
    lines += [f"f {a}//{a} {b}//{b} {c}//{c}" for a, b, c in (faces + 1).tolist()]
    return ("\n".join(lines) + "\n").encode()


def obj_corner_normals(vertices: Floats, faces: Ints, corners: Floats) -> bytes:
    """OBJ with one vn per face corner, as exporters write split normals."""
    flat = corners.reshape(-1, 3)
    lines = ["v " + " ".join(map(six, point)) for point in vertices.tolist()]
    lines += ["vn " + " ".join(map(six, normal)) for normal in flat.tolist()]
    lines += [
        f"f {a}//{3 * k + 1} {b}//{3 * k + 2} {c}//{3 * k + 3}"
        for k, (a, b, c) in enumerate((faces + 1).tolist())
    ]
    return ("\n".join(lines) + "\n").encode()


def report_of(data: bytes, name: str) -> MeshReport:
    return build_report(analyse_mesh(read_mesh(data, name), name, len(data)))


def strict(report: MeshReport) -> Any:
    def refuse(name: str) -> None:
        pytest.fail(f"{name} in the report")

    return json.loads(report.to_json(), parse_constant=refuse)


def assert_all_agree(report: MeshReport) -> FileNormals:
    stored = report.file_normals
    assert stored is not None
    assert stored.compared == stored.stored and stored.unusable == 0
    assert stored.agreeing == stored.compared and stored.opposite == 0
    assert stored.max_angle_degrees is not None and stored.median_angle_degrees is not None
    # 6 decimals of a unit vector: within about 6e-5 degrees.
    assert stored.median_angle_degrees <= stored.max_angle_degrees < 1e-3
    assert "file_normals" not in [item.code for item in report.problems]
    assert "disagree" not in json.dumps(strict(report))
    return stored


def test_the_test_meshes_tell_the_weightings_apart() -> None:
    """Else finding the right weighting below would prove nothing."""
    vertices, faces = blob()
    normals = [vertex_normals(vertices, faces, weighting).normals for weighting in TRIED_WEIGHTINGS]
    for i, first in enumerate(normals):
        for second in normals[i + 1 :]:
            worst = np.degrees(np.arccos(np.clip(np.sum(first * second, axis=1), -1, 1))).max()
            assert worst > 0.05


@pytest.mark.parametrize("weighting", TRIED_WEIGHTINGS)
def test_ply_vertex_normals_find_their_weighting(weighting: Weighting) -> None:
    vertices, faces = blob()
    normals = vertex_normals(vertices, faces, weighting).normals
    stored = assert_all_agree(report_of(ply_text(vertices, faces, normals), "blob.ply"))
    assert (stored.kind, stored.weighting, stored.crease_angle_degrees) == (
        "vertex",
        weighting,
        None,
    )
    assert stored.compared_with.startswith(f"our {_word(weighting)} vertex normals")


def _word(weighting: Weighting) -> str:
    return {"uniform": "unweighted (uniform)", "max": "Max-weighted"}.get(
        weighting, f"{weighting}-weighted"
    )


@pytest.mark.parametrize("weighting", TRIED_WEIGHTINGS)
def test_obj_vn_that_follow_v_are_vertex_normals(weighting: Weighting) -> None:
    """They are compared as vertex normals: compared with corner normals, they would disagree
    at every crease."""
    vertices, faces = prism()
    normals = vertex_normals(vertices, faces, weighting).normals
    mesh = read_mesh(obj_vertex_normals(vertices, faces, normals), "prism.obj")
    assert mesh.file_vertex_normals is not None and mesh.file_corner_normals is not None
    stored = assert_all_agree(report_of(obj_vertex_normals(vertices, faces, normals), "p.obj"))
    assert (stored.kind, stored.weighting, stored.stored) == ("vertex", weighting, len(vertices))


def test_obj_vn_that_follow_v_with_a_spare_vertex_match_crease_180() -> None:
    """The reader keeps such normals per corner only; the smooth corners (180) match them."""
    vertices, faces = prism()
    normals = vertex_normals(vertices, faces, "angle").normals
    data = obj_vertex_normals(vertices, faces, normals, spare=True)
    assert read_mesh(data, "p.obj").file_vertex_normals is None
    stored = assert_all_agree(report_of(data, "p.obj"))
    assert (stored.kind, stored.weighting, stored.crease_angle_degrees) == ("corner", "angle", 180)
    assert "crease angle of 180°" in stored.compared_with


@pytest.mark.parametrize("crease", TRIED_CREASES)
@pytest.mark.parametrize("weighting", TRIED_WEIGHTINGS)
def test_obj_corner_normals_find_their_crease_and_weighting(
    crease: float, weighting: Weighting
) -> None:
    vertices, faces = prism()
    corners = corner_normals(vertices, faces, crease_angle=crease, weighting=weighting).normals
    stored = assert_all_agree(report_of(obj_corner_normals(vertices, faces, corners), "p.obj"))
    if crease == 180:  # the same at every corner of a vertex: the reader sees vertex normals
        assert (stored.kind, stored.weighting) == ("vertex", weighting)
        return
    assert (stored.kind, stored.crease_angle_degrees, stored.weighting) == (
        "corner",
        crease,
        weighting,
    )
    assert f"crease angle of {crease:g}°" in stored.compared_with


def test_the_prism_tells_the_creases_apart() -> None:
    vertices, faces = prism()
    found = [corner_normals(vertices, faces, crease_angle=c).normals for c in TRIED_CREASES]
    for i, first in enumerate(found):
        for second in found[i + 1 :]:
            assert not np.allclose(first, second, atol=1e-3)


def test_stl_facet_normals_are_face_normals() -> None:
    vertices, faces = blob()
    stored = assert_all_agree(report_of(write_mesh(vertices, faces, "stl"), "blob.stl"))
    assert (stored.kind, stored.weighting, stored.crease_angle_degrees) == ("face", None, None)
    assert stored.compared_with == "our face normals"
    assert stored.max_angle_degrees is not None and stored.max_angle_degrees < 1e-4  # float32


def test_inside_out_vertex_normals_are_opposite_for_every_weighting() -> None:
    vertices, faces = blob()
    normals = -vertex_normals(vertices, faces, "area").normals
    report = report_of(ply_text(vertices, faces, normals), "blob.ply")
    stored = report.file_normals
    assert stored is not None
    assert stored.opposite == stored.compared == len(vertices) and stored.agreeing == 0
    assert stored.weighting == "area"  # the lines match, up to the sign
    assert stored.median_angle_degrees is not None and stored.max_angle_degrees is not None
    assert 179.0 < stored.median_angle_degrees <= stored.max_angle_degrees <= 180.0
    [problem] = [item for item in report.problems if item.code == "file_normals"]
    assert "disagree" in problem.detail


def tilted(normals: Floats, radians: Floats, seed: int) -> Floats:
    """Each unit row turned by its angle about a random axis perpendicular to it."""
    rng = np.random.default_rng(seed)
    axis = np.cross(normals, rng.normal(size=normals.shape))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    return normals * np.cos(radians)[:, None] + axis * np.sin(radians)[:, None]


def test_the_median_never_exceeds_the_maximum_below_cosine_resolution() -> None:
    """With angles of 1e-9 rad every cosine is 1: a summary by cosine would take the first
    row as the worst (angle 0 here) while its median row has 1e-9 rad."""
    vertices, faces = blob()
    ours = vertex_normals(vertices, faces, "angle").normals
    radians = np.full(len(ours), 1e-9)
    radians[0] = 0.0
    radians[-1] = 3e-9
    theirs = tilted(ours, radians, seed=3)
    theirs[0] = ours[0]
    mesh = LoadedMesh(vertices, faces, "ply", len(faces), file_vertex_normals=theirs)
    stored = build_report(analyse_mesh(mesh)).file_normals
    assert stored is not None
    assert stored.median_angle_degrees is not None and stored.max_angle_degrees is not None
    assert stored.median_angle_degrees <= stored.max_angle_degrees
    assert stored.median_angle_degrees == pytest.approx(math.degrees(1e-9), rel=1e-3)
    assert stored.max_angle_degrees == pytest.approx(math.degrees(3e-9), rel=1e-3)
    assert stored.weighting == "angle"


def test_angles_are_accurate_over_the_whole_range() -> None:
    rng = np.random.default_rng(5)
    ours = rng.normal(size=(2000, 3))
    ours /= np.linalg.norm(ours, axis=1)[:, None]
    radians = np.concatenate([10.0 ** rng.uniform(-12, 0, 1000), rng.uniform(0, math.pi, 1000)])
    theirs = tilted(ours, radians, seed=6) * rng.uniform(1e-3, 1e3, (2000, 1))
    unit, usable = unit_rows(theirs)
    found = angles_between(unit, usable, Candidate(ours, np.zeros(2000, dtype=bool))).radians
    np.testing.assert_allclose(found, radians, rtol=1e-6, atol=1e-15)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    noise=st.sampled_from([0.0, 1e-12, 1e-9, 1e-6, 1e-3, 0.1, 1.0]),
    flips=st.floats(0.0, 0.5),
    kind=st.sampled_from(["vertex", "corner", "face"]),
)
def test_median_is_at_most_the_maximum(seed: int, noise: float, flips: float, kind: str) -> None:
    """Random small meshes, their own normals tilted by noise and some turned around."""
    rng = np.random.default_rng(seed)
    vertices = rng.normal(size=(int(rng.integers(3, 12)), 3))
    faces = rng.integers(0, len(vertices), size=(int(rng.integers(1, 16)), 3))
    mesh = LoadedMesh(vertices, faces, "ply", len(faces))
    geometry = analyse_mesh(mesh).geometry
    ours = {
        "vertex": lambda: vertex_normals(geometry, weighting="angle").normals,
        "corner": lambda: corner_normals(geometry).normals.reshape(-1, 3),
        "face": lambda: mn.face_normals(geometry).normals,
    }[kind]()
    ours = np.where(np.linalg.norm(ours, axis=1)[:, None] > 0, ours, [0.0, 0.0, 1.0])
    theirs = tilted(ours, np.abs(rng.normal(0, noise, len(ours))), seed)
    theirs[rng.uniform(size=len(ours)) < flips] *= -1
    shape = {"corner": (len(faces), 3, 3)}.get(kind, theirs.shape)
    stored = replace(mesh, **{f"file_{kind}_normals": theirs.reshape(shape)})
    report = build_report(analyse_mesh(stored))
    strict(report)
    found = report.file_normals
    assert found is not None and found.kind == kind
    if found.compared:
        assert found.median_angle_degrees is not None and found.max_angle_degrees is not None
        assert 0.0 <= found.median_angle_degrees <= found.max_angle_degrees <= 180.0
        assert found.agreeing + found.opposite <= found.compared
    else:
        assert found.median_angle_degrees is None and found.max_angle_degrees is None


@pytest.mark.parametrize(("kind", "weighting"), [("vertex", "max"), ("corner", "uniform")])
def test_the_advice_recomputes_the_normals_the_file_holds(kind: str, weighting: Weighting) -> None:
    """Inside-out normals: the snippet makes the file's kind and weighting, the right way out."""
    vertices, faces = prism()
    if kind == "vertex":
        made = vertex_normals(vertices, faces, weighting).normals
        data = obj_vertex_normals(vertices, faces, -made)
    else:
        made = corner_normals(vertices, faces, crease_angle=60, weighting=weighting).normals
        data = obj_corner_normals(vertices, faces, -made)
    report = report_of(data, "p.obj")
    assert report.file_normals is not None and report.file_normals.kind == kind
    [problem] = [item for item in report.problems if item.code == "file_normals"]
    assert problem.python is not None and f'weighting="{weighting}"' in problem.python
    scope: dict[str, Any] = {"vertices": vertices, "faces": faces}
    exec(problem.python, scope)
    np.testing.assert_allclose(scope["normals"], made, atol=1e-12)


def test_a_meshlab_obj_whose_vn_follow_v_agrees() -> None:
    """A real MeshLab file whose vn follow the v: compared as corner normals, 926 of 3,000
    would disagree."""
    data = (DATA / "fuze.obj").read_bytes()
    assert b"Generated by Meshlab" in data
    stored = report_of(data, "fuze.obj").file_normals
    assert stored is not None
    assert (stored.kind, stored.weighting, stored.stored) == ("vertex", "angle", 502)
    assert stored.agreeing == stored.compared == 502 and stored.opposite == 0
    assert stored.max_angle_degrees is not None and stored.max_angle_degrees < 0.05


def test_zero_vertex_normals_are_unusable_and_the_json_has_no_nan() -> None:
    vertices, faces = blob()
    normals = vertex_normals(vertices, faces, "angle").normals
    normals[:10] = 0.0
    report = report_of(ply_text(vertices, faces, normals), "blob.ply")
    stored = report.file_normals
    assert stored is not None and stored.unusable == 10
    assert stored.compared == stored.agreeing == len(vertices) - 10
    data = strict(report)["file_normals"]
    assert data["weighting"] == "angle" and data["crease_angle_degrees"] is None
    everything = report_of(ply_text(vertices, faces, 0 * normals), "blob.ply")
    none = everything.file_normals
    assert none is not None and (none.compared, none.unusable) == (0, len(vertices))
    assert none.median_angle_degrees is None and none.max_angle_degrees is None
    assert strict(everything)["file_normals"]["median_angle_degrees"] is None


def test_unit_rows_and_angles_over_many_blocks_match_numpy() -> None:
    # The compiled passes (blocks claimed by every core) against NumPy's formulas, with rows
    # that are not usable (zero, NaN, infinite) and rows near the ends of the double range.
    rng = np.random.default_rng(11)
    count = 3 * (1 << 14) + 7
    stored = rng.standard_normal((count, 3)) * np.exp(rng.uniform(-700, 700, (count, 1)))
    stored[5] = 0.0
    stored[20000, 1] = np.nan
    stored[-1, 2] = np.inf
    stored[40000] = [1e-320, 0.0, -3e-321]
    unit, usable = unit_rows(stored)
    largest = np.abs(stored).max(axis=1)
    expected_usable = np.isfinite(stored).all(axis=1) & (largest > 0)
    assert usable.tolist() == expected_usable.tolist()
    scaled = stored[usable] / largest[usable, None]
    expected = scaled / np.sqrt((scaled**2).sum(axis=1))[:, None]
    np.testing.assert_allclose(unit[usable], expected, rtol=0, atol=4e-16)
    np.testing.assert_array_equal(unit[~usable], stored[~usable])  # divided by 1.0 twice

    ours = rng.standard_normal((count, 3))
    ours /= np.linalg.norm(ours, axis=1)[:, None]
    missing = rng.random(count) < 0.1
    nearby = ours + 1e-3 * rng.standard_normal((count, 3))
    every_row = unit_rows(nearby)  # all usable: with nothing missing, every row is compared
    for lacking in (missing, np.zeros(count, dtype=bool)):
        for theirs, fine in ((unit, usable), every_row):
            found = angles_between(theirs, fine, Candidate(ours, lacking))
            rows = fine & ~lacking
            a, b = theirs[rows], ours[rows]
            norms = np.linalg.norm(a - b, axis=1), np.linalg.norm(a + b, axis=1)
            assert len(found.radians) == int(rows.sum())
            np.testing.assert_allclose(
                found.radians, 2 * np.arctan2(*norms), rtol=1e-12, atol=1e-15
            )
