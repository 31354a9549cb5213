"""The half-edges sorted by edge, then by face: a counting sort by vertex, against a sort."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mesh_normal import _core
from mesh_normal.mesh import topology


def reference(faces: np.ndarray, valid: np.ndarray, vertex_count: int) -> np.ndarray:
    """The packed half-edges of the valid faces, sorted by NumPy."""
    bits = len(faces).bit_length() + 1
    following = faces[:, [1, 2, 0]]
    low, high = np.minimum(faces, following), np.maximum(faces, following)
    forward = (faces < following).astype(np.int64)
    face = np.arange(len(faces))[:, None]
    packed = (low * vertex_count + high) << bits | face << 1 | forward
    return np.sort(packed[valid].ravel())


def packed_sorted(faces: np.ndarray, valid: np.ndarray, vertex_count: int):  # type: ignore[no-untyped-def]
    bits = len(faces).bit_length() + 1
    packed = np.empty(3 * int(valid.sum()), dtype=np.int64)
    _core.sorted_half_edges(faces, valid, vertex_count, bits, packed)
    return packed


def valid_of(faces: np.ndarray) -> np.ndarray:
    return (
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    )


@settings(max_examples=60, deadline=None)
@given(
    vertex_count=st.integers(3, 40),
    faces=arrays(np.int64, st.tuples(st.integers(0, 120), st.just(3)), elements=st.integers(0, 39)),
)
def test_random_faces_come_out_as_a_full_sort_gives_them(vertex_count, faces) -> None:  # type: ignore[no-untyped-def]
    faces = faces % vertex_count  # repeated edges, non-manifold ones and degenerate faces
    valid = valid_of(faces)
    expected = reference(faces, valid, vertex_count)
    assert np.array_equal(packed_sorted(faces, valid, vertex_count), expected)


def test_a_vertex_of_high_valence_and_shuffled_faces() -> None:
    rng = np.random.default_rng(7)
    rim = 400  # a fan of 400 faces around vertex 0, then a shuffled strip
    fan = np.stack([np.zeros(rim, np.int64), 1 + np.arange(rim), 1 + (np.arange(rim) + 1) % rim], 1)
    strip = rng.integers(0, rim + 1, size=(300, 3))
    faces = np.concatenate([fan, strip])[rng.permutation(rim + 300)]
    faces[::3] = faces[::3, ::-1].copy()  # both directions along the edges
    valid = valid_of(faces)
    expected = reference(faces, valid, rim + 1)
    assert np.array_equal(packed_sorted(faces, valid, rim + 1), expected)


def test_the_sorted_half_edges_give_key_face_and_direction() -> None:
    faces = np.array([[0, 1, 2], [2, 1, 3], [0, 0, 1], [3, 1, 0]])
    valid = valid_of(faces)
    key, face, forward = topology._sorted_half_edges(faces, valid, 4)
    pairs = [
        (int(k) // 4, int(k) % 4, int(f), int(d))
        for k, f, d in zip(key, face, forward, strict=True)
    ]
    assert pairs == sorted(pairs)
    assert len(pairs) == 9  # the face with a repeated vertex has no half-edges
    assert (0, 1, 0, 1) in pairs and (0, 1, 3, 0) in pairs and (1, 2, 1, 0) in pairs


def lexsorted(faces: np.ndarray, valid: np.ndarray, vertex_count: int):  # type: ignore[no-untyped-def]
    """Key, face and direction of the valid faces' half-edges by key, face, corner (NumPy)."""
    following = faces[:, [1, 2, 0]]
    low, high = np.minimum(faces, following), np.maximum(faces, following)
    forward = (faces < following).astype(np.int8)
    face = np.broadcast_to(np.arange(len(faces))[:, None], low.shape)
    low, high, forward, face = (array[valid].ravel() for array in (low, high, forward, face))
    order = np.lexsort((np.arange(len(low)), high, low))
    return low[order] * vertex_count + high[order], face[order], forward[order]


@settings(max_examples=60, deadline=None)
@given(
    vertex_count=st.integers(3, 40),
    faces=arrays(np.int64, st.tuples(st.integers(0, 120), st.just(3)), elements=st.integers(0, 39)),
    fan=st.integers(0, 60),
)
def test_the_wide_sort_gives_what_a_lexsort_gives(vertex_count, faces, fan) -> None:  # type: ignore[no-untyped-def]
    """The counting sort for meshes of more points than a packed key holds (the Lucy size),
    with a vertex of high valence and without."""
    rim = np.arange(fan) % (vertex_count - 1)
    faces = np.concatenate([faces % vertex_count, np.stack([0 * rim, 1 + rim, 2 + rim], 1)])
    faces %= vertex_count
    valid = valid_of(faces)
    count = 3 * int(valid.sum())
    key, face, forward = (
        np.empty(count, np.int64),
        np.empty(count, np.int32),
        np.empty(count, np.int8),
    )
    bits = len(faces).bit_length() + 1
    _core.wide_half_edges(faces, valid, vertex_count, bits, key, face, forward)
    expected = lexsorted(faces, valid, vertex_count)
    for got, want in zip((key, face, forward), expected, strict=True):
        assert np.array_equal(got, want)


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_runs_of_many_vertex_blocks_are_each_sorted(threads: int) -> None:
    """More vertices than one thread's piece of the run sorts: the pieces join up, in the
    packed sort and in the wide one, on any number of threads."""
    rng = np.random.default_rng(11)
    vertex_count = 3 * 4096 + 5
    faces = rng.integers(0, vertex_count, size=(40_000, 3))
    valid = valid_of(faces)
    before = _core.threads()
    _core.set_threads(threads)
    try:
        packed = packed_sorted(faces, valid, vertex_count)
        key, face, forward = topology._wide_half_edges(faces, valid, vertex_count)
    finally:
        _core.set_threads(before)
    assert np.array_equal(packed, reference(faces, valid, vertex_count))
    for got, want in zip((key, face, forward), lexsorted(faces, valid, vertex_count), strict=True):
        assert np.array_equal(got, want)
