from __future__ import annotations

import io
import struct

import laspy
import numpy as np
import pytest

from mesh_normal.files import MeshFileError
from mesh_normal.files.expansion import ExpansionTooLarge
from mesh_normal.points.io import las as las_module
from mesh_normal.points.io.read import read_points

# UTM-like coordinates, millimetre scale: the scaled values, never the stored integers.
X = np.array([500000.123, 500001.5, 500002.25, 500003.0])
Y = np.array([4000000.5, 4000001.0, 4000002.0, 4000003.001])
Z = np.array([1.0, 2.5, -3.0, 0.0])


def las_bytes(
    point_format: int = 3,
    compress: bool = False,
    colors: tuple[int, ...] = (0, 65535, 25700, 257),
    normals: bool = False,
) -> bytes:
    header = laspy.LasHeader(
        point_format=point_format, version="1.4" if point_format >= 6 else "1.2"
    )
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([500000.0, 4000000.0, 0.0])
    if normals:
        header.add_extra_dims(
            [laspy.ExtraBytesParams(name, "f8") for name in ("normal_x", "normal_y", "normal_z")]
        )
    data = laspy.LasData(header)
    data.x, data.y, data.z = X, Y, Z
    data.intensity = np.array([0, 10, 0, 3], dtype=np.uint16)
    if "red" in header.point_format.dimension_names:
        value = np.array(colors, dtype=np.uint16)
        data.red, data.green, data.blue = value, value[::-1].copy(), np.zeros(4, np.uint16)
    if normals:
        data.normal_x = np.array([0.0, 0.6, 1.0, 0.0])
        data.normal_y = np.array([0.0, 0.8, 0.0, 1.0])
        data.normal_z = np.array([1.0, 0.0, 0.0, 0.0])
    out = io.BytesIO()
    data.write(out, do_compress=compress)
    return out.getvalue()


@pytest.mark.parametrize("compress", [False, True])
def test_scaled_coordinates_and_colours(compress: bool) -> None:
    cloud = read_points(las_bytes(compress=compress), "scan.laz" if compress else "scan.las")
    assert cloud.format == ("laz" if compress else "las")
    np.testing.assert_allclose(cloud.points, np.stack([X, Y, Z], axis=1), rtol=0, atol=1e-9)
    stored = laspy.read(io.BytesIO(las_bytes(compress=compress)))
    np.testing.assert_array_equal(cloud.points, np.stack([stored.x, stored.y, stored.z], axis=1))
    np.testing.assert_array_equal(
        cloud.colors, [[0, 1, 0], [255, 100, 0], [100, 255, 0], [1, 0, 0]]
    )
    assert cloud.normals is None
    assert cloud.notes == ("The file's intensity values are not used.",)


def test_8_bit_values_in_16_bit_fields_are_kept_with_a_note() -> None:
    cloud = read_points(las_bytes(colors=(0, 255, 100, 1)))
    np.testing.assert_array_equal(
        cloud.colors, [[0, 1, 0], [255, 100, 0], [100, 255, 0], [1, 0, 0]]
    )
    assert "read as 8-bit values" in cloud.notes[0]


def test_no_colours_and_extra_bytes_normals() -> None:
    cloud = read_points(las_bytes(point_format=1, normals=True))
    assert cloud.colors is None
    np.testing.assert_array_equal(cloud.normals, [[0, 0, 1], [0.6, 0.8, 0], [1, 0, 0], [0, 1, 0]])


@pytest.mark.parametrize("compress", [False, True])
def test_chunks(compress: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(las_module, "CHUNK_POINTS", 3)
    cloud = read_points(las_bytes(compress=compress))
    np.testing.assert_allclose(cloud.points[:, 0], X, rtol=0, atol=1e-9)


def _lie(data: bytes, count: int) -> bytes:
    lying = bytearray(data)
    struct.pack_into("<I", lying, 107, count)  # the legacy point count (LAS 1.2)
    return bytes(lying)


@pytest.mark.parametrize("compress", [False, True])
def test_lying_point_counts_are_refused(compress: bool) -> None:
    with pytest.raises(MeshFileError, match=r"1,000 points|truncated or broken") as caught:
        read_points(_lie(las_bytes(compress=compress), 1000))
    assert caught.value.status_code == 400
    # A count below what follows reads that many, as laspy and LAStools do.
    assert len(read_points(_lie(las_bytes(compress=compress), 2)).points) == 2


def test_a_billion_points_promised_are_refused() -> None:
    """LAS: against the bytes; LAZ: charged to the upload's budget before decompressing."""
    with pytest.raises(MeshFileError, match=r"says 1,000,000,000 points, but the file holds only"):
        read_points(_lie(las_bytes(), 10**9))
    with pytest.raises(ExpansionTooLarge, match=r"LAZ file's 1,000,000,000 compressed points"):
        read_points(_lie(las_bytes(compress=True), 10**9))


def _patch(data: bytes, position: int, value: int) -> bytes:
    return data[:position] + bytes([value]) + data[position + 1 :]


@pytest.mark.parametrize(
    "data",
    [
        las_bytes()[:200],  # the header cut short
        las_bytes()[:-30],  # the points cut short
        las_bytes(compress=True)[:-40],
        las_bytes()[:96] + bytes(300),  # garbage after the signature
        b"LASF" + bytes(range(256)) * 2,  # 4 billion VLRs, as laspy would read them
        _patch(las_bytes(compress=True), 296, 85),  # chunks of 1.4 billion points
    ],
)
def test_broken_files_are_refused_with_a_sentence(data: bytes) -> None:
    with pytest.raises(MeshFileError) as caught:
        read_points(data, "scan.las")
    assert caught.value.status_code == 400
    assert str(caught.value).endswith(".")
