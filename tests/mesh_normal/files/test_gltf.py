from __future__ import annotations

import importlib.util
import json
import re
import struct
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import trimesh

import mesh_normal as mn
from mesh_normal.files import MeshFileError, read_mesh
from mesh_normal.files.expansion import ExpansionTooLarge, expanding
from mesh_normal.files.gltf_buffers import glb_parts
from tests.paths import DATA


def scene() -> trimesh.Scene:
    result = trimesh.Scene()
    result.add_geometry(
        trimesh.creation.box(),
        node_name="box",
        transform=trimesh.transformations.translation_matrix([5, 0, 0]),
    )
    result.add_geometry(
        trimesh.creation.icosphere(1), node_name="ball", transform=np.diag([2.0, 1, 1, 1])
    )
    return result


@pytest.mark.parametrize("file_format", ["glb", "gltf"])
def test_primitives_joined_with_transforms(file_format: str) -> None:
    source = scene()
    if file_format == "glb":
        data = source.export(file_type="glb", include_normals=True)
    else:
        data = source.export(file_type="gltf", embed_buffers=True, include_normals=True)[
            "model.gltf"
        ]
    mesh = read_mesh(data, f"scene.{file_format}")
    assert mesh.format == file_format
    expected = source.to_geometry()
    assert len(mesh.vertices) == len(expected.vertices) and len(mesh.faces) == len(expected.faces)
    np.testing.assert_allclose(np.sort(mesh.vertices, axis=0), np.sort(expected.vertices, axis=0))
    assert mesh.vertices[:, 0].max() == pytest.approx(5.5)  # the box moved, the ball stretched
    assert mesh.file_vertex_normals is not None
    np.testing.assert_allclose(np.linalg.norm(mesh.file_vertex_normals, axis=1), 1)
    assert "Joined 2 primitives with their node transforms applied." in mesh.notes


def test_each_placed_primitive_is_a_group_named_by_its_node() -> None:
    mesh = read_mesh(scene().export(file_type="glb"), "scene.glb")
    assert mesh.group_names is not None and mesh.face_groups is not None
    assert sorted(mesh.group_names) == ["ball", "box"]
    counts = dict(zip(mesh.group_names, np.bincount(mesh.face_groups).tolist(), strict=True))
    assert counts == {"box": 12, "ball": 80}
    report = mn.analyse(mesh)
    assert {item.name: item.orientation for item in report.objects} == {
        "box": "outward",
        "ball": "outward",
    }


def test_mirroring_node_reverses_winding() -> None:
    source = trimesh.Scene()
    source.add_geometry(trimesh.creation.box(), node_name="box", transform=np.diag([-1.0, 1, 1, 1]))
    mesh = read_mesh(source.export(file_type="glb"), "m.glb")
    assert trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).volume > 0
    assert any("Reversed the winding" in note for note in mesh.notes)


def test_external_buffers_are_named() -> None:
    data = (
        b'{"asset": {"version": "2.0"}, "buffers": [{"uri": "model.bin", '
        b'"byteLength": 12}], "meshes": []}'
    )
    with pytest.raises(MeshFileError):
        read_mesh(data, "x.gltf")


def glb(header: dict[str, Any], blob: bytes) -> bytes:
    """A GLB written by hand: the JSON chunk, then the binary chunk."""
    text = json.dumps(header).encode()
    text += b" " * (-len(text) % 4)
    blob = bytes(blob) + b"\0" * (-len(blob) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    body += struct.pack("<II", len(blob), 0x004E4942) + blob
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


TETRA = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
TETRA_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.uint16)


def quantized_tetra(
    component: int, dtype: str, scale: float, normalized: bool = True, stride: int = 0
) -> bytes:
    """A tetrahedron whose positions are integers ``TETRA * scale`` (KHR_mesh_quantization),
    laid out with ``stride`` bytes a row when given, and its indices after them."""
    item = np.dtype(dtype).itemsize
    rows = np.zeros((4, max(stride, 3 * item)), dtype=np.uint8)
    rows[:, : 3 * item] = (TETRA * scale).astype(dtype).view(np.uint8).reshape(4, -1)
    positions = rows.tobytes()
    indices = TETRA_FACES.tobytes()
    view: dict[str, Any] = {"buffer": 0, "byteOffset": 0, "byteLength": len(positions)}
    if stride:
        view["byteStride"] = stride
    header = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "buffers": [{"byteLength": len(positions) + len(indices)}],
        "bufferViews": [
            view,
            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices)},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": component,
                "normalized": normalized,
                "count": 4,
                "type": "VEC3",
            },
            {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0, "scale": [2.0, 2.0, 2.0]}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return glb(header, positions + indices)


