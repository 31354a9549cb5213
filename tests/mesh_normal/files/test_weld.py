from __future__ import annotations

import numpy as np
import pytest

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


@pytest.mark.parametrize("rows", [500, 20_000])  # the Python source, and compiled
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize(
    ("hash_bits", "most"),
    [(2, 1024), (2, 8), (0, 8)],  # 4 groups split in the walk; too many points: the NumPy way
)
def test_hash_collisions_are_split_exactly(
    monkeypatch: pytest.MonkeyPatch, rows: int, dtype: type, hash_bits: int, most: int
) -> None:
    index_bits = (rows - 1).bit_length()
    monkeypatch.setattr(weld_module, "_MOST_PROBES", -1)  # the table gives way to the sort
    monkeypatch.setattr(weld_module, "_HASH_MASK", (1 << index_bits + hash_bits) - 1)
    monkeypatch.setattr(weld_module, "_MOST_DISTINCT", most)
    corners = np.random.default_rng(5).integers(0, 4, (rows, 3)).astype(dtype)
    corners[::5] *= -1.0  # -0.0 among them
    vertices, index = weld(corners)
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)


@pytest.mark.parametrize("rows", [500, 20_000])  # the Python source, and compiled
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize(("slot_bits", "probes"), [(2, 200), (0, 200), (0, 8)])
def test_points_that_share_slots_are_told_apart(
    monkeypatch: pytest.MonkeyPatch, rows: int, dtype: type, slot_bits: int, probes: int
) -> None:
    # 64 points into 4 slots or one: found by their bits along the run of slots; a run longer
    # than the probes allowed gives the table up for the sort, with the same answer.
    calls = []
    sort_way = weld_module._hash_keys
    monkeypatch.setattr(weld_module, "_SLOT_MASK", (1 << slot_bits) - 1)
    monkeypatch.setattr(weld_module, "_MOST_PROBES", probes)
    monkeypatch.setattr(weld_module, "_hash_keys", lambda *args: calls.append(1) or sort_way(*args))
    corners = np.random.default_rng(6).integers(0, 4, (rows, 3)).astype(dtype)
    corners[::5] *= -1.0  # -0.0 among them
    vertices, index = weld(corners)
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
    assert calls == ([1] if probes < 64 else [])  # 64 points: 8 probes are too few


def test_the_numpy_way_splits_its_own_collisions(monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    numpy_way = weld_module._weld_sorted
    monkeypatch.setattr(weld_module, "_MOST_PROBES", -1)  # the table gives way to the sort
    monkeypatch.setattr(weld_module, "_HASH_MASK", 0)  # one group of every point: too many
    monkeypatch.setattr(
        weld_module, "_weld_sorted", lambda *args: calls.append(1) or numpy_way(*args)
    )
    corners = np.random.default_rng(5).integers(0, 4, (500, 3)).astype(np.float64)
    vertices, index = weld(corners)
    assert calls == [1]
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)


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


@pytest.mark.parametrize("faces", [40, 20_000])  # the Python source, and compiled
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


@pytest.mark.parametrize("rows", [900, 60_000])  # the Python source, and compiled
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_table_that_fills_grows_and_goes_on_where_it_stopped(rows: int, dtype: type) -> None:
    # Mostly distinct points: the table (a quarter as many slots as rows) is half full within
    # the first rows and doubles several times, each time going on from the row it reached.
    rng = np.random.default_rng(9)
    corners = rng.standard_normal((rows, 3)).astype(dtype)
    corners[rows // 2 :: 3] = corners[: rows - rows // 2 : 3][: len(corners[rows // 2 :: 3])]
    calls = []
    real = weld_module._regrown

    def counted(*arguments: object) -> bool:
        calls.append(1)
        return bool(real(*arguments))

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(weld_module, "_regrown", counted)
        vertices, index = weld(corners)
    assert len(calls) >= 2
    expected_vertices, expected_index = reference(corners)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(index, expected_index)
