"""The compiled topology kernels (mesh_normal._core) against NumPy and SciPy references, and
their refusals of arguments that do not fit (a sentence, never a crash)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from mesh_normal import _core
from mesh_normal.mesh import topology


def runs_reference(key: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """First positions of the runs of equal sorted keys one, two and more long; the lengths."""
    _, starts, lengths = np.unique(key, return_index=True, return_counts=True)
    return (
        starts[lengths == 1],
        starts[lengths == 2],
        starts[lengths > 2],
        lengths[lengths > 2],
    )


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("paired_type", [np.int32, np.int64])
def test_the_runs_are_found_as_numpy_finds_them(seed: int, paired_type: type) -> None:
    rng = np.random.default_rng(seed)
    key = np.sort(rng.integers(0, 60 + 40 * seed, 200 * seed))
    ones, twos, more, lengths = runs_reference(key)
    assert _core.count_runs(key) == (len(ones), len(twos), len(more))
    boundary, paired = np.empty(len(ones), np.int64), np.empty(len(twos), paired_type)
    nonmanifold, uses = np.empty(len(more), np.int64), np.empty(len(more), np.int64)
    _core.find_runs(key, boundary, paired, nonmanifold, uses)
    for got, want in zip(
        (boundary, paired, nonmanifold, uses), (ones, twos, more, lengths), strict=True
    ):
        assert np.array_equal(got, want)


def test_runs_into_arrays_of_other_sizes_are_refused() -> None:
    key = np.array([1, 1, 2, 3, 3, 3], dtype=np.int64)  # one of each kind
    empty = np.empty(0, np.int64)
    with pytest.raises(ValueError, match="sizes that count_runs gives"):
        _core.find_runs(
            key, empty, np.empty(1, np.int64), np.empty(1, np.int64), np.empty(1, np.int64)
        )
    with pytest.raises(ValueError, match="sizes that count_runs gives"):
        _core.find_runs(
            key,
            np.empty(2, np.int64),
            np.empty(1, np.int64),
            np.empty(1, np.int64),
            np.empty(1, np.int64),
        )
    with pytest.raises(TypeError):  # a wrong dtype is not silently copied
        _core.count_runs(key.astype(np.int32))


def test_pair_faces_reads_both_half_edges_of_each_pair() -> None:
    face = np.array([5, 7, 2, 9, 4], dtype=np.int32)
    forward = np.array([1, 0, 1, 1, 0], dtype=np.int8)
    paired = np.array([0, 2], dtype=np.int32)
    one, two, same = np.empty(2, np.int32), np.empty(2, np.int32), np.empty(2, np.int8)
    _core.pair_faces(face, forward, paired, one, two, same)
    assert one.tolist() == [5, 2] and two.tolist() == [7, 9] and same.tolist() == [0, 1]
    with pytest.raises(IndexError, match="paired position"):
        _core.pair_faces(face, forward, np.array([0, 4], np.int32), one, two, same)
    with pytest.raises(IndexError, match="paired position"):
        _core.pair_faces(face, forward, np.array([-1, 0], np.int32), one, two, same)


def components_reference(count: int, one: np.ndarray, two: np.ndarray) -> np.ndarray:
    """Each node's smallest connected node, by SciPy's connected components."""
    graph = coo_matrix((np.ones(len(one)), (one, two)), shape=(count, count))
    _, label = connected_components(graph, directed=False)
    smallest = np.full(label.max() + 1 if count else 0, count)
    np.minimum.at(smallest, label, np.arange(count))
    return smallest[label]


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("node_type", [np.int32, np.int64])
def test_union_find_labels_each_node_with_its_smallest_connected_node(
    seed: int, node_type: type
) -> None:
    rng = np.random.default_rng(seed)
    count = int(rng.integers(1, 3000))
    edges = int(rng.integers(0, count))
    one = rng.integers(0, count, edges).astype(node_type)
    two = rng.integers(0, count, edges).astype(node_type)
    # Parities from a hidden flip of each node: consistent, so they must come back exactly.
    flip = rng.integers(0, 2, count).astype(np.int8)
    same = (flip[one] ^ flip[two]).astype(np.int8)
    root, parity = np.empty(count, np.int64), np.empty(count, np.int8)
    _core.union_find(count, one, two, same, root, parity)
    assert np.array_equal(root, components_reference(count, one, two))
    assert np.array_equal(parity, flip ^ flip[root])


def test_union_find_refuses_a_node_that_does_not_exist() -> None:
    root, parity = np.empty(3, np.int64), np.empty(3, np.int8)
    same = np.zeros(1, np.int8)
    for bad in (3, -1):
        with pytest.raises(IndexError, match="does not exist"):
            _core.union_find(3, np.array([0]), np.array([bad]), same, root, parity)
    with pytest.raises(ValueError, match="count places"):
        _core.union_find(4, np.array([0]), np.array([1]), same, root, parity)


def test_number_roots_numbers_them_in_order() -> None:
    root = np.array([0, 0, 2, 1, 4, 2, 6], dtype=np.int64)  # node 3's root is 1 (compressed: 0)
    root[3] = 0
    valid = np.array([1, 1, 1, 1, 0, 1, 1], dtype=bool)
    firsts = _core.number_roots(root, valid)
    assert root.tolist() == [0, 0, 1, 0, -1, 1, 2]
    assert firsts.tolist() == [0, 2, 6]
    with pytest.raises(ValueError, match="at or before it"):
        _core.number_roots(np.array([1, 1], dtype=np.int64), np.ones(2, dtype=bool))


def test_mark_unorientable_refuses_faces_and_patches_out_of_range() -> None:
    one, two, same = np.array([0], np.int32), np.array([1], np.int32), np.array([0], np.int8)
    parity, orientable = np.array([0, 1], np.int8), np.ones(1, dtype=bool)
    _core.mark_unorientable(one, two, same, parity, np.array([0, 0]), orientable)
    assert orientable.tolist() == [False]  # parities 0 and 1 but not the same way: a Moebius
    with pytest.raises(IndexError, match="does not exist"):
        _core.mark_unorientable(
            one, np.array([2], np.int32), same, parity, np.array([0, 0]), orientable
        )
    with pytest.raises(IndexError, match="does not exist"):
        _core.mark_unorientable(one, two, same, parity, np.array([1, 0]), orientable)


def test_the_half_edge_sorts_refuse_indices_and_sizes_that_do_not_fit() -> None:
    faces = np.array([[0, 1, 2], [2, 1, 5]], dtype=np.int64)
    valid = np.ones(2, dtype=bool)
    bits = 3
    with pytest.raises(IndexError, match="does not exist"):
        _core.sorted_half_edges(faces, valid, 5, bits, np.empty(6, np.int64))
    with pytest.raises(IndexError, match="does not exist"):
        _core.sorted_half_edges(-faces, valid, 6, bits, np.empty(6, np.int64))
    with pytest.raises(ValueError, match="one place for each half-edge"):
        _core.sorted_half_edges(faces, valid, 6, bits, np.empty(5, np.int64))
    with pytest.raises(ValueError, match="one flag a face"):
        _core.sorted_half_edges(faces, valid[:1], 6, bits, np.empty(6, np.int64))
    with pytest.raises(ValueError, match="do not fit 64 bits"):
        _core.sorted_half_edges(faces, valid, 2**40, bits, np.empty(6, np.int64))
    key, face, forward = np.empty(6, np.int64), np.empty(6, np.int32), np.empty(6, np.int8)
    with pytest.raises(IndexError, match="does not exist"):
        _core.wide_half_edges(faces, valid, 5, bits, key, face, forward)
    with pytest.raises(ValueError, match="a place a half-edge"):
        _core.wide_half_edges(faces, valid, 6, bits, key[:5], face, forward)
    with pytest.raises(ValueError, match="do not fit 64 bits"):
        _core.wide_half_edges(faces, valid, 2**32, bits, key, face, forward)
    with pytest.raises(ValueError, match="fit the key's bits"):
        _core.wide_half_edges(faces, valid, 6, 1, key, face, forward)


def test_the_structure_of_a_mesh_of_many_points_takes_the_wide_sort() -> None:
    """More points than a packed key holds beside the faces (the Lucy size): the wide sort
    gives the same topology as the packed one on the same faces with fewer points."""
    rng = np.random.default_rng(3)
    faces = rng.integers(0, 3000, (20_000, 3))
    few = topology.structure(faces, 3000)
    spread = faces * 2**12  # the same mesh, its points spread over 12M indices
    count = 3000 * 2**12
    many = topology.structure(spread, count)
    assert count * count << (len(faces).bit_length() + 1) >= topology.KEY_LIMIT
    for name in ("boundary_edges", "nonmanifold_edges", "components", "winding_consistent"):
        assert getattr(few.topology, name) == getattr(many.topology, name)
    assert np.array_equal(few.topology.face_component, many.topology.face_component)
    assert np.array_equal(few.parity, many.parity)
    assert np.array_equal(few.topology.boundary_edge_list * 2**12, many.topology.boundary_edge_list)
