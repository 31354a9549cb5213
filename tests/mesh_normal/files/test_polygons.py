"""Tests for mesh_normal.files.polygons: polygons triangulated inside themselves."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

import mesh_normal as mn
from mesh_normal import _core
from mesh_normal.files import LoadedMesh, MeshFileError, read_mesh
from mesh_normal.files.polygon_shapes import measure_polygons
from mesh_normal.files.polygons import fan, triangulate

Points = NDArray[np.float64]

# An L whose first corner is its reflex one's neighbour: the fan from it folds over.
L_SHAPE = [(2, 1), (1, 1), (1, 2), (0, 2), (0, 0), (2, 0)]
# A 10 x 8 wall with a 2 x 3 window, written as one polygon: around the outside, along a slit
# to the window, around the window the other way, and back along the slit.
WALL = [(0, 0), (10, 0), (10, 8), (0, 8), (0, 0), (3, 3), (3, 6), (5, 6), (5, 3), (3, 3)]
WALL_AREA = 10 * 8 - 2 * 3


def star(tips: int = 5, outer: float = 1.0, inner: float = 0.3) -> list[tuple[float, float]]:
    """A star starting at an inner corner (the fan from there folds over)."""
    angles = np.pi / tips * np.arange(2 * tips) + np.pi / tips
    radii = np.where(np.arange(2 * tips) % 2 == 0, inner, outer)
    return list(zip(radii * np.cos(angles), radii * np.sin(angles), strict=True))


def star_area(tips: int = 5, outer: float = 1.0, inner: float = 0.3) -> float:
    # 2 * tips triangles (centre, outer tip, inner corner), each with angle pi / tips at the centre
    return float(2 * tips * 0.5 * outer * inner * np.sin(np.pi / tips))


def placed(flat: list[tuple[float, float]], offset: float = 0.0) -> Points:
    """The 2-D corners turned into a vertical wall (the x-z plane, facing -y), moved away."""
    xy = np.asarray(flat, dtype=np.float64)
    return np.column_stack([xy[:, 0], np.zeros(len(xy)), xy[:, 1]]) + offset


def newell(points: Points) -> Points:
    centred = points - points.mean(axis=0)
    total: Points = np.cross(centred, np.roll(centred, -1, axis=0)).sum(axis=0)
    return total / np.linalg.norm(total)


def area(vertices: Points, triangles: NDArray[np.intp]) -> float:
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return float(np.linalg.norm(np.cross(b - a, c - a), axis=1).sum() / 2)


def assert_inside(
    vertices: Points, flat: NDArray[np.intp], counts: list[int], planar: bool = True
) -> None:
    """Every triangle faces its polygon's way, and (planar) the areas add up to the polygons'."""
    corners, source, _ = triangulate(np.array(counts), flat, vertices)
    starts = np.cumsum(counts) - counts
    for polygon, (start, count) in enumerate(zip(starts, counts, strict=True)):
        ring = vertices[flat[start : start + count]]
        mine = flat[corners[source == polygon]]
        a, b, c = (vertices[mine[:, i]] for i in range(3))
        along = np.cross(b - a, c - a) @ newell(ring)
        assert np.all(along > -1e-9 * np.ptp(ring, axis=0).max() ** 2), along
        if planar:
            assert along.sum() / 2 == pytest.approx(area(vertices, mine), rel=1e-12)


def obj_file(points: Points, ring: list[int]) -> bytes:
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in points]
    lines.append("f " + " ".join(str(i + 1) for i in ring))
    return ("\n".join(lines) + "\n").encode()


def ply_file(points: Points, ring: list[int]) -> bytes:
    header = (
        f"ply\nformat ascii 1.0\nelement vertex {len(points)}\n"
        "property double x\nproperty double y\nproperty double z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    )
    body = "".join(f"{float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in points)
    return (header + body + f"{len(ring)} " + " ".join(map(str, ring)) + "\n").encode()


def off_file(points: Points, ring: list[int]) -> bytes:
    body = "".join(f"{float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in points)
    return f"OFF\n{len(points)} 1 0\n{body}{len(ring)} {' '.join(map(str, ring))}\n".encode()


MakeFile = Callable[[Points, list[int]], bytes]
FILES = pytest.mark.parametrize(
    ("suffix", "make"), [("obj", obj_file), ("ply", ply_file), ("off", off_file)]
)


def welded(flat: list[tuple[float, float]]) -> tuple[list[tuple[float, float]], list[int]]:
    """The distinct corners and each corner's index among them (the wall reuses two)."""
    unique: list[tuple[float, float]] = []
    for point in flat:
        if point not in unique:
            unique.append(point)
    return unique, [unique.index(point) for point in flat]


