"""Tests for mesh_normal.mesh.topology and mesh_normal.mesh.orientation: edges, components, winding,
volume and orient()."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.csgraph
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.mesh import orientation, topology
from mesh_normal.mesh.orientation import (
    ComponentOrientation,
    ComponentTable,
    Orientation,
    orient,
    signed_volume,
)
from mesh_normal.mesh.topology import MeshTopology, mesh_topology
from tests.meshes import CUBE_FACES, CUBE_VERTICES, SAMPLES, TETRA_FACES, TETRA_VERTICES, load


def reversed_rows(faces: np.ndarray, rows: np.ndarray | list[int] | slice) -> np.ndarray:
    """``faces`` with the given rows reversed as orient() does: [a, b, c] -> [a, c, b]."""
    result = np.array(faces)
    result[rows] = result[rows][:, [0, 2, 1]]
    return result


def moebius_strip(segments: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A strip with a half twist: vertex 2 i is its upper edge at step i, 2 i + 1 its lower."""
    theta = 2 * np.pi * np.arange(segments) / segments
    vertices = []
    for t in theta:
        for s in (0.3, -0.3):
            r = 1 + s * np.cos(t / 2)
            vertices.append([r * np.cos(t), r * np.sin(t), s * np.sin(t / 2)])
    faces = []
    for i in range(segments):
        top, bottom = 2 * i, 2 * i + 1
        # After a full turn the upper edge comes back as the lower one.
        next_top, next_bottom = (2 * i + 2, 2 * i + 3) if i < segments - 1 else (1, 0)
        faces += [(top, bottom, next_bottom), (top, next_bottom, next_top)]
    return np.array(vertices), np.array(faces)


def assert_same_topology(a: MeshTopology, b: MeshTopology) -> None:
    for field in MeshTopology.__slots__:
        left, right = getattr(a, field), getattr(b, field)
        if isinstance(left, np.ndarray):
            assert np.array_equal(left, right), field
        else:
            assert left == right, field


# --- hand-built meshes with known answers -----------------------------------------------------


def test_tetrahedron_outward() -> None:
    t = mesh_topology(TETRA_FACES, 4)
    assert (t.boundary_edges, t.nonmanifold_edges, t.components) == (0, 0, 1)
    assert t.watertight and t.winding_consistent and t.orientable
    assert t.face_component.tolist() == [0, 0, 0, 0]
    assert t.boundary_edge_list.shape == t.nonmanifold_edge_list.shape == (0, 2)
    assert signed_volume(TETRA_VERTICES, TETRA_FACES) == pytest.approx(1 / 6, rel=1e-15)
    r = orient(TETRA_VERTICES, TETRA_FACES)
    assert isinstance(r, Orientation)
    assert r.orientation == "outward"
    assert not r.flipped.any()
    assert np.array_equal(r.faces, TETRA_FACES)
    assert r.volume == pytest.approx(1 / 6, rel=1e-15)
    (component,) = r.components
    assert component == ComponentOrientation(
        index=0,
        faces=4,
        closed=True,
        orientable=True,
        method="volume",
        flipped=0,
        volume=component.volume,
        orientation="outward",
        depth=0,
    )
    assert component.volume == pytest.approx(1 / 6, rel=1e-15)
    assert_same_topology(r.topology, t)


def test_tetrahedron_inward() -> None:
    inward = TETRA_FACES[:, ::-1]
    assert signed_volume(TETRA_VERTICES, inward) == pytest.approx(-1 / 6, rel=1e-15)
    t = mesh_topology(inward, 4)
    assert t.watertight and t.winding_consistent
    r = orient(TETRA_VERTICES, inward)
    assert r.orientation == "inward"
    assert r.flipped.all()
    assert np.array_equal(r.faces, inward[:, [0, 2, 1]])
    assert r.volume == pytest.approx(-1 / 6, rel=1e-15)  # of the input
    assert r.components[0].volume == pytest.approx(1 / 6, rel=1e-15)  # after orienting
    assert r.components[0].flipped == 4
    assert signed_volume(TETRA_VERTICES, r.faces) == pytest.approx(1 / 6, rel=1e-15)


def test_the_hand_built_cube_is_outward() -> None:
    assert signed_volume(CUBE_VERTICES, CUBE_FACES) == pytest.approx(1.0, rel=1e-15)
    r = orient(CUBE_VERTICES, CUBE_FACES)
    assert r.orientation == "outward" and not r.flipped.any()
    assert r.topology.watertight and r.topology.winding_consistent


