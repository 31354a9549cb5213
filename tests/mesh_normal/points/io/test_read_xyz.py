from __future__ import annotations

import numpy as np
import pytest

from mesh_normal.files import MeshFileError
from mesh_normal.points.io import xyz
from mesh_normal.points.io.read import read_points


def test_three_columns_comments_commas_and_blank_lines() -> None:
    text = b"# a scan\n// made by hand\n\n1 2 3\n4.5,-6e-3,7\n\t8\t9  10 \n"
    cloud = read_points(text, "scan.xyz")
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4.5, -6e-3, 7], [8, 9, 10]])
    assert cloud.normals is None and cloud.colors is None
    assert (cloud.format, cloud.source_kind, cloud.notes) == ("xyz", "points", ())


def test_six_columns_are_normals_unless_they_look_like_colours() -> None:
    normals = read_points(b"0 0 0 0 0 1\n1 1 1 0.6 0.8 0\n", "a.xyz")
    np.testing.assert_array_equal(normals.normals, [[0, 0, 1], [0.6, 0.8, 0]])
    colours = read_points(b"0 0 0 255 0 1\n1 1 1 12 80 0\n", "a.xyz")
    assert colours.normals is None
    np.testing.assert_array_equal(colours.colors, [[255, 0, 1], [12, 80, 0]])
    # .xyzn: normals even when they are whole numbers; .xyzrgb: colours in 0-1 (Open3D)
    named = read_points(b"0 0 0 0 0 2\n", "a.xyzn")
    np.testing.assert_array_equal(named.normals, [[0, 0, 2]])
    rgb = read_points(b"0 0 0 1 0.5 0\n", "a.xyzrgb")
    np.testing.assert_array_equal(rgb.colors, [[255, 128, 0]])


def test_pts_count_line_intensity_and_colours() -> None:
    cloud = read_points(b"2\n1 2 3 -1200 10 20 30\n4 5 6 7 40 50 60\n", "a.pts")
    assert cloud.format == "pts"
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(cloud.colors, [[10, 20, 30], [40, 50, 60]])
    assert cloud.notes == ("The file's fourth column (intensity, as PTS files hold) is not used.",)
    with pytest.raises(MeshFileError, match="first line says 3 points, but it holds 2"):
        read_points(b"3\n1 2 3 0\n4 5 6 0\n", "a.pts")


def test_nine_columns_either_order() -> None:
    first = read_points(b"0 0 0 0 0 1 255 128 0\n", "a.txt")
    np.testing.assert_array_equal(first.normals, [[0, 0, 1]])
    np.testing.assert_array_equal(first.colors, [[255, 128, 0]])
    second = read_points(b"0 0 0 255 128 0 0 0 1\n", "a.txt")
    np.testing.assert_array_equal(second.normals, [[0, 0, 1]])
    np.testing.assert_array_equal(second.colors, [[255, 128, 0]])


def test_other_widths_keep_xyz_and_say_so() -> None:
    cloud = read_points(b"1 2 3 4 5\n", "a.xyz")
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3]])
    assert "columns 4 to 5 are not used" in cloud.notes[0]


def test_header_row_names_the_columns() -> None:
    cloud = read_points(b"Z,nx,ny,nz,X,Y,intensity\n3,0,0,1,1,2,9\n", "a.csv")
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3]])
    np.testing.assert_array_equal(cloud.normals, [[0, 0, 1]])
    assert cloud.notes == ("The file's intensity columns are not used.",)
    compare = read_points(b"//X,Y,Z,R,G,B\n1,2,3,0,0,1\n", "a.txt")  # CloudCompare's
    np.testing.assert_array_equal(compare.colors, [[0, 0, 255]])
    assert compare.normals is None
    spelled = read_points(b"x y z normal_x normal_y normal_z red green blue\n0 0 0 0 1 0 1 2 3\n")
    np.testing.assert_array_equal(spelled.normals, [[0, 1, 0]])
    np.testing.assert_array_equal(spelled.colors, [[1, 2, 3]])


def test_rows_across_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(xyz, "_CHUNK", 16)
    rows = np.arange(300, dtype=np.float64).reshape(-1, 3) / 7
    text = "x y z\n" + "".join(" ".join(map(repr, row)) + "\n" for row in rows.tolist())
    cloud = read_points((text + "# end\n").encode())
    np.testing.assert_array_equal(cloud.points, rows)
    with pytest.raises(
        MeshFileError, match="Line 90 has 2 numbers, but the lines before it have 3"
    ):
        read_points(text.replace(f"{float(rows[88, 0])!r} ", "", 1).encode(), "a.xyz")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"1 2 3\n4 5\n", "Line 2 has 2 numbers, but the lines before it have 3; every point"),
        (b"1 2\n4 5\n", "Line 1 has only 2 numbers; a point needs x, y and z"),
        (b"1 2 3\n4 five 6\n", "Line 2 has 'five' where a number should be"),
        (b"1 2 3\n4 nan 6\n", "The coordinates of the point on line 2 include nan"),
        (b"1 2 3\n4 5 -inf\n", "The coordinates of the point on line 2 include -inf"),
        (b"1 2 3 0 0 1\n4 5 6 0 nan 1\n", "The normal of the point on line 2 includes nan"),
        (b"# only a comment\n", "The file holds no points"),
        (b"x y z\n", "The file holds no points"),
        (b"a b c\n1 2 3\n", "Line 1 has 'a' where a number should be .a header row"),
        (b"x,y,z,nx\n1,2,3\n", "The header row names 4 columns, but the rows hold 3"),
        (b"0 0 0 1 2 3 4\n0 0 0 1 2 3 -4\n", "A colour value of -4 is outside 0-255"),
        (b"0 0 0 0 0 0 1.5\n", "A colour value of 1.5 is outside 0-1"),
        (b"\x00\x01\x02 garbage\xff\n", "where a number should be"),
    ],
)
def test_broken_tables_are_refused_with_a_sentence(data: bytes, message: str) -> None:
    with pytest.raises(MeshFileError, match=message) as caught:
        read_points(data, "scan.xyz")
    assert caught.value.status_code == 400
    assert str(caught.value).endswith(".")


def test_a_binary_expe_point_set_is_refused_by_name() -> None:
    data = b"[Expe/PointSet/Binary/float32/ascii]\n3 position\x00\x00\x80?\x00\x00"
    with pytest.raises(MeshFileError, match="binary Expe point set") as caught:
        read_points(data, "bunny.pts")
    assert caught.value.status_code == 415
