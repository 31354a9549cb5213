from __future__ import annotations

import struct

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mesh_normal.files import MeshFileError
from mesh_normal.points.io.pcd import lzf_decompress
from mesh_normal.points.io.read import read_points
from tests.mesh_normal.points._pcd import compressed_body, literal_lzf, lzf_compress, pcd_header

POINTS = np.array([[0.5, -1.25, 3.0], [1e5, 2.0, -0.0], [7.0, 8.0, 9.0]])
NORMALS = np.array([[0.0, 0.0, 1.0], [0.6, 0.8, 0.0], [1.0, 0.0, 0.0]])
COLORS = np.array([[255, 0, 10], [1, 2, 3], [200, 100, 50]], dtype=np.uint8)
PACKED = (
    (COLORS[:, 0].astype(np.uint32) << 16) | (COLORS[:, 1].astype(np.uint32) << 8) | COLORS[:, 2]
)
FIELDS = "x y z normal_x normal_y normal_z rgb curvature"
RECORD = np.dtype(
    [(name, "<f4") for name in ("x", "y", "z", "normal_x", "normal_y", "normal_z")]
    + [("rgb", "<u4"), ("curvature", "<f4")]
)


def record() -> np.ndarray:
    rows = np.zeros(len(POINTS), RECORD)
    for i, axis in enumerate("xyz"):
        rows[axis] = POINTS[:, i]
        rows[f"normal_{axis}"] = NORMALS[:, i]
    rows["rgb"] = PACKED
    rows["curvature"] = 0.25
    return rows


def pcd(data: str, types: str = "F F F F F F U F") -> bytes:
    header = pcd_header(FIELDS, "4 4 4 4 4 4 4 4", types, len(POINTS), data)
    rows = record()
    if data == "ascii":
        return (
            header + "".join(_line([row[name] for name in RECORD.names]) for row in rows).encode()
        )
    if data == "binary":
        return header + rows.tobytes()
    return header + compressed_body(rows)


def _line(values: list[np.generic]) -> str:
    return " ".join(repr(float(v)) if v.dtype.kind == "f" else str(v) for v in values) + "\n"


@pytest.mark.parametrize("data", ["ascii", "binary", "binary_compressed"])
def test_fields_normals_colours_and_viewpoint(data: str) -> None:
    cloud = read_points(pcd(data), "scan.pcd")
    assert cloud.format == "pcd" and cloud.source_kind == "points"
    np.testing.assert_array_equal(cloud.points, POINTS.astype(np.float32))
    np.testing.assert_array_equal(cloud.normals, NORMALS.astype(np.float32))
    np.testing.assert_array_equal(cloud.colors, COLORS)
    assert cloud.colors is not None and cloud.colors.dtype == np.uint8
    origin, rotation = cloud.viewpoint or (None, None)
    np.testing.assert_array_equal(origin, [0, 0, 0])
    np.testing.assert_array_equal(rotation, [1, 0, 0, 0])
    np.testing.assert_array_equal(cloud.kept, [0, 1, 2])
    assert cloud.notes == ("The file's curvature fields are not used.",)
    assert not cloud.points.flags.writeable


def test_rgb_packed_in_a_float() -> None:
    header = pcd_header("x y z rgb", "4 4 4 4", "F F F F", 2)
    bits = np.array([0x00FF8001, 0x00010203], dtype=np.uint32)
    rows = np.zeros(2, [("xyz", "<f4", 3), ("rgb", "<u4")])
    rows["rgb"] = bits
    cloud = read_points(header.replace(b"ascii", b"binary") + rows.tobytes())
    np.testing.assert_array_equal(cloud.colors, [[255, 128, 1], [1, 2, 3]])
    text = "".join(f"0 0 0 {float(v)!r}\n" for v in bits.view(np.float32))
    ascii_cloud = read_points(header + text.encode())
    np.testing.assert_array_equal(ascii_cloud.colors, cloud.colors)


