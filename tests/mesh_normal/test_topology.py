"""The half-edges sorted by edge, then by face: a counting sort by vertex, against a sort."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mesh_normal import topology
from mesh_normal.kernels import PARALLEL_KERNELS, load_numba, workers


def reference(faces: np.ndarray, valid: np.ndarray, vertex_count: int) -> np.ndarray:
    """The packed half-edges of the valid faces, sorted by NumPy."""
    bits = len(faces).bit_length() + 1
    following = faces[:, [1, 2, 0]]
    low, high = np.minimum(faces, following), np.maximum(faces, following)
    forward = (faces < following).astype(np.int64)
    face = np.arange(len(faces))[:, None]
    packed = (low * vertex_count + high) << bits | face << 1 | forward
    return np.sort(packed[valid].ravel())


def packed_sorted(faces: np.ndarray, valid: np.ndarray, vertex_count: int, python: bool):  # type: ignore[no-untyped-def]
    bits = len(faces).bit_length() + 1
    packed = np.empty(3 * int(valid.sum()), dtype=np.int64)
    starts = np.zeros(vertex_count + 1, dtype=np.intp)
    run = topology._pack_half_edges.py_func if python else topology._pack_half_edges
    if not python:
        load_numba()
    run(faces, valid, vertex_count, bits, packed, starts)
    with PARALLEL_KERNELS:  # each run sorted on every core (as Python too, before numba loads)
        topology._finish_runs(
            packed, topology._NO_FACES, topology._NO_DIRECTIONS, starts, bits, False, *workers()
        )
    return packed


def valid_of(faces: np.ndarray) -> np.ndarray:
    return (
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    )


@settings(max_examples=60, deadline=None)
@given(
    vertex_count=st.integers(3, 40),
    faces=arrays(np.int64, st.tuples(st.integers(0, 120), st.just(3)), elements=st.integers(0, 39)),
    python=st.booleans(),
)
def test_random_faces_come_out_as_a_full_sort_gives_them(vertex_count, faces, python) -> None:  # type: ignore[no-untyped-def]
    faces = faces % vertex_count  # repeated edges, non-manifold ones and degenerate faces
    valid = valid_of(faces)
    expected = reference(faces, valid, vertex_count)
    assert np.array_equal(packed_sorted(faces, valid, vertex_count, python), expected)


@pytest.mark.parametrize("python", [False, True])
def test_a_vertex_of_high_valence_and_shuffled_faces(python: bool) -> None:
    rng = np.random.default_rng(7)
    rim = 400  # a fan of 400 faces around vertex 0, then a shuffled strip
    fan = np.stack([np.zeros(rim, np.int64), 1 + np.arange(rim), 1 + (np.arange(rim) + 1) % rim], 1)
    strip = rng.integers(0, rim + 1, size=(300, 3))
    faces = np.concatenate([fan, strip])[rng.permutation(rim + 300)]
    faces[::3] = faces[::3, ::-1].copy()  # both directions along the edges
    valid = valid_of(faces)
    expected = reference(faces, valid, rim + 1)
    assert np.array_equal(packed_sorted(faces, valid, rim + 1, python), expected)


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
    python=st.booleans(),
)
def test_the_wide_sort_gives_what_a_lexsort_gives(vertex_count, faces, fan, python) -> None:  # type: ignore[no-untyped-def]
    """The counting sort for meshes of more points than a packed key holds (the Lucy size),
    with a vertex of high valence (the merge sort of its run) and without."""
    rim = np.arange(fan) % (vertex_count - 1)
    faces = np.concatenate([faces % vertex_count, np.stack([0 * rim, 1 + rim, 2 + rim], 1)])
    faces %= vertex_count
    valid = valid_of(faces)
    count = 3 * int(valid.sum())
    key, face = np.empty(count, np.int64), np.empty(count, np.int32)
    forward, starts = np.empty(count, np.int8), np.zeros(vertex_count + 1, np.intp)
    run = topology._sort_wide_half_edges
    if python:
        run = run.py_func
    else:
        load_numba()
    bits = len(faces).bit_length() + 1
    run(faces, valid, vertex_count, bits, key, starts)
    with PARALLEL_KERNELS:
        topology._finish_runs(key, face, forward, starts, bits, True, *workers())
    expected = lexsorted(faces, valid, vertex_count)
    for got, want in zip((key, face, forward), expected, strict=True):
        assert np.array_equal(got, want)


def test_runs_of_many_vertex_blocks_are_each_sorted() -> None:
    """More vertices than one task of the run sorts takes (``RUN_BLOCK``): the blocks claimed
    by every core join up, in the packed sort and in the wide one."""
    rng = np.random.default_rng(11)
    vertex_count = 3 * topology.RUN_BLOCK + 5
    faces = rng.integers(0, vertex_count, size=(40_000, 3))
    valid = valid_of(faces)
    load_numba()
    assert np.array_equal(
        packed_sorted(faces, valid, vertex_count, False), reference(faces, valid, vertex_count)
    )
    key, face, forward = topology._wide_half_edges(faces, valid, vertex_count)
    for got, want in zip((key, face, forward), lexsorted(faces, valid, vertex_count), strict=True):
        assert np.array_equal(got, want)
