"""Tests for mesh_normal.mesh.checks: bad input is refused clearly, good input converted."""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np
import pytest

from mesh_normal.mesh import checks
from mesh_normal.mesh.checks import check_mesh, checked_mesh
from mesh_normal.mesh.corners import corner_normals
from mesh_normal.mesh.faces import face_geometry, face_normals
from mesh_normal.mesh.orientation import orient, signed_volume
from mesh_normal.mesh.topology import mesh_topology
from mesh_normal.mesh.vertices import WEIGHTINGS, vertex_normals
from tests.meshes import TETRA_FACES, TETRA_VERTICES


@pytest.mark.parametrize(
    ("vertices", "faces", "words"),
    [
        (np.zeros((3, 2)), [[0, 1, 2]], "vertices must have shape (n, 3), not (3, 2)"),
        (np.zeros(9), [[0, 1, 2]], "vertices must have shape (n, 3), not (9,)"),
        (np.zeros((3, 3), dtype=bool), [[0, 1, 2]], "vertices must hold real numbers, not bool"),
        (np.zeros((3, 3), dtype=complex), [[0, 1, 2]], "real numbers, not complex128"),
        ([["a", "b", "c"]] * 3, [[0, 1, 2]], "vertices must hold real numbers"),
        (
            [[0, 0, 0], [1, 0, np.nan], [0, 1, 0]],
            [[0, 1, 2]],
            "vertices[1] has a coordinate that is not a finite number",
        ),
        ([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]], [[0, 1, 2]], "vertices[2]"),
        (TETRA_VERTICES, [[0.0, 1.0, 2.0]], "faces must hold integer vertex indices, not float64"),
        (TETRA_VERTICES, [[0, 1, 2, 3]], "faces must have shape (m, 3), not (1, 4)"),
        (TETRA_VERTICES, [0, 1, 2], "faces must have shape (m, 3), not (3,)"),
        (TETRA_VERTICES, [[0, 1, 2], [3, -1, 2]], "faces[1] has a negative vertex index, -1"),
        (
            TETRA_VERTICES,
            [[0, 1, 2], [0, 1, 3], [0, 4, 1]],
            "faces[2] refers to vertex 4, but there are only 4 vertices (indices 0 to 3)",
        ),
        (np.empty((0, 3)), [[0, 1, 2]], "faces[0] refers to vertex 0, but there are no vertices"),
        (
            TETRA_VERTICES,
            np.array([[0, 1, 2**40]], dtype=np.uint64),
            "refers to vertex 1099511627776",
        ),
    ],
)
def test_bad_input_is_refused_with_a_clear_message(
    vertices: object, faces: object, words: str
) -> None:
    for call in (face_normals, vertex_normals, corner_normals, check_mesh):
        with pytest.raises(ValueError, match=re.escape(words)) as error:
            call(vertices, faces)  # type: ignore[operator]
        assert str(error.value).endswith(".")


def test_unknown_weighting_and_bad_crease_angles_are_refused() -> None:
    with pytest.raises(ValueError, match="weighting must be one of uniform, area, angle, max"):
        vertex_normals(TETRA_VERTICES, TETRA_FACES, "mean")  # type: ignore[arg-type]
    for crease in (-1.0, 180.5, math.nan, math.inf):
        with pytest.raises(ValueError, match="between 0 and 180 degrees"):
            corner_normals(TETRA_VERTICES, TETRA_FACES, crease)
    for crease in (True, "30", None):
        with pytest.raises(ValueError, match="crease_angle must be a number of degrees"):
            corner_normals(TETRA_VERTICES, TETRA_FACES, crease)  # type: ignore[arg-type]