def test_viewpoint_and_counts() -> None:
    header = pcd_header(
        "x y z h", "8 8 8 2", "F F F U", 1, counts="1 1 1 3", viewpoint="1 2 3 0.5 0.5 0.5 0.5"
    )
    cloud = read_points(header + b"1 2 3 4 5 6\n")
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3]])
    assert cloud.viewpoint is not None
    np.testing.assert_array_equal(cloud.viewpoint[0], [1, 2, 3])
    np.testing.assert_array_equal(cloud.viewpoint[1], [0.5, 0.5, 0.5, 0.5])
    assert cloud.notes == ("The file's h fields are not used.",)
    assert cloud.normals is None and cloud.colors is None


def test_padding_fields_are_read_past_silently() -> None:
    header = pcd_header("x _ y z _", "4 1 4 4 4", "F U F F F", 1, counts="1 3 1 1 1")
    rows = np.zeros(1, [("x", "<f4"), ("p", "u1", 3), ("y", "<f4"), ("z", "<f4"), ("q", "<f4")])
    rows["x"], rows["y"], rows["z"] = 1, 2, 3
    cloud = read_points(header.replace(b"ascii", b"binary") + rows.tobytes())
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3]])
    assert cloud.notes == ()


@pytest.mark.parametrize("data", ["ascii", "binary"])
def test_organised_cloud_nan_points_are_left_out_and_counted(data: str) -> None:
    values = np.array([[1, 2, 3], [np.nan, np.nan, np.nan], [4, 5, 6], [np.nan, 0, 0]], dtype="<f4")
    header = pcd_header("x y z", "4 4 4", "F F F", 4, data, height=2)
    body = (
        values.tobytes()
        if data == "binary"
        else "".join(" ".join(map(str, row)) + "\n" for row in values.tolist()).encode()
    )
    cloud = read_points(header + body)
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(cloud.kept, [0, 2])
    assert cloud.file_points == 4
    assert cloud.notes == (
        "2 of the file's 4 points have no coordinates (NaN), as organised clouds mark "
        "missing points; they were left out.",
    )


def test_nan_normals_stay_nan_with_a_note() -> None:
    header = pcd_header("x y z normal_x normal_y normal_z", "4 4 4 4 4 4", "F F F F F F", 2)
    cloud = read_points(header + b"0 0 0 nan nan nan\n1 1 1 0 0 1\n")
    assert cloud.normals is not None
    assert np.isnan(cloud.normals[0]).all()
    np.testing.assert_array_equal(cloud.normals[1], [0, 0, 1])
    assert cloud.notes == ("1 point in the file has no normal (NaN).",)


@given(st.lists(st.binary(min_size=1, max_size=40), max_size=30), st.data())
def test_lzf_round_trip(pieces: list[bytes], data: st.DataObject) -> None:
    # Repeats make the compressor write back references, overlapping ones included.
    raw = b"".join(piece * data.draw(st.integers(1, 20)) for piece in pieces)
    assert lzf_decompress(lzf_compress(raw), len(raw)).tobytes() == raw


def test_lzf_back_references() -> None:
    # "abcabcabcX": literal "abc", a back reference of 6 bytes at distance 3 (overlapping), "X"
    packed = bytes([2]) + b"abc" + bytes([(4 << 5) | 0, 2]) + bytes([0]) + b"X"
    assert lzf_decompress(packed, 10).tobytes() == b"abcabcabcX"
    long = bytes([0]) + b"z" + bytes([(7 << 5), 10, 0])  # 7 + 10 + 2 = 19 copies of "z"
    assert lzf_decompress(long, 20).tobytes() == b"z" * 20
    assert lzf_decompress(literal_lzf(bytes(range(100))), 100).tobytes() == bytes(range(100))


@pytest.mark.parametrize(
    ("packed", "size"),
    [
        (bytes([(1 << 5), 5]), 3),  # a reference before the start
        (bytes([5]) + b"ab", 6),  # a literal run past the end
        (bytes([0]) + b"a", 2),  # unpacks short
        (bytes([0]) + b"a" + bytes([(7 << 5)]), 9),  # ends inside a reference
    ],
)
def test_broken_lzf_is_refused(packed: bytes, size: int) -> None:
    with pytest.raises(MeshFileError, match="compressed PCD data"):
        lzf_decompress(packed, size)


