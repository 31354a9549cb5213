from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from mesh_normal.points.io.read import read_points
from mesh_normal.points.io.write import POINT_WRITE_FORMATS, write_points

FINITE = st.floats(allow_nan=False, allow_infinity=False)


def arrays(rows: int) -> st.SearchStrategy[np.ndarray]:
    return hnp.arrays(np.float64, (rows, 3), elements=FINITE)


@given(
    st.integers(1, 20).flatmap(lambda n: st.tuples(arrays(n), st.none() | arrays(n))),
    st.sampled_from(sorted(POINT_WRITE_FORMATS)),
)
def test_round_trip_is_exact(arrays_pair: tuple[np.ndarray, np.ndarray | None], fmt: str) -> None:
    points, normals = arrays_pair
    cloud = read_points(write_points(points, normals, fmt), f"cloud.{fmt}")
    # Bit for bit, -0.0 included: compare the bytes, not the values.
    assert cloud.points.tobytes() == points.tobytes()
    if normals is None:
        assert cloud.normals is None
    else:
        assert cloud.normals is not None and cloud.normals.tobytes() == normals.tobytes()
    assert cloud.notes == ()
    assert cloud.format == ("ply" if fmt == "ply" else "xyz")


@pytest.mark.parametrize("fmt", sorted(POINT_WRITE_FORMATS))
def test_whole_number_normals_stay_normals(fmt: str) -> None:
    normals = np.array([[2.0, 0.0, 255.0]])
    cloud = read_points(write_points(np.zeros((1, 3)), normals, fmt), f"cloud.{fmt}")
    assert cloud.colors is None
    np.testing.assert_array_equal(cloud.normals, normals)


def test_the_files_as_text() -> None:
    points = np.array([[500000.123, 4e6, -0.0], [0.1, 1e-300, 2.5]])
    normals = np.array([[0.0, 0.0, 1.0], [0.6, 0.8, 0.0]])
    assert write_points(points, normals, "xyz") == (
        b"# x y z nx ny nz\n500000.123 4000000.0 -0.0 0.0 0.0 1.0\n0.1 1e-300 2.5 0.6 0.8 0.0\n"
    )
    assert (
        write_points(points, None, "csv") == b"x,y,z\n500000.123,4000000.0,-0.0\n0.1,1e-300,2.5\n"
    )
    ply = write_points(points, normals, "ply")
    header, body = ply.split(b"end_header\n")
    assert b"element vertex 2\n" in header and b"property double nz\n" in header
    assert b"element face" not in header
    assert body == np.hstack([points, normals]).astype("<f8").tobytes()


@pytest.mark.parametrize(
    ("points", "normals", "fmt", "message"),
    [
        (np.zeros((2, 3)), None, "pcd", "written as ply, xyz, csv, not 'pcd'"),
        (np.zeros((2, 2)), None, "ply", r"must be an \(n, 3\) array"),
        (np.zeros((2, 3)), np.zeros((3, 3)), "ply", "3 normals for 2 points"),
        (np.array([[0, 0, np.nan]]), None, "xyz", "not a finite number"),
        (np.zeros((1, 3)), np.array([[0, 0, np.inf]]), "xyz", "normals hold a value"),
    ],
)
def test_bad_input_is_a_value_error(
    points: np.ndarray, normals: np.ndarray | None, fmt: str, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        write_points(points, normals, fmt)