def check_mesh(mesh: LoadedMesh, expected_area: float, tolerance: float = 1e-9) -> None:
    """The area is the polygon's and every vertex normal is the wall's, -y."""
    total = float(mn.face_areas(mesh.vertices, mesh.faces).sum())
    assert total == pytest.approx(expected_area, rel=tolerance)
    normals = mn.vertex_normals(mesh.vertices, mesh.faces).normals
    np.testing.assert_allclose(normals, [[0, -1, 0]] * len(normals), atol=tolerance)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e8])
@pytest.mark.parametrize(
    ("name", "ring", "expected"),
    [("L", L_SHAPE, 3.0), ("star", star(), star_area()), ("star9", star(9), star_area(9))],
)
@FILES
def test_concave_polygons_in_files(
    name: str,
    ring: list[tuple[float, float]],
    expected: float,
    offset: float,
    suffix: str,
    make: MakeFile,
) -> None:
    points, order = placed(ring, offset), list(range(len(ring)))
    assert area(points - offset, fan(np.array([len(ring)]))[0]) > expected * 1.01  # folds over
    mesh = read_mesh(make(points, order), f"{name}.{suffix}")
    assert mesh.source_faces == 1 and len(mesh.faces) == len(ring) - 2
    assert mesh.notes[0] == (
        "Triangulated 1 concave polygon by ear clipping on each one's own plane "
        "(a fan from the first corner would fold over)."
    )
    check_mesh(mesh, expected, 1e-9 if offset < 1e8 else 1e-7)  # 1e8 keeps 8 digits of 1
    assert_inside(points, np.array(order), [len(ring)])


@FILES
def test_a_wall_with_a_window_written_with_a_slit(suffix: str, make: MakeFile) -> None:
    unique, ring = welded(WALL)  # the corners reuse two vertices, as a CAD export does
    points = placed(unique, 1e4)
    assert area(points, np.array(ring)[fan(np.array([len(ring)]))[0]]) > WALL_AREA + 1  # fans
    mesh = read_mesh(make(points, ring), f"wall.{suffix}")
    assert len(mesh.faces) == len(ring) - 2
    check_mesh(mesh, WALL_AREA)
    assert_inside(points, np.array(ring), [len(ring)])


def test_convex_polygons_keep_todays_fans_bit_for_bit() -> None:
    generator = np.random.default_rng(9)
    counts, rings, start = [], [], 0
    for count in generator.integers(3, 9, size=300):
        angles = np.sort(generator.uniform(0, 2 * np.pi, size=count))
        flat = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(count)])
        turn, _ = np.linalg.qr(generator.normal(size=(3, 3)))
        rings.append(flat @ turn * generator.uniform(1e-3, 1e3) + generator.normal(size=3) * 1e5)
        counts.append(int(count))
        start += count
    vertices = np.concatenate(rings)
    flat = generator.permutation(len(vertices))  # any vertex order: corners are looked up
    corner_points = np.empty_like(vertices)
    corner_points[flat] = vertices
    corners, source, notes = triangulate(np.array(counts), flat, corner_points)
    expected_corners, expected_source = fan(np.array(counts))
    np.testing.assert_array_equal(corners, expected_corners)
    np.testing.assert_array_equal(source, expected_source)
    quads, larger = counts.count(4), sum(count > 4 for count in counts)
    assert notes == [
        f"Triangulated {quads} quads and {larger} larger polygons as fans from each one's "
        "first corner."
    ]


def test_triangles_only_skip_the_measures() -> None:
    corners, source, notes = triangulate(np.array([3, 3]), np.arange(6), np.zeros((6, 3)))
    np.testing.assert_array_equal(corners, [[0, 1, 2], [3, 4, 5]])
    np.testing.assert_array_equal(source, [0, 1])
    assert notes == []