def test_cube_with_one_flipped_face() -> None:
    faces = reversed_rows(CUBE_FACES, [7])
    t = mesh_topology(faces, 8)
    assert t.watertight and not t.winding_consistent and t.orientable
    r = orient(CUBE_VERTICES, faces)
    assert r.orientation == "mixed"
    assert np.flatnonzero(r.flipped).tolist() == [7]
    assert np.array_equal(r.faces, CUBE_FACES)
    assert r.volume is None  # the input is not consistently wound
    (component,) = r.components
    assert (component.method, component.flipped, component.orientation) == ("volume", 1, "mixed")
    assert component.volume == pytest.approx(1.0, rel=1e-15)


def test_open_box_is_decided_by_visibility() -> None:
    box = CUBE_FACES[np.r_[0:2, 4:12]]  # no top (quad 1: faces 2 and 3)
    t = mesh_topology(box, 8)
    assert (t.boundary_edges, t.nonmanifold_edges, t.components) == (4, 0, 1)
    assert not t.watertight and t.winding_consistent
    # The rim, z = 1, each edge in the direction its side runs along it.
    rim = {tuple(edge) for edge in t.boundary_edge_list.tolist()}
    assert rim == {(5, 4), (7, 5), (6, 7), (4, 6)}
    for faces, verdict, flips in ((box, "outward", 0), (box[:, ::-1], "inward", 10)):
        r = orient(CUBE_VERTICES, faces)
        assert r.orientation == verdict
        assert r.flipped.sum() == flips
        assert r.volume is None
        (component,) = r.components
        assert (component.closed, component.method, component.volume) == (False, "visibility", None)
        assert np.array_equal(np.sort(r.faces, axis=1), np.sort(box, axis=1))
        assert orient(CUBE_VERTICES, r.faces).orientation == "outward"


def test_two_components() -> None:
    vertices = np.concatenate([TETRA_VERTICES, CUBE_VERTICES + 5])
    faces = np.concatenate([CUBE_FACES + 4, TETRA_FACES[:, ::-1]])
    t = mesh_topology(faces, len(vertices))
    assert t.components == 2 and t.watertight and t.winding_consistent
    assert t.face_component.tolist() == [0] * 12 + [1] * 4  # numbered by first face
    r = orient(vertices, faces)
    assert r.orientation == "mixed"  # the components disagree
    assert np.flatnonzero(r.flipped).tolist() == [12, 13, 14, 15]
    assert [c.orientation for c in r.components] == ["outward", "inward"]
    assert [c.faces for c in r.components] == [12, 4]
    assert r.volume == pytest.approx(1 - 1 / 6, rel=1e-14)
    assert [c.volume for c in r.components] == pytest.approx([1, 1 / 6], rel=1e-14)


def test_moebius_strip_is_reported_not_flipped() -> None:
    vertices, faces = moebius_strip()
    t = mesh_topology(faces, len(vertices))
    assert not t.orientable and not t.winding_consistent
    assert (t.boundary_edges, t.nonmanifold_edges, t.components) == (24, 0, 1)
    r = orient(vertices, faces)
    assert r.orientation == "undetermined"
    assert not r.flipped.any()
    assert np.array_equal(r.faces, faces)
    (component,) = r.components
    assert (component.orientable, component.method, component.flipped) == (False, "none", 0)
    assert component.volume is None


def test_faces_with_a_repeated_index_are_left_out() -> None:
    faces = np.concatenate([[[0, 0, 1]], TETRA_FACES, [[2, 3, 3], [1, 2, 1]]])
    t = mesh_topology(faces, 4)
    assert (t.boundary_edges, t.nonmanifold_edges, t.components) == (0, 0, 1)
    assert t.watertight and t.winding_consistent
    assert t.face_component.tolist() == [-1, 0, 0, 0, 0, -1, -1]
    r = orient(TETRA_VERTICES, faces[:, ::-1])
    assert r.flipped.tolist() == [False, True, True, True, True, False, False]
    assert np.array_equal(r.faces[[0, 5, 6]], faces[[0, 5, 6], ::-1])
    assert r.orientation == "inward"
    assert r.volume == pytest.approx(-1 / 6, rel=1e-15)
    all_repeated = mesh_topology([[0, 0, 1], [2, 2, 2]], 3)
    assert (all_repeated.components, all_repeated.watertight) == (0, False)
    assert orient(TETRA_VERTICES, [[0, 0, 1]]).orientation == "undetermined"


