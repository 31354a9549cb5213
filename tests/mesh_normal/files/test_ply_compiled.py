"""Binary PLY lists read by the compiled loop give the arrays NumPy's view of the records gives."""

from __future__ import annotations

import numpy as np
import pytest

from mesh_normal._core import binary_items
from mesh_normal.files import ply
from mesh_normal.files.errors import MeshFileError


def binary_ply(endian: str, count: str, item: str, extra: bool, faces: np.ndarray) -> bytes:
    """A binary PLY of four vertices and ``faces``, each face's list of ``item`` after a
    ``count``, and (``extra``) a ``uchar`` before and a ``float`` after it."""
    order = {"<": "binary_little_endian", ">": "binary_big_endian"}[endian]
    names = {"u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int", "u4": "uint"}
    header = [
        "ply",
        f"format {order} 1.0",
        "element vertex 4",
        "property float x",
        "property float y",
        "property float z",
        f"element face {len(faces)}",
        *(["property uchar flag"] if extra else []),
        f"property list {names[count]} {names[item]} vertex_indices",
        *(["property float quality"] if extra else []),
        "end_header",
        "",
    ]
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=endian + "f4")
    fields = [
        *([("flag", "u1")] if extra else []),
        ("count", endian + count),
        ("items", endian + item, (faces.shape[1],)),
        *([("quality", endian + "f4")] if extra else []),
    ]
    records = np.zeros(len(faces), dtype=fields)
    records["count"], records["items"] = faces.shape[1], faces
    if extra:
        records["flag"], records["quality"] = 7, 0.5
    return "\n".join(header).encode() + vertices.tobytes() + records.tobytes()


@pytest.mark.parametrize("endian", ["<", ">"])
@pytest.mark.parametrize(
    ("count", "item"), [("u1", "i4"), ("u1", "u4"), ("u2", "i2"), ("u1", "u1")]
)
@pytest.mark.parametrize("extra", [False, True])
def test_the_compiled_lists_are_the_file_s(endian: str, count: str, item: str, extra: bool) -> None:
    faces = np.random.default_rng(5).integers(0, 4, (50, 3))
    faces[:, 1] = (faces[:, 0] + 1) % 4
    faces[:, 2] = (faces[:, 0] + 2) % 4
    mesh = ply.read_ply(binary_ply(endian, count, item, extra, faces))
    np.testing.assert_array_equal(mesh.faces, faces)
    assert mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert not mesh.notes and mesh.source_faces == 50


@pytest.mark.parametrize(("item", "value"), [("i4", -1), ("i2", -2), ("i4", 2**31 - 1)])
def test_signed_items_keep_their_sign(item: str, value: int) -> None:
    faces = np.array([[0, 1, value]])
    with pytest.raises(MeshFileError, match=f"{value:,}"):
        ply.read_ply(binary_ply(">", "u1", item, True, faces))


def test_quads_still_go_through_triangulate() -> None:
    mesh = ply.read_ply(binary_ply("<", "u1", "i4", False, np.array([[0, 1, 2, 3]])))
    assert len(mesh.faces) == 2 and mesh.source_faces == 1


@pytest.mark.parametrize("endian", ["<", ">"])
@pytest.mark.parametrize("item", ["i4", "u4", "i2"])
def test_many_records_read_on_every_core_match_numpy(endian: str, item: str) -> None:
    # Enough records for several threads' chunks (the last one shorter), each item unaligned
    # (13-byte records).
    count = 3 * (1 << 14) + 7
    low, high = (
        (-(2**31), 2**31) if item == "i4" else (0, 2**32) if item == "u4" else (-(2**15), 2**15)
    )
    faces = np.random.default_rng(len(item)).integers(low, high, (count, 3))
    faces[-1] = [high - 1, low, 0]
    records = np.zeros(count, dtype=[("count", "u1"), ("items", endian + item, (3,))])
    records["count"], records["items"] = 3, faces
    element = ply._Element("face", count, [], {"vertex_indices": ("u1", item)}, ["vertex_indices"])
    data = records.tobytes()
    assert ply._binary_lists(element, data, 0, endian) == len(data)
    np.testing.assert_array_equal(element.data["vertex_indices"], faces)


def test_face_colours_and_normals_of_triangles_stay_in_file_order() -> None:
    # Triangles are their own faces (no fans, no gather through their numbers): the face
    # colours and normals read are the file's, row for row.
    rng = np.random.default_rng(9)
    points = rng.normal(size=(30, 3))
    triangles = np.array([[i, (i + 1) % 30, (i + 2) % 30] for i in range(30)])
    colours = rng.integers(0, 256, (30, 3)).astype(np.uint8)
    normals = rng.normal(size=(30, 3))
    data = ply.write_ply(
        points, triangles, face_colors=colours, normals=normals, normals_kind="face"
    )
    own = ply.read_ply(data)
    np.testing.assert_array_equal(own.faces, triangles)
    np.testing.assert_array_equal(own.face_colors, colours)
    np.testing.assert_array_equal(own.file_face_normals, normals)


def test_the_items_of_records_that_end_in_the_last_byte_are_read() -> None:
    data = np.frombuffer(bytes(range(1, 14)), np.uint8)  # two 6-byte records after 1 byte
    items = np.empty((2, 3), np.int64)
    binary_items(data, 1, 6, 2, False, False, items)
    assert items.tolist() == [[0x0203, 0x0405, 0x0607], [0x0809, 0x0A0B, 0x0C0D]]


@pytest.mark.parametrize(
    ("offset", "stride", "size", "rows", "error"),
    [
        (2, 6, 2, 2, IndexError),  # the last item one byte past the end
        (0, 6, 2, 3, IndexError),  # a record more than the data holds
        (0, 2**62, 2, 2, IndexError),  # a stride past any data, without overflow
        (-1, 6, 2, 1, ValueError),
        (0, 5, 2, 1, ValueError),  # records shorter than their lists
        (0, 0, 1, 1, ValueError),
        (0, 6, 3, 1, ValueError),  # 3-byte items
        (2**62, 6, 2, 1, IndexError),
    ],
)
def test_records_past_the_data_are_refused(
    offset: int, stride: int, size: int, rows: int, error: type[Exception]
) -> None:
    data = np.frombuffer(bytes(13), np.uint8)
    with pytest.raises(error, match=r"^[A-Z][^.]*\.$"):
        binary_items(data, offset, stride, size, True, True, np.empty((rows, 3), np.int64))


def test_items_of_a_wrong_type_are_refused_not_converted() -> None:
    data = np.frombuffer(bytes(13), np.uint8)
    with pytest.raises(TypeError):
        binary_items(data, 0, 6, 2, True, True, np.empty((2, 3), np.int32))  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        binary_items(data.astype(np.int8), 0, 6, 2, True, True, np.empty((2, 3), np.int64))  # type: ignore[arg-type]


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_the_items_do_not_depend_on_the_number_of_threads(threads: int) -> None:
    from mesh_normal import _core

    rng = np.random.default_rng(threads)
    records = np.zeros(5 * (1 << 14) + 3, dtype=[("count", "u1"), ("items", ">i4", (3,))])
    records["count"], records["items"] = 3, rng.integers(-(2**31), 2**31, (len(records), 3))
    data = np.frombuffer(records.tobytes(), np.uint8)
    items = np.empty((len(records), 3), np.int64)
    before = _core.threads()
    _core.set_threads(threads)
    try:
        binary_items(data, 1, 13, 4, True, False, items)
    finally:
        _core.set_threads(before)
    np.testing.assert_array_equal(items, records["items"])