def test_a_non_planar_quad_keeps_the_files_corners_and_is_counted() -> None:
    # A quad folded 0.5 out of its plane along a diagonal, and a flat one.
    vertices = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0], [2, 0, 0], [3, 0, 0], [3, 1, 0], [2, 1, 0]],
        dtype=np.float64,
    )
    corners, _, notes = triangulate(np.array([4, 4]), np.arange(8), vertices)
    np.testing.assert_array_equal(corners, fan(np.array([4, 4]))[0])
    # The largest height over the plane through the centroid, along the Newell normal, over
    # the bounding box diagonal (1.5).
    centred = vertices[:4] - vertices[:4].mean(axis=0)
    share = np.abs(centred @ newell(vertices[:4])).max() / np.linalg.norm([1, 1, 0.5])
    assert notes == [
        "Triangulated 2 quads as fans from each one's first corner.",
        f"1 polygon is not planar (largest deviation {share * 100:.3g} % of its size); its "
        "triangles follow the file's corners.",
    ]
    assert_inside(vertices, np.arange(8), [4, 4], planar=False)


def test_concave_quads_and_mixed_polygons_stay_in_file_order() -> None:
    # A dart (concave quad) seen from its reflex corner's neighbour, then a square, then the L.
    dart = [(0, 0), (2, 1), (0, 2), (1, 1)]
    rings = [placed(dart), placed([(5, 0), (6, 0), (6, 1), (5, 1)]), placed(L_SHAPE)]
    vertices = np.concatenate(rings)
    counts = [len(ring) for ring in rings]
    corners, source, notes = triangulate(np.array(counts), np.arange(len(vertices)), vertices)
    np.testing.assert_array_equal(source, [0, 0, 1, 1, 2, 2, 2, 2])
    np.testing.assert_array_equal(corners[2:4], [[4, 5, 6], [4, 6, 7]])  # the square: a fan
    assert set(corners[:2].ravel()) == {0, 1, 2, 3} and set(corners[4:].ravel()) == set(
        range(8, 14)
    )
    assert notes == [
        "Triangulated 1 quad as fans from each one's first corner.",
        "Triangulated 2 concave polygons by ear clipping on each one's own plane "
        "(a fan from the first corner would fold over).",
    ]
    assert_inside(vertices, np.arange(len(vertices)), counts)
    assert area(vertices, corners) == pytest.approx(1 + 1 + 3)


