"""The compiled orientation kernels (mesh_normal._core) against NumPy references and hand-made
cases, their refusals of arguments that do not fit, and their bits on any number of threads."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from mesh_normal import _core
from mesh_normal.mesh.checks import checked_mesh
from mesh_normal.mesh.faces import face_geometry
from tests.paths import ROOT


def cone_reference(
    points: np.ndarray, faces: np.ndarray, crosses: np.ndarray, group: np.ndarray, groups: int
) -> tuple[np.ndarray, np.ndarray]:
    """The cone terms and the group sums, in NumPy, in the kernel's order of operations (so
    the same bits: each sum in face order, as np.bincount adds)."""
    a, b, c = (points[faces[:, k]] for k in range(3))
    u, v = b - a, c - a
    n = crosses
    area = np.sqrt(n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1] + n[:, 2] * n[:, 2])
    sums = np.zeros((groups, 7))
    for k in range(3):
        sums[:, k] = np.bincount(group, area * ((u[:, k] + v[:, k]) / 3 + a[:, k]), groups)
    sums[:, 3] = np.bincount(group, area, groups)
    largest = np.abs(np.concatenate([a, b, c], axis=1)).max(axis=1)
    np.maximum.at(sums[:, 4], group, largest)
    total = np.where(sums[:, 3] != 0, sums[:, 3], 1.0)
    sums[:, :3] /= total[:, None]
    d = a - sums[group, :3]
    terms = n[:, 0] * d[:, 0] + n[:, 1] * d[:, 1] + n[:, 2] * d[:, 2]

    def length(x: np.ndarray) -> np.ndarray:
        return np.sqrt(x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1] + x[:, 2] * x[:, 2])

    to_a, to_b, to_c = length(d), length(d + u), length(d + v)
    sums[:, 5] = np.bincount(group, area * to_a, groups)
    sensitivity = 4 * area + to_a * length(v - u) + to_b * length(v) + to_c * length(u)
    sums[:, 6] = np.bincount(group, sensitivity, groups)
    return terms, sums


@pytest.mark.parametrize("seed", range(3))
def test_the_cone_sums_are_numpy_s_bits(seed: int) -> None:
    rng = np.random.default_rng(seed)
    count = 70_000 if seed == 0 else 500  # more than one chunk of shares
    vertices = rng.standard_normal((300, 3))
    faces = rng.integers(0, 300, (count, 3))
    mesh = checked_mesh(vertices, faces)
    geometry = face_geometry(mesh)
    crosses = geometry.crosses.copy()
    recomputed = np.zeros(count, dtype=bool)  # the geometry's products throughout
    group = rng.integers(0, 7, count)
    terms, sums = np.empty(count), np.zeros((7, 7))
    points = mesh.points * mesh.factor
    _core.cone_sums(points, 1.0, mesh.faces, crosses, recomputed, group, terms, sums)
    want_terms, want_sums = cone_reference(points, mesh.faces, crosses, group, 7)
    assert terms.tobytes() == want_terms.tobytes()
    assert sums.tobytes() == want_sums.tobytes()


def test_the_cone_sums_retake_a_recomputed_product_at_a() -> None:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    faces = np.array([[0, 1, 2]])
    wrong = np.array([[5.0, 5.0, 5.0]])
    terms, sums = np.empty(1), np.zeros((1, 7))
    _core.cone_sums(points, 1.0, faces, wrong, np.array([True]), np.zeros(1, np.int64), terms, sums)
    assert sums[0, 3] == 1.0  # |(1, 0, 0) x (0, 1, 0)|, not |wrong|


def test_the_cone_sums_refuse_what_does_not_fit() -> None:
    points = np.zeros((3, 3))
    faces = np.array([[0, 1, 2]])
    crosses, recomputed = np.zeros((1, 3)), np.zeros(1, dtype=bool)
    terms, sums = np.empty(1), np.zeros((1, 7))
    with pytest.raises(IndexError, match="does not exist"):
        _core.cone_sums(
            points, 1.0, faces + 1, crosses, recomputed, np.zeros(1, np.int64), terms, sums
        )
    with pytest.raises(IndexError, match="group is out of range"):
        _core.cone_sums(points, 1.0, faces, crosses, recomputed, np.ones(1, np.int64), terms, sums)
    with pytest.raises(ValueError, match="one row a face"):
        _core.cone_sums(
            points, 1.0, faces, crosses, recomputed, np.zeros(1, np.int64), np.empty(2), sums
        )


def test_group_sums_and_counts() -> None:
    group = np.array([0, 2, 0, 1, 2, 2])
    sums = np.zeros(3)
    _core.sum_by_group(group, np.array([0.5, 1, 2, 3, 4, 5]), sums)
    assert sums.tolist() == [2.5, 3.0, 10.0]
    _core.sum_by_group(group, np.array([1, 0, 1, 1, 0, 1], dtype=np.int8), sums)
    assert sums.tolist() == [4.5, 4.0, 11.0]
    counts = np.zeros(3)
    _core.count_by_group(group, counts)
    assert counts.tolist() == [2.0, 1.0, 3.0]
    with pytest.raises(IndexError, match="out of range"):
        _core.count_by_group(np.array([0, 3]), counts)
    with pytest.raises(IndexError, match="out of range"):
        _core.sum_by_group(np.array([-1]), np.ones(1), sums)
    with pytest.raises(ValueError, match="one value a face"):
        _core.sum_by_group(group, np.ones(2), sums)


TETRAHEDRON = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
OUTWARD = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def test_winding_numbers_of_a_closed_tetrahedron() -> None:
    samples = np.array(
        [[0.1, 0.1, 0.1], [2.0, 2.0, 2.0], [0.2, 0.3, 0.1], [1.0, 0.0, 0.0], [0.5, -1.0, 0.0]]
    )
    winding, clearance = np.empty(5), np.empty(5)
    _core.winding_numbers(TETRAHEDRON, 1.0, OUTWARD, samples, winding, clearance)
    assert winding[:3] == pytest.approx([1.0, 0.0, 1.0], abs=1e-12)
    assert winding[4] == pytest.approx(0.0, abs=1e-12)
    # The squared distance to the nearest face: a side 0.1 away; the slanted face's centre
    # (1/3, 1/3, 1/3), 5/3 away on each axis; a corner; the edge from (0, 0, 0) to (1, 0, 0).
    assert clearance == pytest.approx([0.01, 25 / 3, 0.01, 0.0, 1.0], abs=1e-15)
    _core.winding_numbers(TETRAHEDRON, 1.0, OUTWARD[:, ::-1].copy(), samples, winding, clearance)
    assert winding[:3] == pytest.approx([-1.0, 0.0, -1.0], abs=1e-12)
    # Scaled by the factor as the points are.
    _core.winding_numbers(TETRAHEDRON * 4, 0.25, OUTWARD, samples, winding, clearance)
    assert clearance[:3] == pytest.approx([0.01, 25 / 3, 0.01], abs=1e-15)
    # A triangle without area: its distance is its edges'.
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    _core.winding_numbers(
        flat, 1.0, np.array([[0, 1, 2]]), np.array([[1.5, 0, 2.0]]), winding[:1], clearance[:1]
    )
    assert clearance[0] == pytest.approx(4.0) and winding[0] == 0.0
    with pytest.raises(IndexError, match="does not exist"):
        _core.winding_numbers(TETRAHEDRON, 1.0, OUTWARD + 1, samples, winding, clearance)
    with pytest.raises(ValueError, match="one place a sample"):
        _core.winding_numbers(TETRAHEDRON, 1.0, OUTWARD, samples, np.empty(2), clearance)
    with pytest.raises(ValueError, match="one place a sample"):
        _core.winding_numbers(TETRAHEDRON, 1.0, OUTWARD, samples, winding, np.empty(6))


def test_contained_boxes() -> None:
    # 0 holds 1 and 2; 2 equals 1; 3 overlaps 0 only; 4 is a point on 0's corner.
    low = np.array([[0.0, 0, 0], [1, 1, 1], [1, 1, 1], [5, 0, 0], [0, 0, 0]])
    high = np.array([[6.0, 6, 6], [2, 2, 2], [2, 2, 2], [7, 1, 1], [0, 0, 0]])
    for axis in range(3):
        pairs, boxed = np.empty((10, 2), dtype=np.int64), np.zeros(5, dtype=bool)
        assert _core.contained_boxes(low, high, axis, 100, pairs, boxed) == 5
        found = sorted(map(tuple, pairs[:5].tolist()))
        assert found == [(1, 0), (1, 2), (2, 0), (2, 1), (4, 0)]
        assert boxed.tolist() == [False, True, True, False, True]
    # Counted past the room given, written up to it.
    pairs, boxed = np.full((2, 2), -1, dtype=np.int64), np.zeros(5, dtype=bool)
    assert _core.contained_boxes(low, high, 0, 100, pairs, boxed) >= 3
    assert (pairs >= 0).all() and boxed.tolist() == [False, True, True, False, True]
    # Past the budget of comparisons: -1.
    assert _core.contained_boxes(low, high, 0, 3, pairs, boxed) == -1
    with pytest.raises(ValueError, match="low <= high"):
        _core.contained_boxes(high, low, 0, 100, pairs, boxed)
    with pytest.raises(ValueError, match="low <= high"):
        _core.contained_boxes(low * np.nan, high, 0, 100, pairs, boxed)
    with pytest.raises(ValueError, match="axis"):
        _core.contained_boxes(low, high, 3, 100, pairs, boxed)
    with pytest.raises(ValueError, match="one row a box"):
        _core.contained_boxes(low, high[:4].copy(), 0, 100, pairs, boxed)
    with pytest.raises(ValueError, match="one row a box"):
        _core.contained_boxes(low, high, 0, 100, pairs, boxed[:4].copy())


def test_twinned_faces_refuse_points_out_of_range() -> None:
    faces = np.array([[0, 1, 2], [0, 2, 1], [0, 1, 3]])
    twinned = np.zeros(3, dtype=bool)
    _core.twinned_faces(faces, 4, twinned)
    assert twinned.tolist() == [True, True, False]
    with pytest.raises(IndexError, match="does not exist"):
        _core.twinned_faces(faces, 3, np.zeros(3, dtype=bool))
    with pytest.raises(ValueError, match="out of range"):
        _core.twinned_faces(faces, 2**31, np.zeros(3, dtype=bool))
    with pytest.raises(ValueError, match="one flag a face"):
        _core.twinned_faces(faces, 4, np.zeros(2, dtype=bool))


THREADS_SCRIPT = """
import hashlib
import numpy as np
from benchmarks.mesh_kernels import torus_mesh
from mesh_normal.mesh.orientation import _twinned, orient
from mesh_normal.mesh.topology import same_points

digest = hashlib.sha256()
vertices, faces = torus_mesh(100_000)
for part in (faces, faces[: len(faces) // 2]):  # closed (the volume), open (the twins, rays)
    r = orient(vertices, part)
    for array in (r.faces, r.flipped, r.components.volume, r.components.orientation,
                  r.topology.face_component, r.topology.boundary_edge_list):
        digest.update(np.ascontiguousarray(array).tobytes())
    digest.update(r.orientation.encode())
digest.update(_twinned(np.concatenate([faces, faces[::7, ::-1]])).tobytes())
digest.update(same_points(vertices, 1e-3).tobytes())
print(digest.hexdigest())
"""


def test_the_orientation_s_bits_do_not_depend_on_the_number_of_threads() -> None:
    digests = set()
    for threads in (1, 2, 3):
        done = subprocess.run(
            [sys.executable, "-c", THREADS_SCRIPT],
            cwd=ROOT,
            env={**os.environ, "MESH_NORMAL_THREADS": str(threads)},
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert done.returncode == 0, done.stderr[-2000:]
        digests.add(done.stdout.strip())
    assert len(digests) == 1 and len(digests.pop()) == 64
