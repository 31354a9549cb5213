from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mesh_normal.files import MeshFileError, read_mesh
from mesh_normal.points.io.read import PointCloud, colors_uint8, read_points
from tests.mesh_normal.points._pcd import pcd_header
from tests.paths import DATA

PCD = pcd_header("x y z", "4 4 4", "F F F", 1) + b"1 2 3\n"


@pytest.mark.parametrize(
    ("name", "found"),
    [("scan.pcd", "pcd"), ("scan.xyz", "pcd"), (None, "pcd"), ("scan.ply", "pcd")],
)
def test_the_bytes_tell_the_format_before_the_name(name: str | None, found: str) -> None:
    cloud = read_points(PCD, name)
    assert cloud.format == found
    if name and not name.endswith(".pcd"):
        assert cloud.notes[0].startswith("The file is named as ")
        assert cloud.notes[0].endswith("but holds PCD; it was read as PCD.")
    else:
        assert cloud.notes == ()


def test_text_without_a_name_is_a_table() -> None:
    assert read_points(b"# scan\n1 2 3\n").format == "xyz"
    assert read_points(b"X,Y,Z\n1,2,3\n").format == "xyz"


def test_sources_path_bytes_and_file_objects(tmp_path: Path) -> None:
    path = tmp_path / "scan.xyz"
    path.write_bytes(b"1 2 3\n")
    for source in (path, str(path), b"1 2 3\n", bytearray(b"1 2 3\n"), io.BytesIO(b"1 2 3\n")):
        np.testing.assert_array_equal(read_points(source).points, [[1, 2, 3]])
    with path.open("rb") as file:
        np.testing.assert_array_equal(read_points(file).points, [[1, 2, 3]])
    with pytest.raises(FileNotFoundError):
        read_points(tmp_path / "missing.xyz")


@pytest.mark.parametrize(
    "name",
    [
        "teapot.stl",
        "fuze.obj",
        "off_face_colors.off",
        "gltf/cube_vertex_colors.glb",
        "threemf_basematerials.3mf",
    ],
)
def test_mesh_files_give_their_vertices(name: str) -> None:
    mesh = read_mesh(DATA / name)
    cloud = read_points(DATA / name)
    assert (cloud.format, cloud.source_kind) == (mesh.format, "mesh vertices")
    np.testing.assert_array_equal(cloud.points, mesh.vertices)
    if mesh.file_vertex_normals is None:
        assert cloud.normals is None
    else:
        np.testing.assert_array_equal(cloud.normals, mesh.file_vertex_normals)
    assert (cloud.colors is None) == (mesh.vertex_colors is None)
    assert cloud.notes[-1] == f"The file is a mesh: its {len(mesh.faces):,} triangles are not used."


def test_mesh_vertex_normals_and_float_colours() -> None:
    assert read_points(DATA / "fuze.obj").normals is not None
    cloud = read_points(DATA / "gltf" / "cube_vertex_colors.glb")
    mesh = read_mesh(DATA / "gltf" / "cube_vertex_colors.glb")
    assert cloud.colors is not None and mesh.vertex_colors is not None
    np.testing.assert_array_equal(cloud.colors, np.round(mesh.vertex_colors[:, :3] * 255))


@pytest.mark.parametrize(
    ("data", "name", "status", "message"),
    [
        (b"", "a.pcd", 400, "The file is empty (0 bytes)."),
        (bytes(range(256)) * 4, None, 415, "not recognised from its content"),
        (bytes(range(256)) * 4, "a.bin", 415, "The format of this .bin file is not supported"),
        (bytes(range(256)) * 4, "a.pcd", 400, "no 'DATA' line"),
        (bytes(range(256)) * 4, "a.las", 400, "does not start with 'LASF'"),
        (b"\x89PNG\r\n\x1a\n" + bytes(100), "a.xyz", 400, "where a number should be"),
    ],
)
def test_unknown_and_garbage(data: bytes, name: str | None, status: int, message: str) -> None:
    with pytest.raises(
        MeshFileError, match=message.replace("(", r"\(").replace(")", r"\)")
    ) as caught:
        read_points(data, name)
    assert caught.value.status_code == status


def test_the_cloud_is_frozen() -> None:
    cloud = read_points(b"1 2 3 0 0 1 \n", "a.xyz")
    assert isinstance(cloud, PointCloud)
    for array in (cloud.points, cloud.normals, cloud.kept):
        assert array is not None and not array.flags.writeable
    assert cloud.points.dtype == np.float64 and cloud.kept.dtype == np.int64
    with pytest.raises(AttributeError):
        cloud.points = cloud.points  # type: ignore[misc]


