"""The rule the fix keeps: it never turns a mesh that is consistently wound by
position into one that is not, it flips nothing on a closed mesh whose volume is already
positive, and its verdict and flips do not depend on where the mesh is, how it is turned or
how large it is. Checked on every real mesh in tests/data and on generated hard cases."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.mesh.checks import checked_mesh
from mesh_normal.mesh.orientation import orient
from mesh_normal.mesh.topology import mesh_topology, row_hashes, same_points
from tests.meshes import (
    HARD_CASES,
    far_triangle,
    icosphere,
    load,
    random_rotation,
    separate_sides_cube,
)

REAL = (
    "cow.obj",
    "airplane.ply",
    "ant.ply",
    "nut.ply",
    "sphere.ply",
    "cube.obj",
    "teapot.stl",
    "soup.stl",
)


def mesh_of(name: str) -> tuple[np.ndarray, np.ndarray]:
    return HARD_CASES[name]() if name in HARD_CASES else load(name)


ALL = (*REAL, *HARD_CASES)


def consistent_by_position(vertices: np.ndarray, faces: np.ndarray) -> bool:
    return mesh_topology(checked_mesh(vertices, faces)).winding_consistent


def component_flips(
    vertices: np.ndarray, faces: np.ndarray, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Reverse a random choice of whole components (by position): still consistent."""
    labels = mesh_topology(checked_mesh(vertices, faces)).face_component
    rng = np.random.default_rng(seed)
    chosen = rng.random(labels.max() + 1) < 0.5
    rows = (labels >= 0) & chosen[labels]
    result = faces.copy()
    result[rows] = faces[rows][:, [0, 2, 1]]
    return result, rows


@pytest.mark.parametrize("name", ALL)
def test_every_mesh_is_consistent_by_position_and_left_consistent(name: str) -> None:
    vertices, faces = mesh_of(name)
    if name in HARD_CASES:  # all generated cases are wound consistently (and outward)
        assert consistent_by_position(vertices, faces)
    r = orient(vertices, faces)
    if consistent_by_position(vertices, faces):
        assert consistent_by_position(vertices, r.faces)
    if name in HARD_CASES:
        assert not r.flipped.any(), name
        assert r.orientation in ("outward", "undetermined")


@settings(max_examples=30, deadline=None)
@given(name=st.sampled_from(ALL), seed=st.integers(0, 2**32 - 1))
def test_the_fix_never_breaks_a_consistent_winding(name: str, seed: int) -> None:
    vertices, faces = mesh_of(name)
    if not consistent_by_position(vertices, faces):
        return
    turned, _ = component_flips(vertices, faces, seed)
    assert consistent_by_position(vertices, turned)
    r = orient(vertices, turned)
    assert consistent_by_position(vertices, r.faces), name


@pytest.mark.parametrize("name", ALL)
def test_nothing_flips_on_a_closed_mesh_with_positive_volume(name: str) -> None:
    vertices, faces = mesh_of(name)
    r = orient(vertices, faces)
    if r.volume is not None and r.volume > 0:
        assert not r.flipped.any(), name
        assert r.orientation == "outward"


def moved(vertices: np.ndarray, shift: float, seed: int, scale: float) -> np.ndarray:
    rotation = random_rotation(seed)
    return scale * vertices @ rotation.T + shift * np.array([1.0, -0.7, 0.3])


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(ALL),
    shift=st.sampled_from([0.0, 1e4, -1e4, 1e8]),
    seed=st.integers(0, 2**32 - 1),
    scale=st.sampled_from([1.0, 2.0**-20, 2.0**-3, 2.0**10, 0.37, 3.3, 1e-3, 1e3]),
    flips=st.integers(0, 2**32 - 1),
)
def test_verdict_and_flips_are_the_same_anywhere(
    name: str, shift: float, seed: int, scale: float, flips: int
) -> None:
    vertices, faces = mesh_of(name)
    rows = np.random.default_rng(flips).random(len(faces)) < 0.05
    faces = faces.copy()
    faces[rows] = faces[rows][:, [0, 2, 1]]
    there = moved(vertices, shift * scale, seed, scale)
    here, away = orient(vertices, faces), orient(there, faces)
    assert away.orientation == here.orientation, name
    assert np.array_equal(away.flipped, here.flipped), name


@pytest.mark.parametrize(
    "name", [n for n in ALL if n not in ("far triangle", "wobbling sides cube")]
)
def test_random_flips_of_a_decided_mesh_are_undone_exactly(name: str) -> None:
    vertices, faces = mesh_of(name)
    if orient(vertices, faces).orientation != "outward":
        pytest.skip("only meshes decided outward in every patch")
    chosen = np.random.default_rng(7).random(len(faces)) < 0.1
    flipped = faces.copy()
    flipped[chosen] = faces[chosen][:, [0, 2, 1]]
    r = orient(vertices, flipped)
    assert np.array_equal(r.flipped, chosen), name
    assert np.array_equal(r.faces, faces)


