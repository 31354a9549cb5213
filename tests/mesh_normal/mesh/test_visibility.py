"""mesh_normal.mesh.visibility: open patches decided by the rays that escape on each side."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from mesh_normal import _core
from mesh_normal.mesh import visibility
from mesh_normal.mesh.checks import checked_mesh
from mesh_normal.mesh.faces import face_geometry
from mesh_normal.mesh.orientation import orient
from mesh_normal.mesh.topology import by_position, structure
from tests.meshes import (
    CUBE_FACES,
    CUBE_VERTICES,
    HARD_CASES,
    combined,
    icosphere,
    load,
    scan_fragments,
)


def scores(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """visible_sides over every orientable open patch, as orient() asks for them."""
    geometry = face_geometry(vertices, faces)
    found = structure(by_position(geometry.mesh), len(vertices))
    area = np.bincount(found.group, geometry.lengths, found.patches + 1)[:-1]
    candidates = found.orientable & ~found.closed[found.patch_component] & (area > 0)
    return visibility.visible_sides(
        geometry.mesh.vertices, geometry.mesh.faces, found.group, found.parity, candidates, area
    )


def square(corner: list[float], side: float, up: bool) -> tuple[np.ndarray, np.ndarray]:
    """A square in a plane z = const, two triangles wound towards +z if ``up``."""
    x, y, z = corner
    points = np.array([[x, y, z], [x + side, y, z], [x + side, y + side, z], [x, y + side, z]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    return points, faces if up else faces[:, ::-1]


def test_a_plate_facing_a_large_floor_sees_nothing_on_that_side() -> None:
    # Every ray leaves at least asin(0.1) above the plate's plane, so from a height of 1 it
    # meets the floor within 10 of the plate: all rays towards the floor are blocked, and
    # all rays away from it escape. The score is -1 exactly; the plate is turned over.
    floor = square([-100.0, -100.0, 0.0], 200.0, up=True)
    plate = square([0.0, 0.0, 1.0], 0.5, up=False)
    vertices, faces = combined(floor, plate)
    score = scores(vertices, faces)
    assert score.tolist()[1] == -1.0
    assert abs(score[0]) < visibility.MARGIN  # the floor sees the sky and the void below
    r = orient(vertices, faces)
    assert r.flipped.tolist() == [False, False, True, True]
    assert [c.method for c in r.components] == ["none", "visibility"]
    assert r.orientation == "inward"


def test_flipping_a_patch_negates_its_score_exactly() -> None:
    vertices, faces = scan_fragments()
    before = scores(vertices, faces)
    assert (before > visibility.MARGIN).all()
    patch_of = structure(by_position(checked_mesh(vertices, faces)), len(vertices)).group
    turned = faces.copy()
    rows = patch_of == 2
    turned[rows] = faces[rows][:, ::-1]
    after = scores(vertices, turned)
    expected = before.copy()
    expected[2] = -before[2]
    assert after.tolist() == expected.tolist()


def test_a_plate_shut_inside_a_box_is_left_as_it_is() -> None:
    box = (CUBE_VERTICES * 4.0 - 2.0, CUBE_FACES)
    for up in (True, False):
        vertices, faces = combined(box, square([-0.5, -0.5, 0.0], 1.0, up=up))
        assert scores(vertices, faces)[-1] == 0.0  # no ray escapes on either side
        r = orient(vertices, faces)
        assert not r.flipped.any()
        assert [c.method for c in r.components] == ["volume", "none"]
        assert r.orientation == "outward"


def test_back_to_back_faces_are_left_as_they_are() -> None:
    # A closed sphere with one face doubled back to back (as in the Stanford bunny of trimesh's
    # test models): the doubled face's three edges become non-manifold and it is a patch of
    # its own whose front sees only the inside. Turning it would only make two faces one.
    vertices, faces = icosphere(2)
    doubled = np.concatenate([faces, faces[:1, ::-1]])
    r = orient(vertices, doubled)
    assert not r.flipped.any()
    # The same face doubled the same way is no twin: both copies face out and stay.
    assert not orient(vertices, np.concatenate([faces, faces[:1]])).flipped.any()


def test_past_the_budget_only_the_largest_patches_are_decided(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    vertices, faces = scan_fragments()
    patch_of = structure(by_position(checked_mesh(vertices, faces)), len(vertices)).group
    # Make the fragment of face 0 larger than the others: it alone fits in a budget of one.
    grown = vertices.copy()
    piece = np.unique(faces[patch_of == patch_of[0]])
    grown[piece] *= 1.01
    monkeypatch.setattr(visibility, "RAYS", 2 * visibility.DIRECTIONS * visibility.FEWEST)
    score = scores(grown, faces)
    assert np.flatnonzero(~np.isnan(score)).tolist() == [patch_of[0]]
    r = orient(grown, faces[:, ::-1])
    assert np.array_equal(r.flipped, patch_of == patch_of[0])


@pytest.mark.parametrize(
    "name", ["teapot.stl", "soup.stl", *[n for n in HARD_CASES if n != "far triangle"]]
)
def test_reversing_every_face_turns_exactly_the_decided_patches_the_other_way(name: str) -> None:
    vertices, faces = HARD_CASES[name]() if name in HARD_CASES else load(name)
    here, there = orient(vertices, faces), orient(vertices, faces[:, ::-1])
    patch_of = structure(by_position(checked_mesh(vertices, faces)), len(vertices)).group
    labels = here.topology.face_component
    for component in here.components:
        rows = labels == component.index
        if component.method == "none":
            assert np.array_equal(there.flipped[rows], here.flipped[rows]), name
        elif len(np.unique(patch_of[rows])) == 1:  # one patch: decided as a whole
            assert np.array_equal(there.flipped[rows], ~here.flipped[rows]), name


def test_the_teapot_of_separate_open_pieces_is_outward() -> None:
    # trimesh's teapot.stl: body, lid, spout and handle, each open, none closing another.
    vertices, faces = load("teapot.stl")
    r = orient(vertices, faces)
    assert r.orientation == "outward" and not r.flipped.any()
    assert [c.method for c in r.components] == ["visibility"] * 4
    assert orient(vertices, faces[:, ::-1]).flipped.all()


def test_a_random_triangle_soup_is_mostly_left_alone() -> None:
    # trimesh's soup.stl: 100 random triangles; none encloses anything. Only triangles whose
    # one side is clearly shut in by the others are decided.
    vertices, faces = load("soup.stl")
    score = scores(vertices, faces)
    decided = np.abs(score) >= visibility.MARGIN
    r = orient(vertices, faces)
    assert np.array_equal(r.flipped, decided & (score < 0))
    assert decided.sum() <= 10


@pytest.mark.parametrize("shift", [1e4, -1e4, 1e8])
def test_the_scores_are_the_same_far_from_the_origin(shift: float) -> None:
    # The rays are cast in the box of the mesh itself, never one stretched to the origin (with
    # the origin in the box, at 1e8 a triangle of trimesh's soup.stl would score -0.3125
    # instead of -0.625 and be left as it is).
    vertices, faces = load("soup.stl")
    here = scores(vertices, faces)
    there = scores(vertices + shift * np.array([1.0, -0.7, 0.3]), faces)
    assert np.array_equal(np.isnan(here), np.isnan(there))
    decided = np.abs(np.nan_to_num(here)) >= visibility.MARGIN
    assert np.array_equal(decided, np.abs(np.nan_to_num(there)) >= visibility.MARGIN)
    np.testing.assert_allclose(there, here, atol=1 / visibility.DIRECTIONS / 2)


def _reference_morton(unit: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The Morton codes of the faces' centroids, bit by bit in NumPy."""
    total = unit[faces[:, 0]] + unit[faces[:, 1]]
    total += unit[faces[:, 2]]
    cells = np.clip(((total / 3 + 1.0) * 512.0).astype(np.int64), 0, 1023)
    code = np.zeros(len(faces), dtype=np.int64)
    for bit in range(10):
        for axis in range(3):
            code |= ((cells[:, axis] >> bit) & 1) << (3 * bit + axis)
    return code


