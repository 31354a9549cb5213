"""Nesting decides cavities: a closed shell inside an even number of others faces out, inside an
odd number in, so every surface faces away from the material (mesh_normal.mesh.orientation).

Each case is built right (every shell facing away from its material); the tests then turn
shells the wrong way and check that orient() turns exactly those back, wherever the mesh is."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.mesh import orientation
from mesh_normal.mesh.orientation import orient, signed_volume
from tests.meshes import (
    CUBE_FACES,
    CUBE_VERTICES,
    Shell,
    ball,
    box,
    built,
    random_rotation,
    turned,
)
from tests.meshes import (
    NESTED_CASES as CASES,
)


@pytest.mark.parametrize("name", CASES)
def test_a_right_mesh_is_left_alone_and_its_depths_are_known(name: str) -> None:
    shells, depths = CASES[name]
    vertices, faces, _ = built(*shells)
    r = orient(vertices, faces)
    assert not r.flipped.any() and r.orientation == "outward"
    assert [c.depth for c in r.components] == depths
    assert [c.method for c in r.components] == ["volume"] * len(depths)
    # Cavities have a negative volume: the volumes sum to the material's.
    assert [c.volume is not None and c.volume < 0 for c in r.components] == [
        d % 2 == 1 for d in depths
    ]


def test_the_innermost_holding_shell_is_named() -> None:
    vertices, faces, _ = built(*CASES["three levels of hollow balls"][0])
    r = orient(vertices, faces)
    assert [c.inside for c in r.components] == [None, 0, 1, 2, 3, 4]
    assert all(c.touches is None for c in r.components)


# What the issue found: each failed before nesting decided.


def test_a_hollow_ball_with_its_cavity_facing_out_is_fixed() -> None:
    vertices, faces, labels = built(*CASES["hollow ball"][0])
    r = orient(vertices, turned(faces, labels, [1]))
    assert np.array_equal(r.flipped, labels == 1)
    assert [c.orientation for c in r.components] == ["outward", "inward"]
    assert r.components[1].method == "volume"
    assert np.array_equal(r.faces, faces)


def test_a_hollow_ball_inside_out_has_both_shells_turned() -> None:
    vertices, faces, _ = built(*CASES["hollow ball"][0])
    r = orient(vertices, faces[:, ::-1])
    assert r.flipped.all() and r.orientation == "inward"
    # The fixed mesh's volume is the material's: the ball less the cavity.
    outer = signed_volume(*ball(1.0))
    cavity = signed_volume(*ball(0.5))
    assert signed_volume(vertices, r.faces) == pytest.approx(outer - cavity)


def test_a_ball_inside_a_hollow_ball_all_facing_out_is_fixed() -> None:
    vertices, faces, labels = built(*CASES["ball in a hollow ball"][0])
    facing_out = turned(faces, labels, [1])
    r = orient(vertices, facing_out)
    assert np.array_equal(r.flipped, labels == 1)
    assert np.array_equal(r.faces, faces)


def test_two_hollow_boxes_side_by_side_all_facing_out_are_fixed() -> None:
    vertices, faces, labels = built(*CASES["two hollow boxes side by side"][0])
    r = orient(vertices, turned(faces, labels, [1, 3]))
    assert np.array_equal(r.flipped, np.isin(labels, [1, 3]))
    assert [c.depth for c in r.components] == [0, 1, 0, 1]


# Anywhere alike, every wrong choice of shells undone.


@settings(max_examples=60, deadline=None)
@given(
    name=st.sampled_from(sorted(CASES)),
    choice=st.integers(0, 2**32 - 1),
    shift=st.sampled_from([0.0, 1.0, -1e4, 1e6]),
    scale=st.sampled_from([1.0, 1e-6, 2.0**-20, 0.37, 1e3, 1e6]),
    seed=st.integers(0, 2**32 - 1),
)
def test_any_shells_turned_wrong_are_turned_back_anywhere(
    name: str, choice: int, shift: float, scale: float, seed: int
) -> None:
    shells, depths = CASES[name]
    vertices, faces, labels = built(*shells)
    wrong = np.flatnonzero(np.random.default_rng(choice).random(len(depths)) < 0.5).tolist()
    moved = scale * vertices @ random_rotation(seed).T + shift * scale * np.array([1, -0.7, 0.3])
    r = orient(moved, turned(faces, labels, wrong))
    assert np.array_equal(r.flipped, np.isin(labels, wrong)), (name, wrong)
    assert [c.depth for c in r.components] == depths


@pytest.mark.parametrize("offset", [1e6, -1e6])
@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_depths_are_the_same_far_away_and_at_any_scale(offset: float, scale: float) -> None:
    # Turned, so that the coordinates are not all float32 values (which would be taken as
    # rounded to float32, too coarse at 1e6 for these shells' volumes to count).
    rotation = random_rotation(1)
    for name, (shells, depths) in CASES.items():
        vertices, faces, labels = built(*shells)
        there = (vertices @ rotation.T + offset) * scale
        r = orient(there, turned(faces, labels, [0]))
        assert [c.depth for c in r.components] == depths, name
        assert np.array_equal(r.flipped, labels == 0), name


# Shells that touch or cross.


def test_a_cavity_touching_the_outer_surface_is_left_as_it_is() -> None:
    # The cavity's corner lies on the outer box's bottom face: its depth is not known.
    outer = box(2.0)
    inner = box(1.0, (0.0, 0.0, -0.5))
    vertices, faces, labels = built((outer, False), (inner, True))
    for winding in (faces, turned(faces, labels, [1])):
        r = orient(vertices, winding)
        assert not r.flipped[labels == 1].any()
        part = r.components[1]
        assert part.depth is None and part.touches == 0 and part.method == "none"
    # The outer shell is still decided.
    assert np.array_equal(orient(vertices, turned(faces, labels, [0])).flipped, labels == 0)


def test_a_shell_that_crosses_another_is_a_body_of_its_own() -> None:
    # A ball sunk mostly into a box, its cap out: no cavity, so it faces out.
    vertices, faces, labels = built((box(2.0), False), (ball(0.3, (0.0, 0.0, 0.9)), False))
    r = orient(vertices, faces)
    assert not r.flipped.any() and [c.depth for c in r.components] == [0, 0]
    assert np.array_equal(orient(vertices, turned(faces, labels, [1])).flipped, labels == 1)


def dented_box() -> Shell:
    """The box of side 2 with a crater in its top: the top's centre pushed down to z = 0.5."""
    vertices = np.r_[(CUBE_VERTICES - 0.5) * 2, [[0.0, 0.0, 0.5]]]
    top = [[4, 5, 8], [5, 7, 8], [7, 6, 8], [6, 4, 8]]
    return vertices, np.r_[CUBE_FACES[:2], CUBE_FACES[4:], top]  # rows 2 and 3 are the top