# --- hard cases, one by one ------------------------------------------------------------------


def test_a_cube_of_separate_float32_sides_is_one_closed_outward_piece() -> None:
    vertices, faces = separate_sides_cube()
    # 6 sides of 4 x 4 vertices, of which 8 corners (3 copies each) and 12 edges of 2 inner
    # points (2 copies each) are shared: 56 points.
    assert len(vertices) == 96 and len(np.unique(vertices, axis=0)) == 56
    t = mesh_topology(checked_mesh(vertices, faces))
    assert t.watertight and t.winding_consistent and t.components == 1
    r = orient(vertices, faces)
    assert r.orientation == "outward" and not r.flipped.any()
    assert r.volume == pytest.approx(1.0, rel=1e-5)
    assert [c.method for c in r.components] == ["volume"]
    inward = orient(vertices, faces[:, ::-1])
    assert inward.orientation == "inward" and inward.flipped.all()


def test_sides_that_miss_by_a_float32_step_are_not_flipped_and_weld_together() -> None:
    vertices, faces = separate_sides_cube(wobble=True, seed=3)
    r = orient(vertices, faces)
    assert not r.flipped.any()
    assert r.orientation in ("outward", "undetermined")
    welded = orient(vertices, faces, weld=1e-6)
    assert welded.topology.watertight and welded.topology.components == 1
    assert welded.orientation == "outward" and not welded.flipped.any()
    assert orient(vertices, faces[:, ::-1], weld=1e-6).flipped.all()
    # The weld keeps the file's faces: the output rows name the input vertices.
    assert np.array_equal(welded.faces, faces)


def test_a_small_triangle_is_undetermined_anywhere() -> None:
    for offset in (0.0, 1e4, -1e4, 1e8, 1e12):
        vertices, faces = far_triangle(offset)
        for winding in (faces, faces[:, ::-1]):
            r = orient(vertices, winding)
            assert r.orientation == "undetermined", offset
            assert not r.flipped.any() and r.components[0].method == "none"


@pytest.mark.parametrize("shift", [1e4, 1e8])
def test_a_closed_mesh_far_away_stays_outward(shift: float) -> None:
    vertices, faces = load("cow.obj")
    r = orient(vertices + shift, faces)
    assert r.orientation == orient(vertices, faces).orientation
    vertices, faces = load("sphere.ply")
    r = orient(vertices + shift, faces)
    assert r.orientation == "outward" and not r.flipped.any()


def test_an_inside_out_eye_is_turned_alone() -> None:
    vertices, faces = HARD_CASES["head with eyes"]()
    labels = mesh_topology(checked_mesh(vertices, faces)).face_component
    eye = labels == 2
    faces = faces.copy()
    faces[eye] = faces[eye][:, [0, 2, 1]]
    r = orient(vertices, faces)
    assert np.array_equal(r.flipped, eye)
    assert [c.orientation for c in r.components] == ["outward", "outward", "inward"]


# --- topology by position ---------------------------------------------------------------------


def test_same_points_maps_to_the_first_vertex_with_those_coordinates() -> None:
    vertices = np.array([[1.0, 2, 3], [0.0, 0, 0], [1, 2, 3], [-0.0, 0, 0], [1, 2, 3.5]])
    assert same_points(vertices).tolist() == [0, 1, 0, 1, 4]
    assert same_points(vertices[[0, 1, 4]]) is None
    assert same_points(np.empty((0, 3))) is None
    rng = np.random.default_rng(0)
    many = rng.integers(0, 5, size=(2000, 3)).astype(np.float64)
    _, first, inverse = np.unique(many, axis=0, return_index=True, return_inverse=True)
    assert np.array_equal(same_points(many), first[inverse.ravel()])


def test_weld_joins_close_vertices_only() -> None:
    vertices = np.array([[0.0, 0, 0], [1e-9, 0, 0], [1, 1, 1], [1, 1, 1 + 1e-3]])
    assert same_points(vertices, weld=1e-7).tolist() == [0, 0, 2, 3]
    assert same_points(vertices, weld=1e-2).tolist() == [0, 0, 2, 2]
    assert same_points(vertices, weld=0.0) is None
    with pytest.raises(ValueError, match="weld tolerance"):
        same_points(vertices, weld=-1.0)
    with pytest.raises(ValueError, match="weld tolerance"):
        same_points(vertices, weld=math.nan)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), weld=st.floats(1e-6, 0.3))
def test_weld_joins_every_pair_closer_than_half_the_tolerance(seed: int, weld: float) -> None:
    rng = np.random.default_rng(seed)
    vertices = rng.random((60, 3))
    side = weld * np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))
    point = same_points(vertices, weld)
    assert point is not None
    gap = np.abs(vertices[:, None] - vertices[None]).max(axis=2)
    close = gap < side / 2
    assert (point[:, None] == point[None])[close].all()