@pytest.mark.parametrize("count", [1, 7, 600, 5000, 20000])
def test_the_hierarchy_order_is_the_stable_sort_of_the_morton_codes(count: int) -> None:
    rng = np.random.default_rng(count)
    unit = rng.uniform(-1, 1, (count + 2, 3))
    unit[: count // 3] = np.round(unit[: count // 3], 1)  # many equal codes: ties in file order
    faces = rng.integers(0, len(unit), (count, 3)).astype(np.intp)
    expected = _reference_morton(unit, faces)
    codes, order = _core.face_morton_order(unit, faces)
    np.testing.assert_array_equal(order, np.argsort(expected, kind="stable"))
    np.testing.assert_array_equal(codes, expected[order])
    corners = _core.bvh_build(unit, faces, codes, order, visibility._LEAF, True)[3]
    np.testing.assert_array_equal(corners, unit[faces[order]].reshape(-1, 9))


def _reference_split(codes: np.ndarray, leaf: int) -> tuple[np.ndarray, np.ndarray]:
    """The nodes' children and spans, made in breadth order: a span of more than ``leaf``
    faces is cut where the highest bit in which its first and last codes differ turns, or in
    the middle where they are equal."""
    spans, children = [(0, len(codes))], []
    for lo, hi in spans:  # the list grows as it is read: breadth order
        if hi - lo <= leaf:
            children.append((-1, -1))
            continue
        differ = int(codes[lo]) ^ int(codes[hi - 1])
        if differ == 0:
            mid = (lo + hi) // 2
        else:
            bit = differ.bit_length() - 1
            mid = lo + int(np.flatnonzero((codes[lo:hi] >> bit) & 1)[0])
        children.append((len(spans), len(spans) + 1))
        spans += [(lo, mid), (mid, hi)]
    return np.array(children), np.array(spans)


@pytest.mark.parametrize("leaf", [1, 4, 64])
def test_the_hierarchy_is_split_at_the_codes_bits_and_boxes_its_faces(leaf: int) -> None:
    rng = np.random.default_rng(leaf)
    unit = rng.uniform(-1, 1, (3000, 3))
    unit[:1000] = np.round(unit[:1000], 1)  # runs of equal codes: split in the middle
    faces = rng.integers(0, len(unit), (5000, 3)).astype(np.intp)
    codes, order = _core.face_morton_order(unit, faces)
    for gather in (True, False):
        boxes, children, spans, corners = _core.bvh_build(unit, faces, codes, order, leaf, gather)
        expected_children, expected_spans = _reference_split(codes, leaf)
        np.testing.assert_array_equal(children, expected_children)
        np.testing.assert_array_equal(spans, expected_spans)
        assert corners.shape == ((len(faces), 9) if gather else (0, 9))
        # Each box: its faces' corners, widened by 2**-26 (x - pad rounds monotonically, so
        # the least corner less the pad is the least of each corner less the pad).
        points = unit[faces[order]].reshape(len(faces), 9, 1)
        for node, (lo, hi) in enumerate(spans):
            span = points[lo:hi].reshape(-1, 3)
            expected = np.concatenate([span.min(axis=0) - 2.0**-26, span.max(axis=0) + 2.0**-26])
            np.testing.assert_array_equal(boxes[node], expected)


@pytest.mark.parametrize("name", ["teapot.stl", "soup.stl", "scan fragments"])
def test_any_leaf_size_gives_the_same_scores(monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    # A ray meets the same faces whatever the hierarchy's leaves hold: leaf_size only trades
    # the time to build it against the time to cast through it.
    vertices, faces = scan_fragments() if name == "scan fragments" else load(name)
    found = {}
    for leaf in (1, visibility._LEAF, 16, visibility._WIDEST_LEAF, 4096):
        monkeypatch.setattr(visibility, "leaf_size", lambda *_, size=leaf: size)
        found[leaf] = scores(vertices, faces)
    assert not np.isnan(found[visibility._LEAF]).all()
    for score in found.values():
        np.testing.assert_array_equal(score, found[visibility._LEAF])


def test_the_leaves_grow_where_the_rays_are_few() -> None:
    assert visibility.leaf_size(1000, 2**19) == visibility._LEAF
    assert visibility.leaf_size(871_414, 1024) == visibility._WIDEST_LEAF
    assert visibility._LEAF < visibility.leaf_size(871_414, 2**12) < visibility._WIDEST_LEAF


def _samples_by_sorting(
    group: np.ndarray, chosen: np.ndarray, per: int
) -> tuple[np.ndarray, np.ndarray]:
    """The samples taken the slow, plain way (the one-pass pick must match it): each patch's
    members by a stable sort, then evenly spread picks."""
    wanted = np.zeros(int(group.max(initial=0)) + 1, dtype=bool)
    wanted[chosen] = True
    members = np.flatnonzero(wanted[group])
    members = members[np.argsort(group[members], kind="stable")]
    starts = np.searchsorted(group[members], chosen)
    counts = np.searchsorted(group[members], chosen, side="right") - starts
    take = np.minimum(counts, per)
    owner = np.repeat(np.arange(len(chosen)), take)
    rank = np.arange(int(take.sum())) - np.repeat(np.cumsum(take) - take, take)
    picks = np.repeat(starts, take) + (rank * np.repeat(counts, take)) // np.repeat(
        np.maximum(take, 1), take
    )
    return members[picks], owner


@given(
    group=st.lists(st.integers(0, 6), min_size=1, max_size=400).map(np.array),
    picked=st.sets(st.integers(0, 6), min_size=1),
    per=st.integers(1, 40),
)
@settings(max_examples=200, deadline=None)
def test_samples_are_the_sorted_picks(group: np.ndarray, picked: set[int], per: int) -> None:
    """One pass picks the same faces as sorting each patch's members did (a patch of no
    faces, the group past the patches and patches left out included)."""
    chosen = np.array(sorted(value for value in picked if value <= group.max()))
    assume(len(chosen))  # as the casting chooses them: patches that the groups number
    samples, owner = visibility._samples(group, chosen, per)
    expected, expected_owner = _samples_by_sorting(group, chosen, per)
    np.testing.assert_array_equal(samples, expected)
    np.testing.assert_array_equal(owner, expected_owner)


def test_the_scores_do_not_depend_on_the_number_of_threads() -> None:
    # A hemisphere of 10,240 faces (the Morton codes and the corners on every thread) beside
    # the scan fragments (many samples, cast on every thread).
    vertices, faces = icosphere(5)
    bowl = (vertices, faces[vertices[faces].mean(axis=1)[:, 2] > 0])
    vertices, faces = combined(bowl, scan_fragments())
    before = _core.threads()
    found = []
    try:
        for threads in (1, 2, 3):
            _core.set_threads(threads)
            found.append(scores(vertices, faces))
    finally:
        _core.set_threads(before)
    assert not np.isnan(found[0]).all()
    for score in found[1:]:
        assert score.tobytes() == found[0].tobytes()


def _small_hierarchy() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    unit = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    faces = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]], dtype=np.intp)
    codes, order = _core.face_morton_order(unit, faces)
    return unit, faces, codes, order