HEAD = pcd_header("x y z", "4 4 4", "F F F", 2)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (HEAD + b"0 0 0\n1.5 1.5\n", "Line 12 has 2 numbers, but the header's fields call for 3"),
        (HEAD + b"0 0 0\n", "The PCD header says 2 points, but the file is too short"),
        (HEAD + b"0 0 0\n1 1 1\n2 2 2\n", "says 2 points, but the file holds 3"),
        (HEAD + b"0 0 0\n1 one 1\n", "Line 12 has 'one' where a number should be"),
        (
            HEAD.replace(b"DATA ascii", b"DATA binary") + bytes(20),
            "holds only 1: it looks truncated",
        ),
        (HEAD.replace(b"POINTS 2", b"POINTS 1000000000000"), "WIDTH 2 and HEIGHT 1 make 2 points"),
        (HEAD.replace(b"DATA ascii\n", b""), "no 'DATA' line"),
        (b"FIELDS x y z\n" + b"1 2 3\n" * 2000, "no 'DATA' line"),
        (b"FIELDS x y z " + b"1" * 70000 + b"\nDATA ascii\n", "no 'DATA' line"),
        (HEAD.replace(b"DATA ascii", b"DATA zip"), "DATA 'zip' is not ascii"),
        (HEAD.replace(b"SIZE 4 4 4", b"SIZE 4 4"), "SIZE line is not 3 whole numbers"),
        (HEAD.replace(b"TYPE F F F", b"TYPE F F"), "names 3 fields but gives 2 TYPE"),
        (HEAD.replace(b"TYPE F F F", b"TYPE F F Q"), "TYPE Q and SIZE 4, which is not"),
        (HEAD.replace(b"SIZE 4 4 4", b"SIZE 4 4 2"), "TYPE F and SIZE 2"),
        (HEAD.replace(b"FIELDS x y z", b"FIELDS x y w"), "no x, y and z fields"),
        (HEAD.replace(b"FIELDS x y z", b"FIELDS x y x"), "names a field twice"),
        (
            HEAD.replace(b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0 nan 1 0 0 0"),
            "VIEWPOINT is not 7",
        ),
        (HEAD.replace(b"WIDTH 2", b"WIDTH -2"), "WIDTH line is not a whole number"),
        (HEAD + b"0 0 0\ninf 0 0\n", None),  # infinite: left out, like NaN
        (HEAD + b"nan 0 0\nnan 0 0\n", "no points with finite coordinates"),
        (pcd_header("x y z", "4 4 4", "F F F", 0), "The file holds no points."),
    ],
)
def test_broken_files_are_refused_with_a_sentence(data: bytes, message: str | None) -> None:
    if message is None:
        assert len(read_points(data).points) == 1
        return
    with pytest.raises(MeshFileError, match=message) as caught:
        read_points(data)
    assert caught.value.status_code == 400
    assert str(caught.value).endswith(".")


def test_lying_point_counts_are_refused_before_allocating() -> None:
    huge = 10**12
    for data in ("ascii", "binary", "binary_compressed"):
        header = pcd_header("x y z", "4 4 4", "F F F", huge, data)
        with pytest.raises(MeshFileError, match="1,000,000,000,000 points"):
            read_points(header + struct.pack("<II", 10, 2**32 - 1) + bytes(10))


def test_compressed_sizes_are_checked() -> None:
    header = pcd_header("x y z", "4 4 4", "F F F", 2, "binary_compressed")
    with pytest.raises(
        MeshFileError, match="unpack to 12 bytes, but 2 points of its fields take 24"
    ):
        read_points(header + struct.pack("<II", 13, 12) + literal_lzf(bytes(12)))
    with pytest.raises(MeshFileError, match="are 100 bytes, but the file holds only 25"):
        read_points(header + struct.pack("<II", 100, 24) + literal_lzf(bytes(24)))
    with pytest.raises(MeshFileError, match="ends before its data sizes"):
        read_points(header + b"\x01")
    many = pcd_header("x y z", "4 4 4", "F F F", 100, "binary_compressed")
    with pytest.raises(MeshFileError, match=r"\(2 bytes\) cannot unpack to the 1,200 bytes"):
        read_points(many + struct.pack("<II", 2, 1200) + b"\x00\x00")