def test_a_repeated_corner_keeps_k_minus_2_triangles() -> None:
    # earcut drops a corner equal to the one before it; it comes back as a zero-area triangle.
    ring = [(0, 0), (1, 0), (1, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    points = placed(ring[4:] + ring[:4])
    corners, _, notes = triangulate(np.array([8]), np.arange(8), points)
    assert len(corners) == 6 and set(corners.ravel()) == set(range(8))
    assert area(points, corners) == pytest.approx(3.0)
    assert "ear clipping" in notes[0]
    assert_inside(points, np.arange(8), [8])


def test_polygons_without_area_or_valid_corners_keep_their_fans() -> None:
    bowtie = np.array([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    corners, _, notes = triangulate(np.array([4]), np.arange(4), bowtie)
    np.testing.assert_array_equal(corners, fan(np.array([4]))[0])
    assert notes == ["Triangulated 1 quad as fans from each one's first corner."]
    # A corner that is no vertex: the fan stands and the reader's check names the face.
    corners, _, _ = triangulate(np.array([4]), np.array([0, 1, 2, 7]), bowtie)
    np.testing.assert_array_equal(corners, fan(np.array([4]))[0])
    with pytest.raises(MeshFileError, match="refers to vertex 7"):
        read_mesh(b"OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 7\n", "bad.off")


def test_non_finite_corners_are_left_to_the_readers_check() -> None:
    with pytest.raises(MeshFileError, match="nan"):
        read_mesh(b"OFF\n4 1 0\n0 0 0\n1 0 0\nnan 1 0\n0 1 0\n4 0 1 2 3\n", "nan.off")


def test_a_polygon_that_crosses_itself_keeps_its_fan_and_says_so() -> None:
    # The fourth corner dips below the first edge: the boundary crosses itself twice.
    ring = placed([(0, 0), (4, 0), (4, 3), (1, -1), (0, 3)])
    corners, _, notes = triangulate(np.array([5]), np.arange(5), ring)
    np.testing.assert_array_equal(corners, fan(np.array([5]))[0])
    assert notes == ["1 polygon crosses itself; its fan from the first corner is kept."]


def shapes_reference(
    counts: NDArray[np.intp], corners: NDArray[np.intp], vertices: Points
) -> tuple[Points, NDArray[np.bool_], Points]:
    """The measures of each polygon of four or more corners, one polygon at a time in NumPy."""
    normals, folded = np.full((len(counts), 3), np.nan), np.zeros(len(counts), dtype=bool)
    deviation = np.zeros(len(counts))
    for polygon, start in enumerate(np.cumsum(counts) - counts):
        if counts[polygon] < 4:
            continue
        points = vertices[corners[start : start + counts[polygon]]]
        size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
        normals[polygon] = newell(points)
        deviation[polygon] = np.abs((points - points.mean(axis=0)) @ normals[polygon]).max() / size
        b, c = points[1:-1] - points[0], points[2:] - points[0]
        folded[polygon] = bool((np.cross(b, c) @ normals[polygon] < -1e-10 * size**2).any())
    return normals, folded, deviation


def test_the_measures_match_a_numpy_reference() -> None:
    rng = np.random.default_rng(21)
    vertices = rng.standard_normal((50, 3))
    counts = rng.integers(0, 9, 400)
    corners = rng.integers(0, 50, counts.sum())
    shapes = measure_polygons(counts, corners, vertices)
    assert shapes is not None
    normals, folded, deviation = shapes_reference(counts, corners, vertices)
    big = counts >= 4
    np.testing.assert_allclose(shapes.normals[big], normals[big], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(shapes.deviation, deviation, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(shapes.folded, folded)
    assert folded[big].any() and not folded[big].all()


def test_polygons_under_four_corners_measure_zero_whatever_new_memory_holds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The compiled pass skips them: their rows must be filled before it, not by chance.
    empty = np.empty

    def poisoned(*args: Any, **kwargs: Any) -> Any:
        found = empty(*args, **kwargs)
        found.view(np.uint8)[...] = 0xA5
        return found

    monkeypatch.setattr(np, "empty", poisoned)
    square = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    shapes = measure_polygons(np.array([3, 4, 2]), np.array([0, 1, 2, 0, 1, 2, 3, 2, 3]), square)
    assert shapes is not None
    np.testing.assert_array_equal(shapes.normals, [[0, 0, 0], [0, 0, 1], [0, 0, 0]])
    np.testing.assert_array_equal(shapes.deviation, [0, 0, 0])
    np.testing.assert_array_equal(shapes.folded, [False, False, False])


def test_the_measures_do_not_depend_on_the_number_of_threads() -> None:
    rng = np.random.default_rng(22)
    vertices = rng.standard_normal((5000, 3))
    counts = rng.integers(3, 9, 60_000)
    corners = rng.integers(0, 5000, counts.sum())
    before, answers = _core.threads(), set()
    try:
        for threads in (1, 2, 3):
            _core.set_threads(threads)
            shapes = measure_polygons(counts, corners, vertices)
            assert shapes is not None
            answers.add(b"".join(np.asarray(a).tobytes() for a in vars(shapes).values()))
    finally:
        _core.set_threads(before)
    assert len(answers) == 1


def test_corners_or_counts_that_are_not_the_files_measure_nothing() -> None:
    square = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert measure_polygons(np.array([4]), np.array([0, 1, 2, 3]), square) is not None
    for counts, corners in (
        ([4], [0, 1, 2, 4]),  # past the vertices
        ([4], [0, -1, 2, 3]),
        ([4], [0, 1, 2]),  # fewer corners than the counts say
        ([-4, 8], [0, 1, 2, 3]),  # a negative count: the next polygon starts before the first
    ):
        assert measure_polygons(np.array(counts), np.array(corners), square) is None
    # Starts past the corners, or arrays of other lengths, given to the compiled pass itself.
    counts, corners = np.array([4]), np.array([0, 1, 2, 3])
    normals, deviation, folded = np.empty((1, 3)), np.zeros(1), np.zeros(1, dtype=bool)
    for starts in ([1], [-1], [2**62]):
        assert not _core.polygon_shapes(
            counts, np.array(starts), corners, square, normals, deviation, folded
        )
    with pytest.raises(ValueError, match="one row per polygon"):
        _core.polygon_shapes(counts, np.array([0, 4]), corners, square, normals, deviation, folded)
    with pytest.raises(TypeError):  # int32 corners are not copied behind the caller's back
        _core.polygon_shapes(
            counts,
            np.array([0]),
            corners.astype(np.int32),  # type: ignore[arg-type]
            square,
            normals,
            deviation,
            folded,
        )