def test_inputs_are_converted_and_not_modified() -> None:
    vertices = TETRA_VERTICES.astype(np.float32)
    faces = TETRA_FACES.astype(np.uint16)
    before = vertices.copy(), faces.copy()
    points, indices = check_mesh(vertices, faces)
    assert points.dtype == np.float64 and indices.dtype == np.intp
    assert np.allclose(
        face_normals(vertices, faces).normals, face_normals(TETRA_VERTICES, TETRA_FACES).normals
    )
    assert vertex_normals(vertices.tolist(), faces.tolist()).normals.shape == (4, 3)
    assert np.array_equal(vertices, before[0]) and np.array_equal(faces, before[1])
    fortran = np.asfortranarray(TETRA_VERTICES)
    assert np.array_equal(
        face_normals(fortran, np.asfortranarray(TETRA_FACES)).normals,
        face_normals(TETRA_VERTICES, TETRA_FACES).normals,
    )


def test_an_empty_mesh_gives_empty_results() -> None:
    r = face_normals(np.empty((0, 3)), [])
    assert r.normals.shape == (0, 3) and r.areas.shape == r.degenerate.shape == (0,)
    smooth = vertex_normals(TETRA_VERTICES, np.empty((0, 3), dtype=int))
    assert smooth.missing.all() and not smooth.normals.any()
    corners = corner_normals(TETRA_VERTICES, np.empty((0, 3), dtype=int))
    assert corners.normals.shape == (0, 3, 3) and corners.missing.shape == (0, 3)


# --- one check and one cross product per mesh -------------------------------------------------


def every_result(source: object, faces: object = None) -> list[np.ndarray]:
    """Every array the core computes, from raw arrays (with ``faces``) or a checked mesh."""
    extra = () if faces is None else (faces,)
    fn = face_normals(source, *extra)  # type: ignore[arg-type]
    out = [fn.normals, fn.areas, fn.degenerate]
    for weighting in WEIGHTINGS:
        vn = vertex_normals(source, *extra, weighting=weighting)  # type: ignore[arg-type]
        cn = corner_normals(source, *extra, crease_angle=20.0, weighting=weighting)  # type: ignore[arg-type]
        out += [vn.normals, vn.missing, cn.normals, cn.missing]
    o = orient(source, *extra)  # type: ignore[arg-type]
    volume = signed_volume(source, *extra)  # type: ignore[arg-type]
    out += [o.faces, o.flipped, np.array([volume, math.nan if o.volume is None else o.volume])]
    out += [o.components.volume, o.topology.face_component]
    return out


def sliver_soup() -> tuple[np.ndarray, np.ndarray]:
    """Random faces with needles, slivers and repeated indices: every path of face_cross."""
    rng = np.random.default_rng(3)
    vertices = rng.normal(size=(400, 3))
    vertices[10] = vertices[11] + 1e-13 * rng.normal(size=3)  # a needle
    vertices[12] = (vertices[13] + vertices[14]) / 2 + 1e-9  # a sliver
    faces = rng.integers(0, 400, size=(900, 3))
    faces[:4] = [[10, 11, 20], [12, 13, 14], [1, 1, 2], [11, 10, 30]]
    return vertices, faces


@pytest.mark.parametrize("scale", [1.0, 2.0**-1040, 1e150])
def test_a_checked_mesh_and_its_geometry_give_the_same_bits_as_raw_arrays(scale: float) -> None:
    vertices, faces = sliver_soup()
    vertices = vertices * scale
    raw = every_result(vertices, faces)
    mesh = checked_mesh(vertices, faces)
    geometry = face_geometry(mesh)
    # The sliver is retaken at its largest corner, the repeated index is degenerate.
    assert geometry.recomputed[[1, 2]].all() and geometry.degenerate[2]
    assert not geometry.recomputed.all()
    for given_form in (every_result(mesh), every_result(geometry)):
        for got, expected in zip(given_form, raw, strict=True):
            assert got.dtype == expected.dtype and got.shape == expected.shape
            assert got.tobytes() == expected.tobytes()
    # A mesh's topology is by position (at 2**-1040 the needle's ends become one point), as
    # orient() finds it from the raw arrays; raw faces alone can only go by index.
    assert repr(mesh_topology(mesh)) == repr(orient(vertices, faces).topology)