def test_collinear_faces_with_distinct_indices_count() -> None:
    line = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    t = mesh_topology([[0, 1, 2]], 3)
    assert (t.boundary_edges, t.components) == (3, 1)
    r = orient(line, [[0, 1, 2]])
    assert r.orientation == "undetermined" and not r.flipped.any()
    assert r.components[0].method == "none"


def test_nonmanifold_fin() -> None:
    vertices = np.concatenate([TETRA_VERTICES, [[0.5, -1.0, -1.0]]])
    faces = np.concatenate([TETRA_FACES, [[0, 1, 4]]])  # a fin on edge 0-1
    t = mesh_topology(faces, 5)
    assert (t.boundary_edges, t.nonmanifold_edges, t.components) == (2, 1, 1)
    assert t.nonmanifold_edge_list.tolist() == [[0, 1]]
    assert not t.watertight and t.winding_consistent and t.orientable
    r = orient(vertices, faces)
    # The tetrahedron is a patch of its own, decided by visibility; the flat fin has no say.
    assert r.orientation == "outward" and not r.flipped.any()
    (component,) = r.components
    assert (component.closed, component.method, component.volume) == (False, "visibility", None)
    inward = orient(vertices, np.concatenate([TETRA_FACES[:, ::-1], [[0, 1, 4]]]))
    assert inward.orientation == "inward"
    assert inward.flipped.tolist() == [True] * 4 + [False]


def test_two_cubes_sharing_an_edge_are_oriented_each_on_its_own() -> None:
    vertices = np.concatenate([CUBE_VERTICES, CUBE_VERTICES + np.array([1, 1, 0])])
    faces = np.concatenate([CUBE_FACES, CUBE_FACES + 8])
    # Weld the second cube's edge (0, 0)-(0, 0, 1) onto the first cube's (1, 1)-(1, 1, 1).
    faces[faces == 8], faces[faces == 12] = 3, 7
    faces = reversed_rows(faces, slice(12, 24))
    t = mesh_topology(faces, len(vertices))
    assert (t.boundary_edges, t.nonmanifold_edges, t.components) == (0, 1, 1)
    assert t.nonmanifold_edge_list.tolist() == [[3, 7]]
    r = orient(vertices, faces)
    assert np.flatnonzero(r.flipped).tolist() == list(range(12, 24))
    assert r.orientation == "mixed"
    assert r.components[0].method == "visibility"


def test_a_duplicate_face_pair() -> None:
    t = mesh_topology([[0, 1, 2], [0, 1, 2]], 3)
    assert t.watertight and not t.winding_consistent
    r = orient(TETRA_VERTICES, [[0, 1, 2], [0, 1, 2]])
    # Back to back they enclose nothing: consistent, but neither way is out.
    assert r.flipped.tolist() == [False, True]
    assert r.orientation == "mixed"
    assert r.components[0].method == "none"
    assert r.components[0].volume == 0.0


def test_flat_sheet() -> None:
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]])
    faces = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2]])
    r = orient(vertices, faces)
    assert r.orientation == "undetermined" and not r.flipped.any()
    assert r.components[0].method == "none"
    # One face against the majority: it is flipped, and the input was mixed.
    r = orient(vertices, reversed_rows(faces, [0]))
    assert r.flipped.tolist() == [True, False, False] and r.orientation == "mixed"
    r = orient(vertices, reversed_rows(faces, [1, 2]))
    assert r.flipped.tolist() == [True, False, False]


def test_empty_and_isolated() -> None:
    empty = mesh_topology(np.empty((0, 3), dtype=int), 0)
    assert (empty.boundary_edges, empty.nonmanifold_edges, empty.components) == (0, 0, 0)
    assert not empty.watertight and empty.winding_consistent
    assert empty.face_component.shape == (0,)
    r = orient(np.empty((0, 3)), np.empty((0, 3), dtype=int))
    assert r.orientation == "undetermined" and r.volume is None
    assert r.faces.shape == (0, 3) and len(r.components) == 0
    assert signed_volume(TETRA_VERTICES, []) == 0.0
    # An isolated vertex is in no component.
    vertices = np.concatenate([TETRA_VERTICES, [[9.0, 9, 9]]])
    assert mesh_topology(TETRA_FACES, 5).components == 1
    assert orient(vertices, TETRA_FACES).volume == pytest.approx(1 / 6, rel=1e-15)


