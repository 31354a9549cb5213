"""The point kernels of the compiled core (cpp/points.cpp) against small NumPy references and
hand-worked cases; what they refuse; and the same bits for any number of threads."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from mesh_normal import _core
from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.io.pcd import lzf_decompress
from mesh_normal.tolerances import POINT_GAP_RATIO, POINT_LINE_RATIO
from tests.mesh_normal.points._pcd import lzf_compress
from tests.paths import ROOT

RNG = np.random.default_rng(11)
#: What lzf_decompress says of data it refuses.
REFUSALS = (
    r"The compressed PCD data (unpack to more than the 3,000 bytes the file says\."
    r"|are broken \(not valid LZF\)\.|unpack to [\d,]+ bytes, not the 3,000 the file says\.)"
)


def estimate(
    points: np.ndarray, indptr: np.ndarray, neighbours: np.ndarray, tiny: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rows = max(0, len(indptr) - 1)
    normals, curvature = np.empty((rows, 3)), np.empty(rows)
    used, status = np.empty(rows, dtype=np.intp), np.empty(rows, dtype=np.intp)
    _core.neighbourhood_normals(
        points,
        indptr,
        neighbours,
        tiny,
        POINT_LINE_RATIO,
        POINT_GAP_RATIO,
        normals,
        curvature,
        used,
        status,
    )
    return normals, curvature, used, status


def test_neighbourhood_normals_match_numpy_eigh() -> None:
    points = RNG.normal(size=(500, 3)) * [1.0, 2.0, 0.1]  # flattened: a clear smallest axis
    sizes = RNG.integers(3, 40, size=300)
    indptr = np.r_[0, np.cumsum(sizes)].astype(np.intp)
    neighbours = RNG.integers(-3, 503, size=indptr[-1]).astype(np.intp)  # some not rows: skipped
    normals, curvature, used, status = estimate(points, indptr, neighbours)
    for r in range(len(sizes)):
        listed = neighbours[indptr[r] : indptr[r + 1]]
        chosen = points[listed[(listed >= 0) & (listed < len(points))]]
        assert used[r] == len(chosen)
        if len(chosen) < 3:
            assert status[r] == 2 and not normals[r].any() and curvature[r] == 0.0
            continue
        values, vectors = np.linalg.eigh(np.cov(chosen.T, bias=True))
        expected = vectors[:, 0] * np.sign(vectors[np.argmax(np.abs(vectors[:, 0])), 0])
        assert status[r] == 0
        np.testing.assert_allclose(normals[r], expected, atol=1e-9)
        np.testing.assert_allclose(curvature[r], values[0] / values.sum(), rtol=1e-9, atol=1e-12)


def test_degenerate_neighbourhoods_get_their_codes() -> None:
    line = np.linspace(0.0, 1.0, 5)[:, None] * [1.0, 2.0, 3.0]
    square = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])  # symmetric in the plane
    pile = np.zeros((4, 3))
    points = np.concatenate([line, square, pile])
    indptr = np.array([0, 5, 9, 13, 15], dtype=np.intp)
    neighbours = np.arange(15, dtype=np.intp)  # the last two rows of the list are no points
    normals, curvature, used, status = estimate(points, indptr, neighbours)
    assert status.tolist() == [4, 0, 3, 2]  # collinear, ok, duplicates, too few
    assert used.tolist() == [5, 4, 4, 0]
    np.testing.assert_array_equal(normals[1], [0.0, 0.0, 1.0])
    assert not normals[[0, 2, 3]].any()
    assert curvature[2] == curvature[3] == 0.0
    # An octahedron's corners: no direction is flatter than another.
    corners = np.concatenate([np.eye(3), -np.eye(3)])
    assert estimate(corners, np.array([0, 6]), np.arange(6))[3].tolist() == [5]  # ambiguous


@pytest.mark.parametrize(
    ("indptr", "error", "words"),
    [
        ([0, 2, 9], IndexError, "outside the neighbour list"),
        ([-1, 2, 3], IndexError, "outside the neighbour list"),
        ([0, 3, 2], ValueError, "run backwards"),
        ([], ValueError, "at least one row pointer"),
    ],
)
def test_bad_row_pointers_are_refused(indptr: list[int], error: type, words: str) -> None:
    points = np.zeros((4, 3))
    with pytest.raises(error, match=words):
        estimate(points, np.array(indptr, dtype=np.intp), np.arange(4, dtype=np.intp))


def test_outputs_of_the_wrong_size_or_type_are_refused() -> None:
    points, indptr, neighbours = np.zeros((4, 3)), np.array([0, 4]), np.arange(4)
    out = (np.empty((2, 3)), np.empty(1), np.empty(1, dtype=np.intp), np.empty(1, dtype=np.intp))
    with pytest.raises(ValueError, match="one row per neighbour list"):
        _core.neighbourhood_normals(points, indptr, neighbours, 0.0, 0.0, 0.0, *out)
    with pytest.raises(TypeError):  # int32 row pointers: not silently converted
        estimate(points, indptr.astype(np.int32), neighbours)


def test_graph_edges_by_hand() -> None:
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    normals = np.array([[0.0, 0, 1], [0, 0, 1], [0, 0.6, 0.8], [1, 0, 0]])
    valid = np.array([True, True, True, False])
    # 0 and 1 list each other (one edge), 2 lists 0 and itself, 3 has no normal, -1 is no one.
    graph = np.array([[1, -1], [0, 2], [0, 2], [0, 1]], dtype=np.int32)
    rows, cols, weights = _core.graph_edges(points, normals, valid, graph, 0.5, 1.0)
    assert list(zip(rows.tolist(), cols.tolist(), strict=True)) == [(0, 1), (1, 2), (2, 0)]
    np.testing.assert_array_equal(weights, [0.5, 1.0 - 0.8 + 0.5, 1.0 - 0.8 + 0.5])
    # The riemannian graph: the step from 1 to 2 leaves 2's plane by sine 0.6 / sqrt(2), from 2
    # to 0 by 0.6, so a limit of 0.5 keeps (0, 1) and (1, 2) and weighs the second more.
    rows, cols, weights = _core.graph_edges(points, normals, valid, graph, 0.5, 0.5)
    assert list(zip(rows.tolist(), cols.tolist(), strict=True)) == [(0, 1), (1, 2)]
    assert weights[1] == 1.0 - 0.8 + 0.5 + 0.6 / np.sqrt(2.0)


def test_graph_edges_refuse_a_neighbour_that_is_no_point() -> None:
    points = np.zeros((2, 3))
    graph = np.array([[1], [2]], dtype=np.int32)
    with pytest.raises(IndexError, match="not one of the points"):
        _core.graph_edges(points, points, np.ones(2, dtype=bool), graph, 0.0, 1.0)
    with pytest.raises(ValueError, match="one row per point"):
        _core.graph_edges(points, points, np.ones(3, dtype=bool), graph[:1], 0.0, 1.0)


def test_signs_follow_the_tree_and_stop_at_sharp_edges() -> None:
    # A chain 0 - 1 - 2 - 3 rooted at 0 (flipped); 2 disagrees with 1; the edge 3 is sharp.
    order = np.array([0, 1, 2, 3], dtype=np.int32)
    parent = np.array([-1, 0, 1, 2], dtype=np.int32)
    agrees = np.array([True, True, False, True])
    sharp = np.array([False, False, False, True])
    seed_flip = np.array([True, False, False, False])
    flip, cut = _core.propagate_signs(order, parent, agrees, sharp, seed_flip)
    assert flip.tolist() == [True, True, False, False]
    assert cut.tolist() == [False, False, False, True]


def test_signs_refuse_points_that_are_not_there() -> None:
    flags = np.zeros(2, dtype=bool)
    with pytest.raises(IndexError, match="tree's order"):
        _core.propagate_signs(np.array([0, 2], np.int32), np.array([-1, 0], np.int32), *[flags] * 3)
    with pytest.raises(IndexError, match="parent"):
        _core.propagate_signs(np.array([0, 1], np.int32), np.array([-1, 5], np.int32), *[flags] * 3)


def test_mutated_and_cut_lzf_is_unpacked_or_refused_in_one_sentence() -> None:
    raw = bytes(RNG.integers(0, 3, size=3000).astype(np.uint8))
    packed = lzf_compress(raw)
    refusals = []
    for trial in range(500):
        data = bytearray(packed)
        for _ in range(1 + trial % 4):
            data[int(RNG.integers(0, len(data)))] = int(RNG.integers(0, 256))
        if trial % 3 == 0:
            data = data[: int(RNG.integers(0, len(data)))]
        try:
            unpacked = lzf_decompress(bytes(data), len(raw))
        except MeshFileError as error:
            refusals.append(str(error))
            continue
        assert len(unpacked) == len(raw)
    assert len(refusals) > 100
    assert [text for text in refusals if not re.fullmatch(REFUSALS, text)] == []


THREADS = """
import hashlib, numpy as np
from mesh_normal.points import point_normals
from tests.mesh_normal.points import _clouds
points = np.concatenate([_clouds.torus(20_000)[0], _clouds.terrain(5_000)[0]])
for orient in ("mst", "riemannian"):
    result = point_normals(points, k=16, orient=orient)
    digest = hashlib.sha256()
    for array in (result.normals, result.curvature, result.neighbours, result.status):
        digest.update(array.tobytes())
    print(digest.hexdigest())
"""


def test_the_same_bits_for_any_number_of_threads() -> None:
    digests = []
    for threads in ("1", "2"):
        environment = {**os.environ, "MESH_NORMAL_THREADS": threads}
        result = subprocess.run(
            [sys.executable, "-c", THREADS],
            cwd=ROOT,
            env=environment,
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert result.returncode == 0, result.stderr[-2000:]
        digests.append(result.stdout.split())
    assert len(digests[0]) == 2
    assert digests[0] == digests[1]