def test_topology_of_a_mesh_is_by_position_and_of_raw_faces_by_index() -> None:
    vertices, faces = separate_sides_cube()
    by_index = mesh_topology(faces, len(vertices))
    assert by_index.components == 6 and by_index.boundary_edges == 6 * 12
    by_position = mesh_topology(checked_mesh(vertices, faces))
    assert by_position.watertight and by_position.boundary_edge_list.shape == (0, 2)
    with pytest.raises(TypeError, match="coordinates"):
        mesh_topology(faces, len(vertices), weld=1e-6)


def test_a_face_with_two_corners_at_one_point_has_no_edges() -> None:
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0]])
    t = mesh_topology(checked_mesh(vertices, [[0, 1, 2], [0, 1, 3]]))
    assert t.face_component.tolist() == [0, -1]
    assert t.boundary_edges == 3


def test_a_cavity_faces_into_itself_and_a_part_inside_a_shell_is_a_cavity() -> None:
    # Nesting decides: a shell inside one other faces in, away from the material around it.
    vertices, faces = HARD_CASES["hollow ball"]()
    r = orient(vertices, faces)
    assert r.orientation == "outward" and not r.flipped.any()
    assert [c.method for c in r.components] == ["volume", "volume"]
    assert [c.depth for c in r.components] == [0, 1]
    assert r.volume is not None and r.volume > 0
    inner = mesh_topology(checked_mesh(vertices, faces)).face_component == 1
    part = faces.copy()
    part[inner] = faces[inner][:, [0, 2, 1]]
    assert np.array_equal(orient(vertices, part).flipped, inner)
    # Inside out, both shells are turned.
    assert orient(vertices, faces[:, [0, 2, 1]]).flipped.all()


def test_nested_shells_past_the_limits_are_left_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    from mesh_normal.mesh import orientation

    vertices, faces = HARD_CASES["head with eyes"]()
    labels = mesh_topology(checked_mesh(vertices, faces)).face_component
    eye = labels == 2
    faces[eye] = faces[eye][:, [0, 2, 1]]
    assert np.array_equal(orient(vertices, faces).flipped, eye)
    monkeypatch.setattr(orientation, "_NEST_WORK", 10)
    assert not orient(vertices, faces).flipped.any()  # not cleared: left as it is
    monkeypatch.setattr(orientation, "_NEST_WORK", 2 * 10**8)
    monkeypatch.setattr(orientation, "_NEST_PAIRS", 1)
    assert not orient(vertices, faces).flipped.any()


def test_many_separate_inward_shells_are_still_fixed_past_the_pair_limits() -> None:
    # 5,000 tetrahedra wound inward, side by side: more shells than _NEST_SHELLS, and no box
    # lies inside another's, so each is decided by its own volume and turned outward.
    tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    inward = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    count = 5000
    offsets = np.stack(
        [np.arange(count) % 100 * 3, np.arange(count) // 100 * 3, 0 * np.arange(count)], 1
    )
    vertices = (tetra[None] + offsets[:, None]).reshape(-1, 3)
    faces = (inward[None] + 4 * np.arange(count)[:, None, None]).reshape(-1, 3)
    fixed = orient(vertices, faces)
    assert fixed.flipped.all() and fixed.orientation == "inward"


def test_crossing_shells_in_one_box_are_left_alone_quickly() -> None:
    # 1,000 tetrahedra jittered around one place: every one crosses the others, or lies in
    # no other's box; all face out, and nothing is flipped.
    tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    outward = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    jitter = np.random.default_rng(0).normal(size=(1000, 1, 3)) * 0.01
    vertices = (tetra[None] + jitter).reshape(-1, 3)
    faces = (outward[None] + 4 * np.arange(1000)[:, None, None]).reshape(-1, 3)
    assert not orient(vertices, faces).flipped.any()


@pytest.mark.parametrize("weld", [1e-310, 5e-324])
def test_a_subnormal_weld_joins_nothing_beyond_equality(weld: float) -> None:
    # The grid's cells would overflow to infinity and every vertex would share one cell.
    tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    vertices = np.concatenate([tetra, tetra + 5])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        found = orient(vertices, np.concatenate([faces, faces + 4]), weld=weld)
    assert found.topology.components == 2


@pytest.mark.parametrize("kind", ["grid cells", "sphere"])
def test_the_position_hash_keeps_rows_apart(kind: str) -> None:
    """Whole numbers (a weld's cells) and a subdivided sphere's vertices get distinct keys."""
    if kind == "grid cells":
        rows = np.indices((60, 60, 60)).reshape(3, -1).T.astype(np.float64) + 1e5
    else:
        rows, _ = icosphere(6)
    keys = row_hashes((rows + 0.0).view(np.uint64))
    assert len(np.unique(keys)) >= len(rows) - 1