def test_bad_input_is_refused() -> None:
    with pytest.raises(ValueError, match="refers to vertex 4"):
        mesh_topology([[0, 1, 4]], 4)
    with pytest.raises(ValueError, match="shape"):
        orient(TETRA_VERTICES, [[0, 1]])


def test_component_table_is_a_sequence() -> None:
    vertices = np.concatenate([TETRA_VERTICES, CUBE_VERTICES + 5])
    r = orient(vertices, np.concatenate([CUBE_FACES + 4, TETRA_FACES]))
    table = r.components
    assert isinstance(table, ComponentTable) and len(table) == 2
    assert table[-1].index == 1 and table[-1].faces == 4
    assert table[0:2] == tuple(table) == (table[0], table[1])
    assert [c.index for c in reversed(table)] == [1, 0]
    with pytest.raises(IndexError):
        table[2]
    assert table.faces.tolist() == [12, 4]
    assert table.volume == pytest.approx([1, 1 / 6])


def test_signed_volume_is_accurate_far_from_the_origin() -> None:
    # det(A, B, C) about the origin would cancel terms of 2**60; about the centroid it does not.
    far = CUBE_VERTICES * 2.0**-10 + 2.0**30  # exact
    assert signed_volume(far, CUBE_FACES) == pytest.approx(2.0**-30, rel=1e-14)
    naive = np.linalg.det(far[CUBE_FACES]).sum() / 6
    assert abs(naive - 2.0**-30) > 0.1 * 2.0**-30  # what the shift avoids
    huge = CUBE_VERTICES * 1e200
    assert signed_volume(huge, CUBE_FACES) == math.inf
    assert orient(huge, CUBE_FACES[:, ::-1]).orientation == "inward"


@pytest.mark.parametrize("limit", [2**25, 2**12])
def test_the_slower_sorts_agree(monkeypatch: pytest.MonkeyPatch, limit: int) -> None:
    vertices, faces = load("ant.ply")
    faces = reversed_rows(faces, slice(0, 300))
    faces = np.concatenate([faces[:-5], [[1, 1, 2]], faces[:1]])  # boundary, non-manifold
    expected = orient(vertices, faces)
    monkeypatch.setattr(topology, "KEY_LIMIT", limit)
    got = orient(vertices, faces)
    assert_same_topology(got.topology, expected.topology)
    assert np.array_equal(got.flipped, expected.flipped)


# --- against trimesh ----------------------------------------------------------------------------


def variants(name: str) -> list[tuple[str, np.ndarray]]:
    _vertices, faces = load(name)
    rng = np.random.default_rng(len(faces))
    holes = np.delete(faces, rng.choice(len(faces), 5, replace=False), axis=0)
    flipped = reversed_rows(faces, rng.choice(len(faces), 7, replace=False))
    doubled = np.concatenate([faces, faces[:3]])
    return [("as is", faces), ("holes", holes), ("flipped", flipped), ("doubled", doubled)]


def edge_connected_components(mesh: trimesh.Trimesh) -> int:
    """Components of the graph of faces and edges, each face joined to its three edges."""
    m = len(mesh.faces)
    edge = mesh.edges_unique_inverse + m
    face = np.repeat(np.arange(m), 3)
    graph = scipy.sparse.coo_matrix(
        (np.ones(3 * m), (face, edge)), shape=(m + len(mesh.edges_unique),) * 2
    )
    _, labels = scipy.sparse.csgraph.connected_components(graph, directed=False)
    return len(np.unique(labels[:m]))


@pytest.mark.parametrize("name", SAMPLES)
def test_against_trimesh(name: str) -> None:
    vertices, _ = load(name)
    for label, faces in variants(name):
        mesh = trimesh.Trimesh(vertices, faces, process=False)
        t = mesh_topology(faces, len(vertices))
        _, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
        assert t.boundary_edges == np.count_nonzero(counts == 1), label
        assert t.nonmanifold_edges == np.count_nonzero(counts >= 3), label
        assert t.watertight == mesh.is_watertight, label
        assert t.winding_consistent == mesh.is_winding_consistent, label
        assert t.components == edge_connected_components(mesh), label
        if not t.nonmanifold_edges:  # trimesh's face adjacency skips non-manifold edges
            pieces = trimesh.graph.connected_components(
                mesh.face_adjacency, nodes=np.arange(len(faces))
            )
            assert t.components == len(pieces), label
        r = orient(vertices, faces)
        assert (r.volume is None) == (not t.watertight or not t.winding_consistent), label
        if r.volume is not None:
            assert r.volume == pytest.approx(mesh.volume, rel=1e-12), label
            assert signed_volume(vertices, faces) == pytest.approx(mesh.volume, rel=1e-12)