@pytest.mark.parametrize(
    ("component", "dtype", "scale"),
    [(5120, "<i1", 127), (5121, "<u1", 255), (5122, "<i2", 32767), (5123, "<u2", 65535)],
)
def test_normalized_integer_positions_are_decoded(component: int, dtype: str, scale: int) -> None:
    mesh = read_mesh(quantized_tetra(component, dtype, scale), "q.glb")
    np.testing.assert_allclose(mesh.vertices, TETRA * 2, atol=1e-6)  # the node scales by 2
    np.testing.assert_array_equal(mesh.faces, TETRA_FACES)
    assert "Decoded 1 quantized (normalized integer) glTF accessors." in mesh.notes


def test_normalized_int16_with_a_stride_and_the_minus_one_clamp() -> None:
    data = quantized_tetra(5122, "<i2", -32768, stride=8)  # -32768 / 32767 clamps to -1
    mesh = read_mesh(data, "q.glb")
    np.testing.assert_allclose(mesh.vertices, TETRA * -2, atol=1e-6)


def test_unnormalized_integers_are_their_values() -> None:
    mesh = read_mesh(quantized_tetra(5122, "<i2", 100, normalized=False), "q.glb")
    np.testing.assert_allclose(mesh.vertices, TETRA * 200)


@pytest.mark.parametrize(
    "extension", ["EXT_meshopt_compression", "EXT_mesh_gpu_instancing", "KHR_made_up"]
)
def test_required_extensions_we_cannot_honour_are_named(extension: str) -> None:
    header = {"asset": {"version": "2.0"}, "extensionsRequired": [extension], "meshes": []}
    with pytest.raises(MeshFileError) as error:
        read_mesh(glb(header, b""), "x.glb")
    assert error.value.status_code == 415
    assert f"This glTF needs {extension}, which is not supported" in str(error.value)


def test_extensions_that_only_change_looks_are_ignored() -> None:
    data = bytearray(quantized_tetra(5122, "<i2", 32767))
    header, chunk = glb_parts(bytes(data))
    header["extensionsRequired"] += ["KHR_materials_unlit", "KHR_texture_transform"]
    mesh = read_mesh(glb(header, chunk or b""), "x.glb")
    assert len(mesh.faces) == 4


def test_draco_is_decoded() -> None:
    source = trimesh.creation.icosphere(2)
    data = trimesh.Scene(source).export(file_type="glb", extension_draco=True)
    header, _ = glb_parts(data)
    assert "KHR_draco_mesh_compression" in header["extensionsRequired"]
    mesh = read_mesh(data, "ball.glb")
    assert len(mesh.faces) == len(source.faces)
    areas = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).area_faces
    assert areas.min() > 0  # never the placeholder zeros
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 1, atol=1e-3)
    assert any("Draco" in note for note in mesh.notes)


def test_draco_without_dracopy_is_a_415_naming_it(monkeypatch: pytest.MonkeyPatch) -> None:
    data = trimesh.Scene(trimesh.creation.box()).export(file_type="glb", extension_draco=True)
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "DracoPy" else real(name, *a)
    )
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, "box.glb")
    assert error.value.status_code == 415 and "DracoPy" in str(error.value)


def test_gltf_alone_with_an_external_bin_says_to_send_a_zip_or_glb() -> None:
    data = json.dumps(
        {"asset": {"version": "2.0"}, "buffers": [{"uri": "model.bin", "byteLength": 12}]}
    ).encode()
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, "x.gltf")
    assert error.value.status_code == 400
    assert "model.bin" in str(error.value) and "together in one request, or in a .zip" in str(
        error.value
    )
    assert ".glb" in str(error.value)


def test_real_draco_holding_quantized_positions() -> None:
    """gltf-transform's DenseSphere: int16 normalized positions inside Draco, node scale 0.93."""
    mesh = read_mesh(DATA / "gltf" / "DenseSphere.glb")
    assert len(mesh.faces) == 30720
    radii = np.linalg.norm(mesh.vertices, axis=1)
    assert radii.min() > 0.92 and radii.max() < 0.932  # not 32767 times that
    assert trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).volume > 0
    assert "Decoded 1 Draco-compressed (KHR_draco_mesh_compression) primitives." in mesh.notes