def test_a_checked_mesh_is_checked_once_and_its_cross_products_computed_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from mesh_normal import _core

    vertices, faces = sliver_soup()
    counts = {"checks": 0, "crosses": 0}
    real_check = checks._as_vertices

    def counted_check(array: object) -> np.ndarray:
        counts["checks"] += 1
        return real_check(array)  # type: ignore[arg-type]

    def counting(real: Callable[..., bool], crosses: Callable[..., bool]) -> Callable[..., bool]:
        def counted(*arguments: object) -> bool:
            counts["crosses"] += crosses(*arguments)
            return real(*arguments)

        return counted

    # The one-pass kernels take the cross products too: of faces from a mesh, and the vertex
    # sums' terms when fused (their eighth argument).
    monkeypatch.setattr(_core, "face_normals", counting(_core.face_normals, lambda *_: True))
    monkeypatch.setattr(_core, "vertex_sums", counting(_core.vertex_sums, lambda *a: bool(a[7])))
    monkeypatch.setattr(_core, "face_geometry", counting(_core.face_geometry, lambda *_: True))
    monkeypatch.setattr(checks, "_as_vertices", counted_check)
    geometry = face_geometry(vertices, faces)
    every_result(geometry)
    assert counts == {"checks": 1, "crosses": 1}
    every_result(vertices, faces)  # raw arrays: checked (and crossed) by every call
    assert counts["checks"] > 10 and counts["crosses"] > 10


def test_a_checked_mesh_is_not_given_faces_twice() -> None:
    mesh = checked_mesh(TETRA_VERTICES, TETRA_FACES)
    with pytest.raises(TypeError, match="pass it without faces"):
        face_normals(mesh, TETRA_FACES)
    with pytest.raises(TypeError, match="pass it without faces"):
        vertex_normals(face_geometry(mesh), TETRA_FACES)
    with pytest.raises(TypeError, match="faces are required"):
        orient(TETRA_VERTICES)
    with pytest.raises(TypeError, match="pass it alone"):
        mesh_topology(mesh, 4)
    with pytest.raises(TypeError, match="vertex_count is required"):
        mesh_topology(TETRA_FACES)


def test_a_checked_mesh_holds_converted_arrays_and_their_scale() -> None:
    mesh = checked_mesh(TETRA_VERTICES.astype(np.float32) * 8, TETRA_FACES.astype(np.uint8))
    assert mesh.vertices.dtype == np.float64 and mesh.faces.dtype == np.intp
    assert mesh.scale == 4 and mesh.factor == 2.0**-4 and mesh.points is mesh.vertices
    tiny = checked_mesh(TETRA_VERTICES * 2.0**-1040, TETRA_FACES)
    assert tiny.factor == 1.0 and tiny.scale == -1039
    assert np.array_equal(tiny.points, TETRA_VERTICES / 2)


#: Enough faces (or coordinates) for each of three threads to take a part of the range pass.
MANY = 3 * 2**16 + 5


@pytest.mark.parametrize("planted", [0, 1, 16383, 65536, 131072, MANY - 1])
def test_the_index_range_on_every_core_finds_any_bad_index(planted: int) -> None:
    # Faces over every thread's part of the pass (the last one short): a negative or too
    # large index anywhere, even the last row, is found, as NumPy finds it.
    rng = np.random.default_rng(planted)
    faces = rng.integers(0, 1000, (MANY, 3))
    assert checks._index_range(faces) == (0, int(faces.max()))
    for bad, words in ((-7, "negative vertex index, -7"), (5000, "refers to vertex 5000")):
        broken = faces.copy()
        broken[planted, 2] = bad
        assert checks._index_range(broken) == (min(0, bad), max(int(faces.max()), bad))
        with pytest.raises(ValueError, match=re.escape(f"faces[{planted}]")):
            checked_mesh(rng.random((1000, 3)), broken)
        with pytest.raises(ValueError, match=words):
            checked_mesh(rng.random((1000, 3)), broken)
    strided = np.asfortranarray(faces)  # NumPy's min and max (no 0 among them)
    assert checks._index_range(strided) == (int(faces.min()), int(faces.max()))