@pytest.mark.parametrize(
    ("values", "expected"),
    [
        (np.array([[0, 128, 255]], np.uint8), [[0, 128, 255]]),
        (np.array([[0, 257, 65535]], np.uint16), [[0, 1, 255]]),
        (np.array([[0.0, 0.5, 1.0]], np.float32), [[0, 128, 255]]),
        (np.array([[0.0, 2.0, 255.0]]), [[0, 2, 255]]),  # whole numbers above 1: 0-255
        (np.array([[0, 1, 1]], np.int32), [[0, 1, 1]]),
    ],
)
def test_colours_become_8_bit(values: np.ndarray, expected: list[list[int]]) -> None:
    result = colors_uint8(values)
    assert result.dtype == np.uint8
    np.testing.assert_array_equal(result, expected)


@pytest.mark.parametrize(
    "values",
    [np.array([[0, 0, 256.0]]), np.array([[0, 0, -1]], np.int16), np.array([[0, np.nan, 0]])],
)
def test_colours_out_of_range_are_refused(values: np.ndarray) -> None:
    with pytest.raises(MeshFileError, match="colour value"):
        colors_uint8(values)


def test_an_obj_without_faces_is_its_v_lines() -> None:
    text = b"# cloud\nv 1 2 3 1 0 0\nvn 0 0 1\nv 4 5 6 0 0.5 1\nvn 0 1 0\n"
    with pytest.raises(MeshFileError, match="no faces"):
        read_mesh(text, "cloud.obj")
    cloud = read_points(text, "cloud.obj")
    assert (cloud.format, cloud.source_kind) == ("obj", "points")
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(cloud.normals, [[0, 0, 1], [0, 1, 0]])
    np.testing.assert_array_equal(cloud.colors, [[255, 0, 0], [0, 128, 255]])
    weights = read_points(b"v 1 2 3 1\nv 4 5 6 1\nvn 0 0 1\n")
    assert weights.normals is None
    assert weights.notes == (
        "The file's vertex weights (w) are not used.",
        "The file's 1 vn normals are not used: without faces they follow the 2 vertices "
        "only when there are as many.",
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (b"v 1 2 3\nv 4 5\n", "The OBJ vertex on line 2 has 2 numbers"),
        (b"v 1 2 3\nv 4 five 6\n", "Line 2 has 'five' where a number should be"),
        (b"v 1 2 3\nv 4 nan 6\n", "The coordinates of the vertex on line 2 include nan"),
        (b"v 1 2 3\nvn 0 0\n", "The OBJ normal on line 2 is not 3 numbers"),
        (b"v 1 2 3\nvn 0 0 x\n", "Line 2 has 'x' where a number should be"),
    ],
)
def test_broken_obj_clouds(text: bytes, message: str) -> None:
    with pytest.raises(MeshFileError, match=message):
        read_points(text, "cloud.obj")


SAMPLES = {
    "cloud.pcd": pcd_header("x y z rgb", "4 4 4 4", "F F F U", 2, "binary") + bytes(range(32)),
    "cloud.ply": b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
    b"property float z\nproperty uchar red\nend_header\n0 0 0 1\n1 1 1 2\n",
    "cloud.xyz": b"# x y z nx ny nz\n1 2 3 0 0 1\n4 5 6 0 1 0\n",
    "cloud.pts": b"2\n1 2 3 0 10 20 30\n4 5 6 0 40 50 60\n",
    "cloud.obj": b"v 1 2 3\nv 4 5 6\nvn 0 0 1\nvn 0 1 0\n",
}


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(sorted(SAMPLES)), st.data())
def test_damaged_files_give_a_cloud_or_a_sentence(name: str, data: st.DataObject) -> None:
    """Bytes changed, cut or added anywhere: a cloud, or one MeshFileError, nothing else."""
    damaged = bytearray(SAMPLES[name])
    for _ in range(data.draw(st.integers(1, 4))):
        position = data.draw(st.integers(0, len(damaged)))
        damaged[position : position + data.draw(st.integers(0, 3))] = data.draw(
            st.binary(max_size=3) | st.sampled_from([b"9", b" ", b"\n", b"nan", b"-"])
        )
    outcome = _read_or_refuse(bytes(damaged), name)
    if isinstance(outcome, MeshFileError):
        assert str(outcome)[:1].isupper() and str(outcome).endswith(".")
        assert outcome.status_code in (400, 415)
    else:
        assert np.isfinite(outcome.points).all() and len(outcome.points) == len(outcome.kept)


def _read_or_refuse(data: bytes, name: str) -> PointCloud | MeshFileError:
    try:
        return read_points(data, name)
    except MeshFileError as error:
        return error