def test_a_gltf_read_from_a_path_finds_its_buffer_beside_it() -> None:
    mesh = read_mesh(DATA / "gltf" / "Box.gltf")
    assert mesh.faces.shape == (12, 3)
    report = mn.analyse(DATA / "gltf" / "BoxDraco.gltf")
    assert (report.faces, report.watertight, report.orientation) == (12, True, "outward")
    assert report.file.bytes == (DATA / "gltf" / "BoxDraco.gltf").stat().st_size


def test_a_gltf_sent_as_bytes_still_asks_for_its_buffer() -> None:
    data = (DATA / "gltf" / "Box.gltf").read_bytes()
    with pytest.raises(MeshFileError, match=r"separate buffer file Box0\.bin"):
        read_mesh(data, "Box.gltf")


def test_nodes_that_place_too_many_triangles_are_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    from mesh_normal.files import gltf_scene

    monkeypatch.setattr(gltf_scene, "MAX_TRIANGLES", 1000)  # DenseSphere places 30,720
    with pytest.raises(MeshFileError, match="nodes place more than 1,000 triangles"):
        read_mesh(DATA / "gltf" / "DenseSphere.glb")


def coloured_tetras(colors: list[np.ndarray | None], component: int = 5121) -> bytes:
    """One tetrahedron primitive per entry, each with ``COLOR_0`` (normalized integers of
    ``component``, or float32 when the array is) unless the entry is ``None``."""
    blob = b""
    views: list[dict[str, Any]] = []
    accessors: list[dict[str, Any]] = []
    primitives = []

    def add(data: bytes, accessor: dict[str, Any]) -> int:
        nonlocal blob
        blob = bytes(blob) + b"\0" * (-len(blob) % 4)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data
        accessors.append({"bufferView": len(views) - 1, **accessor})
        return len(accessors) - 1

    for color in colors:
        position = add(
            TETRA.astype("<f4").tobytes(),
            {"componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
        )
        indices = add(TETRA_FACES.tobytes(), {"componentType": 5123, "count": 12, "type": "SCALAR"})
        attributes = {"POSITION": position}
        if color is not None:
            floats = color.dtype.kind == "f"
            attributes["COLOR_0"] = add(
                color.tobytes(),
                {
                    "componentType": 5126 if floats else component,
                    "normalized": not floats,
                    "count": 4,
                    "type": f"VEC{color.shape[1]}",
                },
            )
        primitives.append({"attributes": attributes, "indices": indices})
    header = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": [{"primitives": primitives}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return glb(header, blob)


RGBA_BYTES = np.array([[255, 0, 0, 255], [0, 255, 0, 128], [0, 0, 255, 1], [7, 8, 9, 0]], np.uint8)


@pytest.mark.parametrize(
    ("colors", "component"),
    [
        (RGBA_BYTES, 5121),
        (RGBA_BYTES[:, :3].astype("<u2") * 257, 5123),
        (np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.25, 0.5, 0.75]], "<f4"), 5126),
    ],
    ids=["ubyte-rgba", "ushort-rgb", "float-rgb"],
)
def test_color_0_is_kept_in_its_accessors_type(colors: np.ndarray, component: int) -> None:
    mesh = read_mesh(coloured_tetras([colors], component), "c.glb")
    assert mesh.vertex_colors is not None
    assert mesh.vertex_colors.dtype == colors.dtype.newbyteorder("=")
    np.testing.assert_array_equal(mesh.vertex_colors, colors)
    np.testing.assert_array_equal(mesh.vertices, TETRA)  # positions untouched by the colours
    assert not any("quantized" in note for note in mesh.notes)  # colours are not "decoded"


def test_primitives_without_color_0_are_white() -> None:
    mesh = read_mesh(coloured_tetras([RGBA_BYTES[:, :3], None]), "c.glb")
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.uint8
    np.testing.assert_array_equal(mesh.vertex_colors[:4], RGBA_BYTES[:, :3])
    assert mesh.vertex_colors[4:].tolist() == [[255, 255, 255]] * 4
    assert "1 primitive without COLOR_0 is white in the vertex colours, as glTF draws it." in (
        mesh.notes
    )


