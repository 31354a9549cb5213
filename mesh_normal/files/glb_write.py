"""Writing binary glTF (GLB): one node, one mesh, one triangle primitive.

glTF stores one normal per vertex (``NORMAL``), so face and corner normals are written by
splitting vertices: each distinct pair of vertex and normal becomes one glTF vertex, in the
order of the original vertices (a smooth vertex stays one, a vertex on a crease becomes one a
side). Coordinates and normals are float32, as glTF holds them; vertex colours go to
``COLOR_0``: RGBA bytes or shorts as normalized integers, anything else as float32 0-1 (glTF
aligns each attribute on 4 bytes, which three bytes are not).
"""

from __future__ import annotations

import json
import struct

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.formats import MAKER

#: glTF's codes: component types, and the targets of vertex and index buffer views.
FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
_TYPES = {1: "SCALAR", 3: "VEC3", 4: "VEC4"}
_COMPONENTS = {np.dtype(np.float32): FLOAT, np.dtype(np.uint8): UNSIGNED_BYTE}
_COMPONENTS[np.dtype(np.uint16)] = UNSIGNED_SHORT
_COMPONENTS[np.dtype(np.uint32)] = UNSIGNED_INT


def split_vertices(
    triangles: NDArray[np.intp], normals: NDArray[np.float64], kind: str
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """Vertices split so that every corner's normal is its vertex's.

    Parameters
    ----------
    triangles : (m, 3) intp
    normals : (n, 3), (m, 3) or (m, 3, 3) float64
        Vertex, face or corner normals, as ``kind`` says.

    Returns
    -------
    source : (k,) intp
        The original vertex of each new vertex, ascending (``arange(n)`` for vertex normals).
    faces : (m, 3) intp
        The triangles over the new vertices.
    vertex_normals : (k, 3) float64
    """
    if kind == "vertex":
        return np.arange(len(normals), dtype=np.intp), triangles, normals
    corners = np.repeat(normals[:, None, :], 3, axis=1) if kind == "face" else normals
    flat = np.ascontiguousarray(corners.reshape(-1, 3))
    # The vertex and the normal's exact bits as one key: np.unique sorts by vertex first.
    keys = np.concatenate([triangles.reshape(-1, 1).astype(np.int64), flat.view(np.int64)], 1)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    source = triangles.reshape(-1)[first].astype(np.intp)
    return source, inverse.reshape(-1, 3).astype(np.intp), flat[first]


def write_glb(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_colors: NDArray[np.generic] | None = None,
    normals: NDArray[np.float64] | None = None,
    normals_kind: str | None = None,
) -> bytes:
    """A GLB file of the mesh (see the module docstring).

    Parameters
    ----------
    points : (n, 3) float64
        Checked; beyond float32's range is a :class:`MeshFileError` (422).
    triangles : (m, 3) intp
    vertex_colors : (n, 3) or (n, 4), optional
    normals : (n, 3), (m, 3) or (m, 3, 3) float64, optional
        Vertex, face or corner normals, as ``normals_kind`` says.
    """
    largest = float(np.abs(points).max(initial=0.0))
    if largest > float(np.finfo(np.float32).max):
        raise MeshFileError(
            f"Coordinates up to {largest:.3g} do not fit in GLB, which stores "
            "32-bit floats (up to about 3.4e38); choose PLY or OBJ.",
            422,
        )
    source: NDArray[np.intp] | None = None  # None: every vertex as it is, no gathered copy
    faces, vertex_normals = triangles, None
    if normals is not None and normals_kind is not None:
        source, faces, vertex_normals = split_vertices(triangles, normals, normals_kind)
    positions = (points if source is None else points[source]).astype(np.float32)
    attributes: list[tuple[str, NDArray[np.generic]]] = [("POSITION", positions)]
    if vertex_normals is not None:
        attributes.append(("NORMAL", vertex_normals.astype(np.float32)))
    if vertex_colors is not None:
        colors = vertex_colors if source is None else vertex_colors[source]
        attributes.append(("COLOR_0", _glb_colors(colors)))
    return _glb(attributes, faces.astype(np.uint32).reshape(-1))


def _glb_colors(colors: NDArray[np.generic]) -> NDArray[np.generic]:
    if colors.dtype in (np.uint8, np.uint16) and colors.shape[1] == 4:
        return colors
    from mesh_normal.files.obj import unit_colors

    return unit_colors(colors).astype(np.float32)


def _glb(attributes: list[tuple[str, NDArray[np.generic]]], indices: NDArray[np.uint32]) -> bytes:
    """The GLB container: the JSON chunk, then one binary buffer of every array.

    The arrays go into the file as they are (byte views, joined once): no copy of each."""
    pieces: list[bytes | memoryview] = []
    length = 0  # of the binary buffer so far
    views: list[dict[str, int]] = []
    accessors: list[dict[str, object]] = []
    named: dict[str, int] = {}
    for name, array in [*attributes, ("indices", indices)]:
        data = np.ascontiguousarray(array).reshape(-1).view(np.uint8).data
        target = ELEMENT_ARRAY_BUFFER if name == "indices" else ARRAY_BUFFER
        views.append({"buffer": 0, "byteOffset": length, "byteLength": len(data), "target": target})
        pieces += [data, b"\0" * (-len(data) % 4)]
        length += len(data) + -len(data) % 4
        accessor: dict[str, object] = {
            "bufferView": len(views) - 1,
            "componentType": _COMPONENTS[array.dtype],
            "count": len(array),
            "type": _TYPES[1 if array.ndim == 1 else array.shape[1]],
        }
        if name == "COLOR_0" and array.dtype != np.float32:
            accessor["normalized"] = True
        if name == "POSITION" and len(array):  # glTF requires the bounds of positions
            accessor["min"] = array.min(axis=0).tolist()
            accessor["max"] = array.max(axis=0).tolist()
        named[name] = len(accessors)
        accessors.append(accessor)
    primitive = {
        "attributes": {name: named[name] for name, _ in attributes},
        "indices": named["indices"],
        "mode": 4,
    }
    header = {
        "asset": {"version": "2.0", "generator": MAKER},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [primitive]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": length}],
    }
    text = json.dumps(header, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + length
    return b"".join(
        [
            struct.pack("<4sII", b"glTF", 2, total),
            struct.pack("<I4s", len(text), b"JSON"),
            text,
            struct.pack("<I4s", length, b"BIN\0"),
            *pieces,
        ]
    )