def test_the_core_refuses_faces_naming_missing_vertices() -> None:
    unit, faces, codes, order = _small_hierarchy()
    for bad in (4, -1, 2**62):
        wrong = faces.copy()
        wrong[2, 1] = bad
        with pytest.raises(IndexError, match="vertex that the points do not have"):
            _core.face_morton_order(unit, wrong)
        for gather in (True, False):  # read through the gathered corners, or from the points
            with pytest.raises(IndexError, match="vertex that the points do not have"):
                _core.bvh_build(unit, wrong, codes, order, 4, gather)
            with pytest.raises(IndexError, match="vertex that the points do not have"):
                _core.cast_rays(unit, wrong, codes, order, 4, gather, order, unit[:1], 1e-9)
    with pytest.raises(IndexError, match="vertex that the points do not have"):
        _core.face_morton_order(unit[:0], faces)


def test_the_core_refuses_a_hierarchy_that_is_not_the_faces() -> None:
    unit, faces, codes, order = _small_hierarchy()
    pattern = unit[1:]
    with pytest.raises(ValueError, match="one value for each face"):
        _core.bvh_build(unit, faces, codes[:3], order, 4, True)
    with pytest.raises(ValueError, match="increasing order"):
        _core.bvh_build(unit, faces, np.arange(4)[::-1].copy(), order, 1, True)
    with pytest.raises(ValueError, match="at least one face"):
        _core.cast_rays(unit, faces, codes, order, 0, True, order, pattern, 1e-9)
    for bad in (4, -1):
        wrong = order.copy()
        wrong[0] = bad
        with pytest.raises(IndexError, match="order names a face"):
            _core.bvh_build(unit, faces, codes, wrong, 4, False)
        with pytest.raises(IndexError, match="sample names a face"):
            _core.cast_rays(unit, faces, codes, order, 4, True, wrong, pattern, 1e-9)
    with pytest.raises(TypeError):  # an int32 order is refused, not copied
        _core.bvh_build(unit, faces, codes, order.astype(np.int32), 4, True)


def test_the_core_refuses_samples_that_do_not_fit() -> None:
    group = np.array([0, 1, 0, 1, 2], dtype=np.intp)
    counts, take = np.array([2, 2], dtype=np.intp), np.array([2, 2], dtype=np.intp)
    slot = np.array([0, 1, -1], dtype=np.intp)
    samples = np.empty(4, dtype=np.intp)
    _core.pick_samples(group, slot, counts, take, np.array([0, 2], dtype=np.intp), samples)
    assert samples.tolist() == [0, 2, 1, 3]
    with pytest.raises(IndexError, match="do not fit"):
        _core.pick_samples(group, slot, counts, take, np.array([0, 3], dtype=np.intp), samples)
    with pytest.raises(IndexError, match="do not fit"):
        _core.pick_samples(group, slot, counts, take, np.array([-1, 2], dtype=np.intp), samples)
    with pytest.raises(IndexError, match="chosen patch that there is not"):
        _core.pick_samples(group, np.array([0, 2, -1]), counts, take, counts - 2, samples)
    with pytest.raises(ValueError, match="each chosen patch"):
        _core.pick_samples(group, slot, counts, take[:1], counts - 2, samples)
