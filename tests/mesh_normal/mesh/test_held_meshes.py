"""Every mesh function takes the meshes people hold: what read_mesh returns, a (vertices, faces)
tuple, a trimesh.Trimesh, an Open3D TriangleMesh and a PyVista PolyData of triangles, each
giving the results of the raw arrays; anything else gets one sentence saying what can be passed.

PyVista is not a test dependency (its VTK wheel alone is over 100 MB): :class:`PolyData` below
has the attributes the conversion reads of a real ``pyvista.PolyData``, as its documentation
gives them (``points``, the flat cell array ``faces``, ``n_strips``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import trimesh

import mesh_normal as mn
from tests.meshes import CUBE_FACES, CUBE_VERTICES

open3d = pytest.importorskip("open3d")

#: The unit cube with two faces turned inward: every function has something to say.
FACES = CUBE_FACES.copy()
FACES[[1, 6]] = FACES[[1, 6]][:, ::-1]
VERTICES = CUBE_VERTICES * 2.0 + 1.0


class PolyData:
    """What the conversion reads of a ``pyvista.PolyData``."""

    def __init__(self, points: np.ndarray, faces: np.ndarray, n_strips: int = 0) -> None:
        self.points = points
        self.faces = faces
        self.n_strips = n_strips


def cell_array(faces: np.ndarray) -> np.ndarray:
    """The flat VTK cell array of triangles: ``[3, a, b, c, 3, ...]``, as vtkIdType (int64)."""
    return np.column_stack([np.full(len(faces), 3), faces]).astype(np.int64).ravel()


def obj_text(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    return ("\n".join(lines) + "\n").encode()


def open3d_mesh(vertices: np.ndarray, faces: np.ndarray) -> Any:
    return open3d.geometry.TriangleMesh(
        open3d.utility.Vector3dVector(vertices), open3d.utility.Vector3iVector(faces)
    )


#: Each way of holding the mesh, made from its arrays.
HOLDERS: dict[str, Callable[[np.ndarray, np.ndarray], object]] = {
    "read_mesh": lambda v, f: mn.read_mesh(obj_text(v, f), "cube.obj"),
    "tuple": lambda v, f: (v, f),
    "checked": lambda v, f: mn.checked_mesh(v, f),
    "trimesh": lambda v, f: trimesh.Trimesh(v, f, process=False),
    "open3d": open3d_mesh,
    "pyvista": lambda v, f: PolyData(v.astype(np.float32), cell_array(f)),
}


@pytest.fixture(params=list(HOLDERS))
def held(request: pytest.FixtureRequest) -> object:
    return HOLDERS[request.param](VERTICES, FACES)


def same(ours: object, theirs: object) -> None:
    """Equal results: arrays bit for bit, dataclasses field by field."""
    if isinstance(ours, np.ndarray):
        np.testing.assert_array_equal(ours, theirs)  # type: ignore[arg-type]
    elif hasattr(ours, "__dataclass_fields__"):
        for name in ours.__dataclass_fields__:
            if name != "topology" and not name.startswith("_"):
                same(getattr(ours, name), getattr(theirs, name))
    elif isinstance(ours, tuple | list):
        assert len(ours) == len(theirs)  # type: ignore[arg-type]
        for a, b in zip(ours, theirs, strict=True):  # type: ignore[call-overload]
            same(a, b)
    else:
        assert ours == theirs


FUNCTIONS = {
    "face_normals": mn.face_normals,
    "face_areas": mn.face_areas,
    "vertex_normals": mn.vertex_normals,
    "corner_normals": mn.corner_normals,
    "orient": mn.orient,
    "signed_volume": mn.signed_volume,
}


@pytest.mark.parametrize("name", list(FUNCTIONS))
def test_every_function_takes_the_mesh_alone(held: object, name: str) -> None:
    function = FUNCTIONS[name]
    same(function(held), function(VERTICES, FACES))


def test_the_geometry_topology_and_checked_mesh_of_a_held_mesh(held: object) -> None:
    geometry = mn.face_geometry(held)
    np.testing.assert_array_equal(geometry.normals, mn.face_geometry(VERTICES, FACES).normals)
    same(mn.mesh_topology(held), mn.mesh_topology(mn.checked_mesh(VERTICES, FACES)))
    checked = mn.checked_mesh(held)
    np.testing.assert_array_equal(checked.faces, FACES)
    np.testing.assert_array_equal(checked.vertices, VERTICES)


def test_keywords_keep_working_with_a_held_mesh(held: object) -> None:
    ours = mn.corner_normals(held, crease_angle=45, weighting="area")
    same(ours, mn.corner_normals(VERTICES, FACES, crease_angle=45, weighting="area"))
    same(mn.orient(held, weld=1e-6), mn.orient(VERTICES, FACES, weld=1e-6))


def test_the_report_and_the_file_of_a_held_mesh(held: object) -> None:
    ours, theirs = mn.analyse(held), mn.analyse(obj_text(VERTICES, FACES), "cube.obj")
    assert ours.fix == theirs.fix and ours.problems == theirs.problems
    assert ours.fix.faces_flipped == 2 and ours.volume == theirs.volume
    assert mn.write_mesh(held, "ply") == mn.write_mesh(VERTICES, FACES, "ply")
    assert mn.write_mesh(held, file_format="off") == mn.write_mesh(VERTICES, FACES, "off")


def test_a_report_on_memory_says_so() -> None:
    report = mn.analyse(trimesh.Trimesh(VERTICES, FACES, process=False))
    assert report.file.format == "memory" and report.file.name is None
    assert report.file.bytes == 0


def test_read_meshes_are_not_checked_again(monkeypatch: pytest.MonkeyPatch) -> None:
    from mesh_normal.mesh import checks

    mesh = mn.read_mesh(obj_text(VERTICES, FACES), "cube.obj")

    def refused(*_: object) -> None:
        raise AssertionError("the reader's arrays were checked again")

    monkeypatch.setattr(checks, "_as_vertices", refused)
    same(mn.face_normals(mesh), mn.face_normals(mesh.checked()))


@pytest.mark.parametrize(
    ("value", "words"),
    [
        ("bunny.obj", "not a file: read it with mn.read_mesh first"),
        (
            42,
            "a trimesh.Trimesh, an Open3D TriangleMesh or a PyVista PolyData of triangles, not int",
        ),
        ({"vertices": VERTICES}, "not dict"),
        (VERTICES, "faces are required with raw vertices: pass vertices and faces arrays"),
    ],
)
@pytest.mark.parametrize("name", [*FUNCTIONS, "face_geometry", "checked_mesh", "mesh_topology"])
def test_anything_else_gets_a_sentence_of_what_can_be_passed(
    value: object, words: str, name: str
) -> None:
    function = getattr(mn, name)
    if name == "mesh_topology" and isinstance(value, np.ndarray):
        words = "vertex_count is required with raw faces: pass faces and vertex_count, or a mesh"
    with pytest.raises(TypeError, match=words.replace("(", r"\(").replace(")", r"\)")) as error:
        function(value)
    assert str(error.value).count(". ") == 0  # one sentence


def test_a_held_mesh_with_faces_beside_it_is_refused() -> None:
    mesh = trimesh.Trimesh(VERTICES, FACES, process=False)
    with pytest.raises(TypeError, match="a Trimesh holds its faces: pass it without faces"):
        mn.face_normals(mesh, FACES)
    with pytest.raises(TypeError, match="a TriangleMesh holds its faces"):
        mn.vertex_normals(open3d_mesh(VERTICES, FACES), FACES)


def test_polydata_with_other_cells_is_refused_with_what_to_do() -> None:
    quads = np.array([4, 0, 1, 3, 2, 3, 4, 5, 6])
    with pytest.raises(ValueError, match="a face of 4 corners: call its triangulate"):
        mn.face_normals(PolyData(VERTICES, np.concatenate([cell_array(FACES[:2]), quads])))
    with pytest.raises(ValueError, match="a cut-off cell array"):
        mn.face_normals(PolyData(VERTICES, cell_array(FACES)[:-1]))
    with pytest.raises(ValueError, match="2 triangle strips: call its triangulate"):
        mn.face_normals(PolyData(VERTICES, cell_array(FACES), n_strips=2))


def test_a_held_mesh_with_a_bad_index_gets_the_arrays_sentence() -> None:
    faces = FACES.copy()
    faces[3, 1] = 99
    with pytest.raises(ValueError, match="faces\\[3\\] refers to vertex 99"):
        mn.face_normals(trimesh.Trimesh(VERTICES, faces, process=False, validate=False))