def test_a_shell_whose_samples_lie_inside_but_that_crosses_is_no_cavity(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # One sample, inside the box; but the crater's tip lies inside the ball: they cross.
    monkeypatch.setattr(orientation, "_NEST_SAMPLES", 1)
    monkeypatch.setattr(orientation, "_NEST_FIRST", 1)
    points, triangles = dented_box()
    ball_points, ball_faces = ball(0.3)
    low = ball_points[ball_faces[0, 0]]
    centre = (0.0, 0.0, 0.45 - low[2]) if low[2] < 0 else (0.0, 0.0, 0.45)
    vertices, faces, _ = built(((points, triangles), False), (ball(0.3, centre), False))
    r = orient(vertices, faces)
    assert r.topology.watertight
    assert not r.flipped.any() and [c.depth for c in r.components] == [0, 0]


def test_nested_shells_past_the_limits_are_left_as_they_are(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    vertices, faces, labels = built(*CASES["hollow ball"][0])
    wrong = turned(faces, labels, [1])
    assert np.array_equal(orient(vertices, wrong).flipped, labels == 1)
    monkeypatch.setattr(orientation, "_NEST_WORK", 10)
    r = orient(vertices, wrong)
    assert not r.flipped[labels == 1].any() and r.components[1].depth is None
    monkeypatch.setattr(orientation, "_NEST_WORK", 2 * 10**8)
    monkeypatch.setattr(orientation, "_NEST_PAIRS", 0)
    r = orient(vertices, wrong)
    assert not r.flipped[labels == 1].any() and r.components[1].depth is None
    # A shell in no other's box has depth 0 without a winding number.
    assert r.components[0].depth == 0


def test_many_small_closed_parts_side_by_side_are_decided_quickly() -> None:
    # 10,000 hollow boxes (20,000 shells) in a grid, every cavity facing out: all fixed.
    count = 10_000
    single, _, labels = built((box(1.0), False), (box(0.5), True))
    _, single_faces, _ = built((box(1.0), False), (box(0.5), True))
    offsets = np.stack(
        [np.arange(count) % 100 * 2.0, np.arange(count) // 100 * 2.0, 0 * np.arange(count)], 1
    )
    vertices = (single[None] + offsets[:, None]).reshape(-1, 3)
    faces = (single_faces[None] + len(single) * np.arange(count)[:, None, None]).reshape(-1, 3)
    all_labels = np.tile(labels, count)
    wrong = turned(faces, all_labels, [1])
    r = orient(vertices, wrong)
    assert np.array_equal(r.flipped, all_labels == 1)


def test_many_shells_in_one_place_are_left_as_they_are_quickly(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 3,000 cubes one inside the next, wound inward: 4.5 million pairs of boxes, far past the
    # room for them. Only the largest, in no other's box, has a known depth (0): turned out.
    count = 3000
    vertices, faces, labels = built(*[(box(1.0 + 1e-3 * i), True) for i in range(count)])
    r = orient(vertices, faces)
    assert np.array_equal(r.flipped, labels == count - 1)
    assert [c.depth for c in r.components] == [None] * (count - 1) + [0]
    # Past the budget of comparisons, the same.
    vertices, faces, labels = built(*CASES["hollow ball"][0])
    monkeypatch.setattr(orientation, "_NEST_COMPARISONS", 0)
    r = orient(vertices, turned(faces, labels, [1]))
    assert not r.flipped.any() and [c.depth for c in r.components] == [None, None]
