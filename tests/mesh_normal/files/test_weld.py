from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
import pytest

from mesh_normal import _core
from mesh_normal.files import weld as weld_module
from mesh_normal.files.weld import weld


def reference(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Plain dictionary welding in order of first appearance."""
    ids: dict[tuple[float, ...], int] = {}
    index = [ids.setdefault(tuple(row), len(ids)) for row in (corners + 0.0).tolist()]
    return np.array(list(ids), dtype=np.float64).reshape(-1, 3), np.array(index)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_matches_a_dictionary(dtype: type) -> None:
    rng = np.random.default_rng(3)
    points = rng.standard_normal((300, 3)).astype(dtype)
    corners = points[rng.integers(0, 300, 2000)]
    corners[::7] *= -0.0  # some -0.0 rows, which must weld with +0.0
    corners[1::7] = 0.0
    vertices, index = weld(corners)
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
    assert vertices.dtype == np.float64 and index.dtype == np.intp


@pytest.mark.parametrize("rows", [500, 20_000])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_sort_way_matches_a_dictionary(
    monkeypatch: pytest.MonkeyPatch, rows: int, dtype: type
) -> None:
    monkeypatch.setattr(weld_module, "_SLOT_MASK", 0)  # every point in one slot, and no
    monkeypatch.setattr(weld_module, "_MOST_PROBES", 0)  # probe past it: the sort takes over
    corners = np.random.default_rng(5).integers(0, 4, (rows, 3)).astype(dtype)
    corners[::5] *= -1.0  # -0.0 among them
    calls = []
    sort_way = weld_module._weld_by_sort
    monkeypatch.setattr(
        weld_module, "_weld_by_sort", lambda *args: calls.append(1) or sort_way(*args)
    )
    vertices, index = weld(corners)
    assert calls == [1]
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
    assert vertices.dtype == np.float64 and index.dtype == np.intp


@pytest.mark.parametrize("rows", [500, 20_000])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize(("slot_bits", "probes"), [(2, 200), (0, 200), (0, 8)])
def test_points_that_share_slots_are_told_apart(
    monkeypatch: pytest.MonkeyPatch, rows: int, dtype: type, slot_bits: int, probes: int
) -> None:
    # 64 points into 4 slots or one: found by their bits along the run of slots; a run longer
    # than the probes allowed gives the table up for the sort, with the same answer.
    calls = []
    sort_way = weld_module._weld_by_sort
    monkeypatch.setattr(weld_module, "_SLOT_MASK", (1 << slot_bits) - 1)
    monkeypatch.setattr(weld_module, "_MOST_PROBES", probes)
    monkeypatch.setattr(
        weld_module, "_weld_by_sort", lambda *args: calls.append(1) or sort_way(*args)
    )
    corners = np.random.default_rng(6).integers(0, 4, (rows, 3)).astype(dtype)
    corners[::5] *= -1.0  # -0.0 among them
    vertices, index = weld(corners)
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
    assert calls == ([1] if probes < 64 else [])  # 64 points: 8 probes are too few


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_large_mesh_matches_a_dictionary(dtype: type) -> None:
    rng = np.random.default_rng(8)
    points = rng.standard_normal((30_000, 3)).astype(dtype)
    corners = points[rng.integers(0, len(points), 100_000)]
    vertices, index = weld(corners)
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
    np.testing.assert_array_equal(vertices[index], corners.astype(np.float64))


def test_empty() -> None:
    vertices, index = weld(np.zeros((0, 3)))
    assert vertices.shape == (0, 3) and index.shape == (0,)


@pytest.mark.parametrize("faces", [40, 20_000])  # one thread's share, and several
def test_corners_read_in_their_records_weld_as_rows(faces: int) -> None:
    # A binary STL's (f, 3, 3) corners, strided through 50-byte records: the same answer as
    # the same corners as a (3 f, 3) array, -0.0 and all.
    from mesh_normal.files.stl import RECORD

    rng = np.random.default_rng(faces)
    records = np.zeros(faces, RECORD)
    records["corners"] = rng.integers(-3, 4, (faces, 3, 3)).astype(np.float32) / 2
    records["corners"][::7, 1] *= -0.0
    view = np.frombuffer(records.tobytes(), RECORD)["corners"]
    assert not view.flags.c_contiguous
    vertices, index = weld(view)
    expected_vertices, expected_index = reference(view.reshape(-1, 3))
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
    assert not np.signbit(vertices).any() or (vertices[np.signbit(vertices)] != 0).all()


@pytest.mark.parametrize("rows", [900, 60_000])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_table_that_fills_grows_and_goes_on_where_it_stopped(
    monkeypatch: pytest.MonkeyPatch, rows: int, dtype: type
) -> None:
    # Mostly distinct points: the table (a quarter as many slots as rows) is half full within
    # the first rows and doubles several times, each time going on from the row it reached.
    # The table is not given up for the sort on the way.
    monkeypatch.setattr(weld_module, "_weld_by_sort", None)
    rng = np.random.default_rng(9)
    corners = rng.standard_normal((rows, 3)).astype(dtype)
    corners[rows // 2 :: 3] = corners[: rows - rows // 2 : 3][: len(corners[rows // 2 :: 3])]
    vertices, index = weld(corners)
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_non_finite_coordinates_weld_by_their_bits(dtype: type) -> None:
    nan = np.array(np.nan, dtype)
    other_nan = (nan.view(np.uint32 if dtype == np.float32 else np.uint64) | 1).view(dtype)
    corners = np.array([[nan, 0, 1], [np.inf, -np.inf, 0], [nan, -0.0, 1], [other_nan, 0, 1]])
    corners = corners.astype(dtype)
    vertices, index = weld(corners)
    assert index.tolist() == [0, 1, 0, 2]  # a NaN with other bits is another point
    np.testing.assert_array_equal(vertices[:2], corners[:2].astype(np.float64))


def test_other_layouts_and_types_weld_as_rows() -> None:
    rng = np.random.default_rng(4)
    corners = rng.integers(0, 3, (3000, 3)).astype(np.float64)
    expected_vertices, expected_index = reference(corners)
    for layout in (
        np.asfortranarray(corners),  # the coordinates of a corner apart: copied
        corners[::-1][::-1],
        corners.reshape(-1, 3, 3)[::-1][::-1],
        corners.astype(">f8"),  # big-endian
        corners.astype(np.float16),
        corners.astype(np.float32)[:, [0, 1, 2]],
    ):
        vertices, index = weld(layout)
        np.testing.assert_array_equal(vertices, expected_vertices)
        np.testing.assert_array_equal(index, expected_index)
    backwards = corners.reshape(-1, 3, 3)[::-1]  # a negative stride, read where it lies
    vertices, index = weld(backwards)
    expected_vertices, expected_index = reference(backwards.reshape(-1, 3))
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)


@pytest.fixture
def threads() -> Iterator[Callable[[int], None]]:
    """Set the compiled core's number of threads; the number before comes back after."""
    before = _core.threads()
    yield _core.set_threads
    _core.set_threads(before)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_weld_does_not_depend_on_the_number_of_threads(
    threads: Callable[[int], None], dtype: type
) -> None:
    rng = np.random.default_rng(11)
    corners = rng.integers(-20, 20, (300_000, 3)).astype(dtype) / 4
    grid = weld_module._corner_bytes(corners)
    answers: set[tuple[bytes, bytes]] = set()
    for count in (1, 2, 3):
        threads(count)
        for vertices, index in (weld(corners), weld_module._weld_by_sort(grid)):
            answers.add((vertices.tobytes(), index.tobytes()))
    assert len(answers) == 1


def test_the_compiled_weld_refuses_what_it_cannot_read() -> None:
    with pytest.raises(ValueError, match="3 coordinates of 4 or 8 bytes"):
        _core.weld_table(np.zeros((2, 3, 10), np.uint8), 0xFFFFFFFF, 64)
    with pytest.raises(ValueError, match="3 coordinates of 4 or 8 bytes"):
        _core.weld_sort(np.zeros((2, 3, 16), np.uint8))
    with pytest.raises(ValueError, match="contiguous"):
        _core.weld_table(np.zeros((2, 3, 24), np.uint8)[:, :, ::-1], 0xFFFFFFFF, 64)
    with pytest.raises(TypeError):  # the bytes, not the floats
        _core.weld_table(np.zeros((2, 3, 3), np.float32), 0xFFFFFFFF, 64)  # type: ignore[arg-type]