def test_color_0_of_mixed_types_become_floats_and_rgb_gets_an_opaque_alpha() -> None:
    floats = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.25, 0.5, 0.75]], "<f4")
    mesh = read_mesh(coloured_tetras([RGBA_BYTES, floats]), "c.glb")
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.float32
    np.testing.assert_array_equal(mesh.vertex_colors[:4], (RGBA_BYTES / 255).astype(np.float32))
    np.testing.assert_array_equal(mesh.vertex_colors[4:, :3], floats)
    assert np.all(mesh.vertex_colors[4:, 3] == 1)


def test_a_real_glb_with_vertex_colours_matches_trimesh() -> None:
    path = DATA / "gltf" / "cube_vertex_colors.glb"
    mesh = read_mesh(path.read_bytes(), path.name)
    theirs = trimesh.load(path, force="mesh", process=False)
    assert mesh.vertex_colors is not None and mesh.vertex_colors.shape == (54, 3)
    assert mesh.vertex_colors.dtype == np.float32
    np.testing.assert_array_equal(mesh.vertices, theirs.vertices)
    # trimesh keeps them as bytes: the nearest to ours times 255
    np.testing.assert_allclose(
        mesh.vertex_colors * 255, theirs.visual.vertex_colors[:, :3], atol=0.5
    )


def test_a_gltf_without_meshes_says_so() -> None:
    """As trimesh's models/empty_nodes.glb: nodes, no meshes, no accessors."""
    header = {"asset": {"version": "2.0"}, "nodes": [{"name": "a"}], "scenes": [{"nodes": [0]}]}
    with pytest.raises(MeshFileError, match=r"^The glTF file holds no meshes\.$"):
        read_mesh(glb(header, b""), "empty_nodes.glb")


@pytest.mark.parametrize("draco", [False, True], ids=["plain", "draco"])
def test_trimesh_exported_vertex_colours_come_back(draco: bool) -> None:
    """trimesh writes COLOR_0 as normalized RGBA bytes, inside Draco too."""
    box = trimesh.creation.box()
    colors = np.zeros((8, 4), dtype=np.uint8)
    colors[:, 0], colors[:, 1], colors[:, 3] = np.arange(8) * 30, 7, 255
    box.visual.vertex_colors = colors
    data = trimesh.Scene(box).export(file_type="glb", extension_draco=draco)
    mesh = read_mesh(data, "box.glb")
    assert mesh.vertex_colors is not None and mesh.vertex_colors.dtype == np.uint8
    # Draco may reorder the vertices: each position keeps its colour
    order = [int(np.flatnonzero((box.vertices == point).all(axis=1))[0]) for point in mesh.vertices]
    np.testing.assert_array_equal(mesh.vertex_colors, colors[order])


def placed(triangles: int, nodes: int) -> dict[str, Any]:
    """A glTF header whose ``nodes`` root nodes each place one mesh of ``triangles`` triangles
    over three vertices. Its blob: :func:`placed_blob`."""
    header: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36 + 12 * triangles}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 12 * triangles},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5125, "count": 3 * triangles, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0, "translation": [index, 0, 0]} for index in range(nodes)],
        "scenes": [{"nodes": list(range(nodes))}],
    }
    return header


def placed_blob(triangles: int) -> bytes:
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32).tobytes()
    return corners + np.tile(np.arange(3, dtype=np.uint32), triangles).tobytes()


def test_nodes_placing_one_mesh_again_and_again_are_charged_before_trimesh_reads_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import trimesh.exchange.gltf

    def never(*_: object, **__: object) -> None:
        raise AssertionError("trimesh read the buffers before the charge")

    monkeypatch.setattr(trimesh.exchange.gltf, "load_gltf", never)
    header = placed(1000, 2000) | {"nodes": [{"mesh": 0}] * 2000}
    data = glb(header, placed_blob(1000))
    assert len(data) < 50_000
    with expanding(len(data)), pytest.raises(ExpansionTooLarge) as raised:
        read_mesh(data, "bomb.glb")
    assert raised.value.status_code == 413
    assert "the glTF file's nodes, placing 2,000,000 triangles, would take about" in str(
        raised.value
    )


