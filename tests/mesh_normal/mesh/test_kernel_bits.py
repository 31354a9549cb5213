"""The one-pass kernels give the bits of the step-by-step path, on any number of threads.

``face_normals`` and ``vertex_normals`` of raw arrays (or a checked mesh) take the cross
products as they go; given a :class:`FaceGeometry` they read its arrays. Both must agree bit
for bit with each other and with a straightforward NumPy reference of the documented
arithmetic, and a run on one thread, two or three must give the same bytes.
"""

from __future__ import annotations

import hashlib
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from mesh_normal import face_normals, vertex_normals
from mesh_normal.mesh.checks import checked_mesh
from mesh_normal.mesh.faces import face_geometry
from mesh_normal.mesh.vertices import WEIGHTINGS
from mesh_normal.tolerances import MESH_CANCELLED_SUM
from tests.paths import ROOT


def soup(seed: int = 0, count: int = 3000, faces: int = 2577) -> tuple:
    """Random faces with repeated indices, coincident, collinear and nearly coincident points."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(count, 3))
    points[100:200] = points[100]
    points[200:300] = np.linspace(0.0, 1.0, 100)[:, None] * np.array([1.0, 2.0, 3.0])
    points[300:400] = points[400:500] + 1e-12 * rng.normal(size=(100, 3))
    indices = rng.integers(0, count, size=(faces, 3))
    indices[: faces // 10, 1] = indices[: faces // 10, 0]
    indices[faces // 10 : faces // 5] = rng.integers(100, 500, size=(faces // 5 - faces // 10, 3))
    return points, indices


#: Scales whose area exponent 2 * scale - 1 falls inside the normal range (multiplied), at
#: its edge (areas become subnormal) and outside it (huge, tiny and subnormal coordinates).
SCALES = [1.0, 2.0**-511, 2.0**-520, 2.0**511, 1e150, 1e-160, 1e-310, 1e300]


@pytest.mark.parametrize("scale", SCALES)
def test_face_normals_of_a_mesh_are_the_geometry_s_bits(scale: float) -> None:
    points, indices = soup()
    vertices = points * scale
    geometry = face_geometry(vertices, indices)
    reference_normals = (
        np.where(
            geometry.degenerate[:, None],
            0.0,
            geometry.crosses / np.where(geometry.degenerate, 1.0, geometry.lengths)[:, None],
        )
        + 0.0
    )
    with np.errstate(over="ignore"):
        reference_areas = np.ldexp(geometry.lengths, 2 * geometry.mesh.scale - 1)
    for result in (face_normals(vertices, indices), face_normals(checked_mesh(vertices, indices))):
        assert result.normals.tobytes() == reference_normals.tobytes()
        assert result.areas.tobytes() == reference_areas.tobytes()
        assert result.degenerate.tobytes() == geometry.degenerate.tobytes()
    via_geometry = face_normals(geometry)
    assert via_geometry.areas.tobytes() == reference_areas.tobytes()
    assert via_geometry.normals.tobytes() == reference_normals.tobytes()


def test_areas_at_the_edge_of_the_normal_range_are_the_subnormals_ldexp_gives() -> None:
    # Coordinates near 2**-511: the area exponent is -1023 + 1, the areas of small faces are
    # subnormal, and multiplying by 2**exponent must round them as ldexp does.
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [3, 1e-9, 0], [1e-7, 2e-7, 5e-8]])
    vertices = vertices * 2.0**-512
    indices = np.array([[0, 1, 2], [0, 3, 4], [1, 4, 2], [0, 4, 3]])
    geometry = face_geometry(vertices, indices)
    assert -1022 <= 2 * geometry.mesh.scale - 1 <= 1023
    areas = face_normals(vertices, indices).areas
    assert (areas[1:] < 2.0**-1022).any() and (areas > 0).all()
    assert areas.tobytes() == np.ldexp(geometry.lengths, 2 * geometry.mesh.scale - 1).tobytes()


def dot(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """p . q over the last axis, summed in the kernels' order: x, then y, then z."""
    return p[..., 0] * q[..., 0] + p[..., 1] * q[..., 1] + p[..., 2] * q[..., 2]


_atan2 = np.frompyfunc(math.atan2, 2, 1)


