"""mesh_normal.mesh.report.objects: the report's objects (OBJ o and g groups) and their verdicts."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.typing import NDArray

from mesh_normal.files import read_mesh
from mesh_normal.mesh.report.analysis import analyse_mesh, build_report
from mesh_normal.mesh.report.models import MeshReport, ObjectReport
from mesh_normal.mesh.report.objects import _closed, _closed_numbered
from mesh_normal.record import INDEX_LIST_LIMIT
from tests.meshes import CUBE_OBJ_FACES, CUBE_OBJ_POINTS
from tests.paths import DATA

Face = Sequence[int]


def report_of(text: str, name: str = "objects.obj") -> MeshReport:
    data = text.encode()
    return build_report(analyse_mesh(read_mesh(data, name), name, len(data)))


def cube_points(shift: float) -> str:
    """The unit cube's ``v`` lines, moved by ``shift`` along x."""
    return "".join(f"v {x + shift} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))


def faces(rows: Sequence[Face], base: int) -> str:
    return "".join(f"f {' '.join(str(i + base + 1) for i in row)}\n" for row in rows)


def two_cubes(second: Sequence[Face] = CUBE_OBJ_FACES, name: str = "right") -> str:
    """Two unit cubes apart, objects ``left`` and ``name``; the second with ``second`` faces."""
    return (
        "o left\n"
        + cube_points(0)
        + faces(CUBE_OBJ_FACES, 0)
        + f"o {name}\n"
        + cube_points(3)
        + faces(second, 8)
    )


def by_name(report: MeshReport) -> dict[str, ObjectReport]:
    return {item.name: item for item in report.objects}


def test_two_objects_file_gives_both_with_their_counts() -> None:
    report = report_of((DATA / "two_objects.obj").read_text())
    assert report.object_count == 2
    cube, tetra = report.objects
    assert (cube.name, cube.faces, cube.area, cube.degenerate_faces) == ("cube", 12, 6.0, 0)
    assert (tetra.name, tetra.faces) == ("tetra", 4)
    assert tetra.area is not None and abs(tetra.area - (1.5 + 3**0.5 / 2)) < 1e-12
    # The tetrahedron sits on a cube corner: the mesh is not watertight by position (the
    # edges there are used four times), but each object is closed on its own.
    assert not report.watertight
    assert cube.closed and tetra.closed
    assert [item.orientation for item in report.objects] == ["outward", "outward"]
    assert [item.faces_flipped for item in report.objects] == [0, 0]
    assert report.faces == 16 and report.area == cube.area + tetra.area  # totals stay


def test_the_inward_object_is_named_and_the_other_is_outward() -> None:
    inward = [face[::-1] for face in CUBE_OBJ_FACES]
    report = report_of(two_cubes(inward, "turned"))
    objects = by_name(report)
    assert objects["turned"].orientation == "inward"
    assert objects["turned"].faces_flipped == 12
    assert objects["left"].orientation == "outward"
    assert objects["left"].faces_flipped == 0
    assert report.orientation == "mixed" and report.fix.faces_flipped == 12


def test_one_flipped_face_makes_its_object_mixed() -> None:
    one = [CUBE_OBJ_FACES[0][::-1], *CUBE_OBJ_FACES[1:]]
    objects = by_name(report_of(two_cubes(one)))
    assert (objects["right"].orientation, objects["right"].faces_flipped) == ("mixed", 1)
    assert objects["left"].orientation == "outward"


def test_an_object_that_is_part_of_a_closed_surface_is_open() -> None:
    lid = CUBE_OBJ_FACES[-2:]
    text = CUBE_OBJ_POINTS + "g box\n" + faces(CUBE_OBJ_FACES[:-2], 0) + "g lid\n" + faces(lid, 0)
    report = report_of(text)
    assert report.watertight
    box, cover = report.objects
    assert (box.faces, cover.faces) == (10, 2)
    assert not box.closed and not cover.closed
    # Both belong to the cube's one component, and take its verdict.
    assert box.components == cover.components == 1
    assert box.orientation == cover.orientation == "outward"


def test_an_inward_cube_in_two_groups_is_inward_in_both() -> None:
    inward = [face[::-1] for face in CUBE_OBJ_FACES]
    text = CUBE_OBJ_POINTS + "g a\n" + faces(inward[:6], 0) + "g b\n" + faces(inward[6:], 0)
    report = report_of(text)
    assert [(item.orientation, item.faces_flipped) for item in report.objects] == [
        ("inward", 6),
        ("inward", 6),
    ]


def test_a_flat_object_is_undetermined_and_counts_its_parts() -> None:
    text = (
        "o flat\nv 0 0 5\nv 1 0 5\nv 0 1 5\nv 9 0 5\nv 10 0 5\nv 9 1 5\nf 1 2 3\nf 4 5 6\n"
        "o cube\n" + cube_points(0) + faces(CUBE_OBJ_FACES, 6)
    )
    objects = by_name(report_of(text))
    flat = objects["flat"]
    assert (flat.orientation, flat.components, flat.closed, flat.faces) == (
        "undetermined",
        2,
        False,
        2,
    )
    assert objects["cube"].orientation == "outward" and objects["cube"].closed


def test_degenerate_faces_are_counted_per_object() -> None:
    text = (
        "o thin\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n"
        "o cube\n" + cube_points(5) + faces(CUBE_OBJ_FACES, 3)
    )
    objects = by_name(report_of(text))
    assert (objects["thin"].faces, objects["thin"].degenerate_faces) == (2, 2)
    # The sliver has edges (one component); the face naming vertex 1 twice has none.
    assert objects["thin"].area == 0.0 and objects["thin"].components == 1
    assert objects["thin"].orientation == "undetermined" and not objects["thin"].closed
    assert objects["cube"].degenerate_faces == 0


def test_a_file_without_groups_has_no_objects() -> None:
    report = report_of(CUBE_OBJ_POINTS + faces(CUBE_OBJ_FACES, 0))
    assert report.objects == [] and report.object_count == 0


def many_triangles(count: int) -> str:
    """``count`` objects of one triangle each, ``part0`` on."""
    return "".join(
        f"o part{i}\nv {3 * i} 0 0\nv {3 * i + 1} 0 0\nv {3 * i} 1 0\nf -3 -2 -1\n"
        for i in range(count)
    )


def test_objects_are_capped_and_counted() -> None:
    count = INDEX_LIST_LIMIT + 5
    report = report_of(many_triangles(count))
    assert report.object_count == count
    assert len(report.objects) == INDEX_LIST_LIMIT
    assert [item.name for item in report.objects[:2]] == ["part0", "part1"]


@settings(max_examples=60, deadline=None)
@given(
    faces=arrays(np.intp, st.tuples(st.integers(1, 40), st.just(3)), elements=st.integers(0, 7)),
    seed=st.integers(0, 2**16),
)
def test_the_sorted_keys_and_the_numbered_edges_agree_on_closed(
    faces: NDArray[np.intp], seed: int
) -> None:
    """Random faces over 8 points in up to 3 groups: both ways of counting edge uses agree."""
    groups = np.random.default_rng(seed).integers(0, 3, len(faces)).astype(np.intp)
    assert _closed(groups, faces, 3).tolist() == _closed_numbered(groups, faces, 3).tolist()


def test_one_object_is_closed_as_its_mesh_is() -> None:
    """A single object's verdicts come from the topology: the same as counting its edges."""
    closed = report_of("o cube\n" + cube_points(0) + faces(CUBE_OBJ_FACES, 0))
    opened = report_of("o cube\n" + cube_points(0) + faces(CUBE_OBJ_FACES[:-1], 0))
    assert [o.closed for o in closed.objects] == [True]
    assert [o.closed for o in opened.objects] == [False]
    assert [o.components for o in closed.objects] == [1]