def test_a_mesh_placed_by_several_nodes_is_read_once_per_node() -> None:
    data = glb(placed(2, 3), placed_blob(2))
    with expanding(len(data)):
        mesh = read_mesh(data, "instances.glb")
    assert len(mesh.faces) == 6
    assert sorted(set(mesh.vertices[:, 0])) == [0, 1, 2, 3]


def test_accessors_of_zeros_are_charged_by_their_declared_count() -> None:
    header = placed(1, 1)
    header["accessors"].append({"componentType": 5126, "count": 10**11, "type": "VEC3"})
    data = glb(header, placed_blob(1))
    with expanding(len(data)), pytest.raises(ExpansionTooLarge) as raised:
        read_mesh(data, "zeros.glb")
    assert "the glTF file's accessors would take about" in str(raised.value)


@pytest.mark.parametrize(
    ("children", "sentence"),
    [
        (
            {3: [5], 5: [3]},
            "The glTF file's node 3 is its own descendant (node 3 -> 5 -> 3); the glTF "
            "specification forbids cycles.",
        ),
        ({2: [2]}, "The glTF file's node 2 is its own descendant (node 2 -> 2);"),
        (
            {1: [2], 2: [4], 4: [1]},
            "The glTF file's node 1 is its own descendant (node 1 -> 2 -> 4 -> 1);",
        ),
        (
            {0: [5], 2: [5]},
            "The glTF file's node 5 has two parents (nodes 0 and 2); the glTF specification "
            "allows one.",
        ),
        ({0: [9]}, "The glTF file's node 0 is not an object whose children are among its 6 nodes."),
    ],
)
def test_nodes_must_form_trees(children: dict[int, list[int]], sentence: str) -> None:
    header = placed(1, 6)
    for node, found in children.items():
        header["nodes"][node]["children"] = found
    with pytest.raises(MeshFileError, match=re.escape(sentence)) as raised:
        read_mesh(glb(header, placed_blob(1)), "loop.glb")
    assert raised.value.status_code == 400


def test_a_deep_chain_of_nodes_is_answered_quickly() -> None:
    count = 100_000
    nodes = [{"children": [index + 1]} for index in range(count)] + [{"mesh": 0}]
    header = placed(1, 1) | {"nodes": nodes, "scenes": [{"nodes": [0]}]}
    header["nodes"][count // 2]["children"].append(0)  # the root becomes its own descendant
    start = time.perf_counter()
    loop = r"node 0 is its own descendant \(node 0 -> 1 -> 2 -> \.\.\. -> 50000 -> 0\)"
    with pytest.raises(MeshFileError, match=loop):
        read_mesh(glb(header, placed_blob(1)), "chain.glb")
    assert time.perf_counter() - start < 10


def broken(change: Callable[[dict[str, Any]], None]) -> bytes:
    header = placed(1, 1)
    change(header)
    return glb(header, placed_blob(1))


@pytest.mark.parametrize(
    ("data", "sentence"),
    [
        (
            broken(lambda h: h["bufferViews"][1].update(byteLength=400)),
            "The glTF buffer view 1 does not fit in its buffer of 48 bytes.",
        ),
        (
            broken(lambda h: h["bufferViews"][0].update(byteOffset=-12)),
            "The glTF buffer view 0 does not fit in its buffer of 48 bytes.",
        ),
        (
            broken(lambda h: h["bufferViews"][0].update(byteStride=0)),
            "The glTF buffer view 0 has a byteStride that is not above 0.",
        ),
        (
            broken(
                lambda h: (
                    h["bufferViews"][0].update(byteStride=12) or h["accessors"][0].update(count=30)
                )
            ),
            "The glTF accessor 0 runs past the end of its buffer view 0.",
        ),
        (
            broken(lambda h: h["accessors"][1].update(byteOffset=100)),
            "The glTF accessor 1 runs past the end of its buffer view 1.",
        ),
        (
            broken(lambda h: h["accessors"][1].update(type=["SCALAR"])),
            "The glTF accessor 1 has no valid count, componentType or type.",
        ),
        (broken(lambda h: h["accessors"].append(None)), "The glTF accessor 2 is not an object."),
    ],
)
def test_buffers_that_trimesh_would_assert_on_are_named(data: bytes, sentence: str) -> None:
    with pytest.raises(MeshFileError) as raised:
        read_mesh(data, "broken.glb")
    assert str(raised.value) == sentence