@pytest.mark.parametrize("planted", [0, 1, 32767, 65536, 131072, 3 * MANY - 1])
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_the_coordinate_range_on_every_core_finds_any_bad_coordinate(
    planted: int, bad: float
) -> None:
    # Coordinates over every thread's part of the pass (the last one short): a NaN or an
    # infinity anywhere, even the last coordinate, is found, and the check names its row.
    rng = np.random.default_rng(planted)
    points = rng.normal(size=(MANY, 3)) + 0.25
    assert checks._coordinate_range(points) == (min(0.0, points.min()), max(0.0, points.max()))
    broken = points.copy()
    broken.reshape(-1)[planted] = bad
    assert all(map(math.isnan, checks._coordinate_range(broken)))
    with pytest.raises(ValueError, match=re.escape(f"vertices[{planted // 3}] has a coordinate")):
        checked_mesh(broken, [[0, 1, 2]])


def test_the_coordinate_range_includes_zero_and_matches_numpy() -> None:
    positive = np.random.default_rng(5).random((MANY, 3)) + 3.0
    mesh = checked_mesh(positive, [[0, 1, 2]])
    assert mesh.scale == math.frexp(float(positive.max()))[1]
    assert checks._coordinate_range(positive) == (0.0, float(positive.max()))
    assert checks._coordinate_range(-positive) == (float(-positive.max()), 0.0)
    assert checks._coordinate_range(positive[:10]) == (0.0, float(positive[:10].max()))
    assert checks._coordinate_range(positive[::2]) == (0.0, float(positive[::2].max()))
    signed = np.zeros((MANY, 3))
    signed[7, 1] = -0.0  # never below the 0 the range starts from
    low, high = checks._coordinate_range(signed)
    assert (low, high) == (0.0, 0.0) and not math.copysign(1.0, low) < 0


@pytest.mark.parametrize("planted", [0, 511, 512, 16384, 40000, 49156])
def test_normals_find_a_bad_index_as_their_kernel_reads_it(planted: int) -> None:
    # Raw intp faces skip the range pass: the one-pass kernel checks each index it reads, in
    # any thread's part, and the check then names the face, as it would have up front.
    rng = np.random.default_rng(planted)
    vertices = rng.random((1000, 3))
    faces = rng.integers(0, 1000, (3 * 16384 + 5, 3))
    assert faces.dtype == np.intp
    expected = face_normals(checked_mesh(vertices, faces))
    assert np.array_equal(face_normals(vertices, faces).normals, expected.normals)
    for bad, words in ((-7, "negative vertex index, -7"), (1000, "refers to vertex 1000")):
        broken = faces.copy()
        broken[planted, planted % 3] = bad
        for call in (face_normals, vertex_normals):
            with pytest.raises(ValueError, match=re.escape(f"faces[{planted}] ") + ".*" + words):
                call(vertices, broken)  # type: ignore[operator]
    assert np.array_equal(
        vertex_normals(vertices, faces, "area").normals,
        vertex_normals(checked_mesh(vertices, faces), weighting="area").normals,
    )


def test_the_scale_from_the_check_is_the_scale_of_the_vertices() -> None:
    rng = np.random.default_rng(1)
    for size in (1e-300, 3e-5, 1.0, 7e200):
        vertices = size * rng.standard_normal((50, 3))
        mesh = checked_mesh(vertices, [[0, 1, 2]])
        assert (mesh.factor, mesh.scale) == checks.scaling(vertices)[1:]