@pytest.mark.parametrize("name", SAMPLES)
def test_components_match_trimesh_split(name: str) -> None:
    vertices, faces = load(name)
    t = mesh_topology(faces, len(vertices))
    pieces = trimesh.Trimesh(vertices, faces, process=False).split(only_watertight=False)
    assert t.components == len(pieces)
    assert sorted(np.bincount(t.face_component).tolist()) == sorted(len(p.faces) for p in pieces)


# --- properties ---------------------------------------------------------------------------------


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), share=st.sampled_from([0.0, 0.01, 0.5, 0.99, 1.0]))
def test_orient_undoes_random_flips_of_a_closed_mesh(seed: int, share: float) -> None:
    vertices, faces = load("sphere.ply")
    chosen = np.random.default_rng(seed).random(len(faces)) < share
    r = orient(vertices, reversed_rows(faces, chosen))
    assert np.array_equal(r.flipped, chosen)
    assert np.array_equal(r.faces, faces)
    expected = "outward" if not chosen.any() else "inward" if chosen.all() else "mixed"
    assert r.orientation == expected


@settings(max_examples=20, deadline=None)
@given(
    name=st.sampled_from(SAMPLES),
    angles=st.tuples(*[st.floats(-math.pi, math.pi)] * 3),
    shift=st.tuples(*[st.floats(-1e3, 1e3)] * 3),
    scale=st.floats(1e-3, 1e3),
)
def test_rigid_motions_and_scaling_change_no_verdict(
    name: str, angles: tuple[float, float, float], shift: tuple[float, float, float], scale: float
) -> None:
    vertices, faces = load(name)
    faces = reversed_rows(faces, slice(0, len(faces), 9))
    rotation = trimesh.transformations.euler_matrix(*angles)[:3, :3]
    moved = scale * vertices @ rotation.T + shift
    before, after = orient(vertices, faces), orient(moved, faces)
    assert_same_topology(before.topology, after.topology)
    assert np.array_equal(before.flipped, after.flipped)
    assert before.orientation == after.orientation
    assert after.components.volume == pytest.approx(before.components.volume * scale**3, rel=1e-9)


@pytest.mark.parametrize("name", SAMPLES)
def test_reversing_every_face_negates_the_volume(name: str) -> None:
    vertices, faces = load(name)
    assert signed_volume(vertices, faces[:, [0, 2, 1]]) == -signed_volume(vertices, faces)
    r = orient(vertices, faces[:, [0, 2, 1]])
    assert r.orientation == "inward" and r.flipped.all()


def test_twinned_faces_match_the_rotations_definition() -> None:
    """A face is twinned when another has its points wound the other way: by rotations of the
    sorted points, as it was computed before (without the rolled copies)."""
    from mesh_normal.mesh.orientation import _twinned

    def by_rotations(faces: np.ndarray) -> np.ndarray:
        ordered = np.sort(faces, axis=1)
        even = np.zeros(len(faces), dtype=bool)
        for shift in range(3):
            even |= np.all(np.roll(faces, shift, axis=1) == ordered, axis=1)
        keys = [tuple(row) for row in ordered.tolist()]
        kinds: dict[tuple[int, ...], set[bool]] = {}
        for key, kind in zip(keys, even.tolist(), strict=True):
            kinds.setdefault(key, set()).add(kind)
        return np.array([len(kinds[key]) == 2 for key in keys], dtype=bool)

    rng = np.random.default_rng(7)
    for count in (1, 4, 40, 400):
        for top in (2, 3, 6, 30):
            faces = rng.integers(0, top, (count, 3)).astype(np.intp)
            np.testing.assert_array_equal(_twinned(faces), by_rotations(faces))
    # Points too many for one key a face: the lexsorted way, same definition.
    faces = rng.integers(0, 6, (400, 3)).astype(np.intp) * 2**21
    np.testing.assert_array_equal(_twinned(faces), by_rotations(faces))
    # Too many for one key, but a pair fits: groups by the smallest point (a few, many), on
    # any number of threads.
    from mesh_normal import _core
    from mesh_normal.mesh.orientation import _even, _twinned_lexsorted, _twinned_wide

    before = _core.threads()
    try:
        for top in (3, 6, 30, 300, 9000):  # 9000: more points than one thread's piece
            faces = rng.integers(0, top, (600 if top < 9000 else 30_000, 3)).astype(np.intp)
            for threads in (1, 2, 3):
                _core.set_threads(threads)
                np.testing.assert_array_equal(_twinned_wide(faces, top), by_rotations(faces))
    finally:
        _core.set_threads(before)
    faces = rng.integers(0, 6, (400, 3)).astype(np.intp) * 2**21 + 2**22
    np.testing.assert_array_equal(_twinned_lexsorted(faces, _even(faces)), by_rotations(faces))