def _libm_atan2(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    return _atan2(y, x).astype(np.float64)


def reference_vertex_normals(vertices: np.ndarray, indices: np.ndarray, weighting: str) -> tuple:
    """The documented sums in NumPy: summed in face order (``np.add.at`` is unbuffered and in
    order), then normalised."""
    geometry = face_geometry(vertices, indices)
    usable = ~geometry.degenerate
    lengths = np.where(usable, geometry.lengths, 1.0)
    units = geometry.crosses / lengths[:, None]
    corners = geometry.mesh.points[indices] * geometry.mesh.factor
    edges = np.roll(corners, -1, axis=1) - corners  # edge k runs from corner k to k + 1
    incoming, outgoing = np.roll(edges, 1, axis=1), edges
    if weighting == "uniform":
        weights = np.ones((len(indices), 3))
    elif weighting == "area":
        weights = np.repeat(lengths[:, None], 3, axis=1)
    elif weighting == "angle":
        # The C library's atan2, as the kernels call it: NumPy's own arctan2 is a SIMD one on
        # AVX-512 machines, within an ulp or so but not the same bits.
        weights = _libm_atan2(
            np.broadcast_to(lengths[:, None], incoming.shape[:2]), -dot(incoming, outgoing)
        )
    else:
        squares = dot(edges, edges)
        with np.errstate(divide="ignore", invalid="ignore"):  # degenerate rows are left out
            weights = lengths[:, None] / (np.roll(squares, 1, axis=1) * squares)
        weights[~usable] = 0.0
    if weighting == "area":
        terms = np.repeat(geometry.crosses[:, None, :], 3, axis=1)
    else:
        terms = weights[:, :, None] * units[:, None, :]
    total = np.zeros((len(vertices), 4))
    np.add.at(total[:, :3], indices[usable].ravel(), terms[usable].reshape(-1, 3))
    np.add.at(total[:, 3], indices[usable].ravel(), weights[usable].ravel())
    square = dot(total[:, :3], total[:, :3])
    cancel = MESH_CANCELLED_SUM * total[:, 3]
    missing = square <= cancel * cancel
    length = np.where(missing, np.inf, np.sqrt(square))
    return total[:, :3] / length[:, None] + 0.0, missing


@pytest.mark.parametrize("weighting", WEIGHTINGS)
@pytest.mark.parametrize("scale", [1.0, 1e150, 1e-160])
def test_vertex_normals_match_the_reference_sums_bit_for_bit(weighting: str, scale: float) -> None:
    points, indices = soup(seed=1)
    vertices = points * scale
    normals, missing = reference_vertex_normals(vertices, indices, weighting)
    assert missing.any() and not missing.all()
    for source in (
        (vertices, indices),
        (checked_mesh(vertices, indices), None),
        (face_geometry(vertices, indices), None),
    ):
        result = vertex_normals(*source, weighting=weighting)  # type: ignore[arg-type]
        assert result.missing.tobytes() == missing.tobytes()
        assert result.normals.tobytes() == normals.tobytes()


SCRIPT = """
import hashlib
import numpy as np
from mesh_normal import corner_normals, face_normals, vertex_normals
from mesh_normal.mesh.corners import corner_weights
from mesh_normal.mesh.faces import face_geometry
from mesh_normal.mesh.report.stored_normals import unit_rows
from tests.mesh_normal.mesh.test_kernel_bits import soup

digest = hashlib.sha256()
for seed, count, faces in ((0, 3000, 40_000), (1, 600, 1500), (2, 500, 1)):
    vertices, indices = soup(seed, count, faces)
    for result in (face_normals(vertices, indices), face_normals(face_geometry(vertices, indices))):
        for array in (result.normals, result.areas, result.degenerate):
            digest.update(array.tobytes())
    geometry = face_geometry(vertices, indices)
    for array in (geometry.crosses, geometry.lengths, geometry.degenerate, geometry.recomputed):
        digest.update(array.tobytes())
    for weighting in ("uniform", "area", "angle", "max"):
        for source in ((vertices, indices), (geometry, None)):
            result = vertex_normals(*source, weighting=weighting)
            digest.update(result.normals.tobytes())
            digest.update(result.missing.tobytes())
        digest.update(corner_weights(geometry, weighting).tobytes())
    corners = corner_normals(geometry, crease_angle=45.0)
    digest.update(corners.normals.tobytes())
    digest.update(corners.missing.tobytes())
    for array in unit_rows(geometry.crosses * 3.0):
        digest.update(array.tobytes())
print(digest.hexdigest())
"""


def digest_with(threads: int) -> str:
    environment = {**os.environ, "MESH_NORMAL_THREADS": str(threads)}
    result = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    return result.stdout.strip()


def test_the_bits_do_not_depend_on_the_number_of_threads() -> None:
    digests = {threads: digest_with(threads) for threads in (1, 2, 3)}
    assert len(set(digests.values())) == 1, digests
    assert len(next(iter(digests.values()))) == 64
    assert hashlib.sha256(b"").hexdigest() not in digests.values()