def test_an_open_mesh_s_head_start_gives_what_taking_it_in_turn_gives(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A large open mesh takes its twins and its rays' Morton order on another thread while the
    topology runs (orientation.HeadStart); the answer is the one taken in turn."""
    from benchmarks.mesh_kernels import torus_mesh

    vertices, faces = torus_mesh(70_001)  # a torus grid with faces left out: open
    faces = np.concatenate([faces, faces[:500, ::-1]])  # and some twinned faces
    started = []
    real_run = orientation.HeadStart._run

    def run(self: orientation.HeadStart) -> None:
        started.append(True)
        real_run(self)

    monkeypatch.setattr(orientation.HeadStart, "_run", run)
    ahead = orient(vertices, faces)
    assert started == [True]
    monkeypatch.setattr(orientation, "HEAD_START_FACES", 10**9)  # in turn
    in_turn = orient(vertices, faces)
    assert started == [True]
    assert ahead.orientation == in_turn.orientation
    for field in dataclasses.fields(ahead.components):  # the open patches' volumes are NaN
        np.testing.assert_array_equal(
            getattr(ahead.components, field.name), getattr(in_turn.components, field.name)
        )
    np.testing.assert_array_equal(ahead.flipped, in_turn.flipped)
    np.testing.assert_array_equal(ahead.faces, in_turn.faces)


def test_a_head_start_s_failure_is_raised_where_its_result_is_needed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from benchmarks.mesh_kernels import torus_mesh

    vertices, faces = torus_mesh(70_001)

    def failing(_points: np.ndarray) -> np.ndarray:
        raise MemoryError("no room for the twins")

    monkeypatch.setattr(orientation, "_twinned", failing)
    with pytest.raises(MemoryError, match="no room for the twins"):
        orient(vertices, faces)


def test_a_closed_mesh_starts_no_head_start(monkeypatch: pytest.MonkeyPatch) -> None:
    from benchmarks.mesh_kernels import torus_mesh

    vertices, faces = torus_mesh(2 * 200 * 200)  # every face of the grid: closed
    monkeypatch.setattr(orientation.HeadStart, "start", lambda _self: pytest.fail("started"))
    assert orient(vertices, faces).topology.watertight


def test_without_a_thread_to_start_the_head_start_is_taken_in_turn(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from benchmarks.mesh_kernels import torus_mesh

    vertices, faces = torus_mesh(70_001)
    expected = orient(vertices, faces)

    def refused(_self: object) -> None:
        raise RuntimeError("can't start new thread")

    monkeypatch.setattr(orientation.threading.Thread, "start", refused)
    result = orient(vertices, faces)
    np.testing.assert_array_equal(result.flipped, expected.flipped)
    assert result.orientation == expected.orientation


def test_a_head_start_nobody_asks_for_is_waited_for(monkeypatch: pytest.MonkeyPatch) -> None:
    """Started, but its results never asked for (no open patch scored after all): orient()
    still waits for it, so no work of the mesh goes on after the call."""
    import threading
    import time

    from benchmarks.mesh_kernels import torus_mesh

    vertices, faces = torus_mesh(70_001)
    real_run = orientation.HeadStart._run

    def slow(self: orientation.HeadStart) -> None:
        time.sleep(0.3)
        real_run(self)

    monkeypatch.setattr(orientation.HeadStart, "_run", slow)
    monkeypatch.setattr(
        orientation.HeadStart, "twinned", lambda self: orientation._twinned(self._points)
    )
    monkeypatch.setattr(
        orientation, "visible_sides", lambda *arguments: np.full(len(arguments[4]), np.nan)
    )
    orient(vertices, faces)
    assert not any(thread.name == "mesh-normal-ahead" for thread in threading.enumerate())
