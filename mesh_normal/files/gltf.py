"""GLB and glTF through trimesh's glTF reader, flattened into one mesh.

Every triangle primitive of every node of the scene is taken, in the order trimesh walks the
scene graph, with its node's world transform applied (a mesh used by two nodes appears twice).
``NORMAL`` attributes, when every primitive has them, become the vertex normals, transformed by
the inverse transpose of the transform and normalised. ``COLOR_0`` becomes the vertex colours
in its accessor's type (normalized bytes or shorts stay integers, floats 0-1), inside Draco too;
a primitive without one is white, as glTF draws it. A node whose transform mirrors (negative
determinant) has its triangles' winding reversed, as the glTF specification asks, so fronts
stay fronts. Point and line primitives are skipped with a note.

Before trimesh reads it, :mod:`mesh_normal.files.gltf_buffers` refuses required extensions we
cannot honour, decodes quantized accessors and gathers the buffers: a ``.gltf`` sent alone must
embed them (``data:`` URIs); one with separate ``.bin`` files comes in a ``.zip``. Then
:mod:`mesh_normal.files.gltf_scene` refuses node cycles and nodes with two parents, and charges
what the scene places against the upload's expansion budget.
"""

from __future__ import annotations

import dataclasses
import io
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.gltf_buffers import (
    PACKED_URI,
    Resolver,
    check_extensions,
    glb_parts,
    gltf_header,
    packed_gltf,
)
from mesh_normal.files.gltf_scene import check_scene
from mesh_normal.files.loaded import LoadedMesh, build


def read_glb(data: bytes) -> LoadedMesh:
    """Read binary glTF (see the module docstring)."""
    header, chunk = glb_parts(data)
    return _read(header, chunk, None, "glb")


def read_gltf(data: bytes, resolve: Resolver | None = None) -> LoadedMesh:
    """Read JSON glTF; ``resolve`` finds the files its URIs name (from a ``.zip``), if any."""
    return _read(gltf_header(data), None, resolve, "gltf")


def _read(
    header: dict[str, Any],
    chunk: memoryview | None,
    resolve: Resolver | None,
    file_format: Literal["glb", "gltf"],
) -> LoadedMesh:
    from trimesh.exchange.gltf import load_gltf  # imported on first use: trimesh is slow

    check_extensions(header)
    packed = packed_gltf(header, chunk, resolve)
    del chunk  # the upload's view: the packed buffer holds what is needed of it
    if not header.get("meshes"):  # trimesh would fail on the missing accessors
        raise MeshFileError("The glTF file holds no meshes.")
    check_scene(header)  # before trimesh makes the arrays: nodes may place a mesh many times
    draco, quantized = packed.draco, packed.quantized
    scene = load_gltf(
        io.BytesIO(packed.header),
        resolver={PACKED_URI: memoryview(packed.blob)},
        merge_primitives=False,
        skip_materials=True,
    )
    del packed
    mesh = _flatten(scene, file_format)
    del scene
    notes = []
    if draco:
        notes.append(f"Decoded {draco:,} Draco-compressed (KHR_draco_mesh_compression) primitives.")
    if quantized:
        notes.append(f"Decoded {quantized:,} quantized (normalized integer) glTF accessors.")
    return dataclasses.replace(mesh, notes=(*notes, *mesh.notes)) if notes else mesh


def _world_transforms(scene: dict[str, Any]) -> list[tuple[NDArray[np.float64], str, str]]:
    """(world transform, geometry name, node name) for every node that holds a geometry, in
    graph order."""
    edges = scene.get("graph") or []
    world = {scene.get("base_frame", "world"): np.eye(4)}
    placed: list[tuple[NDArray[np.float64], str, str]] = []
    pending = list(edges)
    for _ in range(len(edges) + 1):  # parents normally come first; a few passes otherwise
        waiting = []
        for edge in pending:
            parent = edge.get("frame_from")
            if parent not in world:
                waiting.append(edge)
                continue
            matrix = np.asarray(edge.get("matrix", np.eye(4)), dtype=np.float64)
            world[edge["frame_to"]] = world[parent] @ matrix
            if edge.get("geometry") is not None:
                placed.append((world[edge["frame_to"]], edge["geometry"], str(edge["frame_to"])))
        if not waiting or len(waiting) == len(pending):
            break
        pending = waiting
    return placed


def _flatten(scene: dict[str, Any], file_format: Literal["glb", "gltf"]) -> LoadedMesh:
    geometry = scene.get("geometry") or {}
    parts: list[tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.float64] | None]] = []
    colors: list[NDArray[Any] | None] = []
    names: list[str] = []  # one group per primitive placed, named by its node: the objects
    skipped = mirrored = 0
    for transform, name, node in _world_transforms(scene):
        kwargs = geometry.get(name) or {}
        if "faces" not in kwargs or "vertices" not in kwargs:
            skipped += 1
            continue
        faces = np.asarray(kwargs["faces"], dtype=np.intp).reshape(-1, 3)
        vertices = np.asarray(kwargs["vertices"], dtype=np.float64).reshape(-1, 3)
        linear = transform[:3, :3]
        if np.linalg.det(linear) < 0:
            faces, mirrored = faces[:, ::-1], mirrored + 1
        normals = kwargs.get("vertex_normals")
        if normals is not None:
            normals = _unit(
                np.asarray(normals, dtype=np.float64).reshape(-1, 3) @ np.linalg.inv(linear)
            )  # row vectors: n @ inv(A) is inv(A).T @ n
        if not np.array_equal(transform, np.eye(4)):  # else no copy of every vertex
            vertices = vertices @ linear.T + transform[:3, 3]
        parts.append((vertices, faces, normals))
        found = kwargs.get("vertex_colors")
        colors.append(None if found is None else np.asarray(found).reshape(len(vertices), -1))
        names.append(node)
    notes = []
    if skipped:
        notes.append(f"Skipped {skipped:,} point or line primitives: only triangles are read.")
    if mirrored:
        notes.append(f"Reversed the winding of {mirrored:,} mirrored primitives, as glTF asks.")
    if len(parts) > 1:
        notes.append(f"Joined {len(parts):,} primitives with their node transforms applied.")
    if not parts:
        raise MeshFileError("The glTF file holds no triangle meshes.")
    vertices, faces, normals = _joined(parts)
    groups = (
        np.broadcast_to(np.intp(0), (len(faces),))  # one group: never 8 bytes a face
        if len(parts) == 1
        else np.repeat(np.arange(len(parts)), [len(part[1]) for part in parts])
    )
    vertex_colors = _joined_colors(colors, [len(part[0]) for part in parts], notes)
    return build(
        file_format,
        vertices,
        faces,
        source_faces=len(faces),
        vertex_normals=normals,
        vertex_colors=vertex_colors,
        face_groups=groups,
        group_names=names,
        notes=notes,
    )


def _joined(
    parts: list[tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.float64] | None]],
) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.float64] | None]:
    """The primitives' vertices, faces (renumbered) and normals (if all have them), joined."""
    if len(parts) == 1:  # as they are: a copy of a large mesh is most of the reader's memory
        vertices, faces, normals = parts[0]
        return (
            vertices,
            faces,
            normals if normals is None or len(normals) == len(vertices) else None,
        )
    offsets = np.cumsum([0] + [len(part[0]) for part in parts])
    vertices = np.concatenate([part[0] for part in parts])
    faces = np.concatenate([part[1] + offset for part, offset in zip(parts, offsets, strict=False)])
    normals = None
    if all(part[2] is not None and len(part[2]) == len(part[0]) for part in parts):
        normals = np.concatenate([part[2] for part in parts])
    return vertices, faces, normals


def _joined_colors(
    colors: list[NDArray[Any] | None], sizes: list[int], notes: list[str]
) -> NDArray[Any] | None:
    """One ``COLOR_0`` array for the joined vertices, or ``None`` when no primitive has one.

    glTF multiplies the material's colour by ``COLOR_0``, so a primitive without one is white:
    it gets the type's full value. Colours keep their accessor's type (uint8, uint16 or float32)
    when all share it, else all become float32 0-1; RGB gets an opaque alpha beside RGBA.
    """
    if all(color is None for color in colors):
        return None
    given = [color for color in colors if color is not None]
    width = max(color.shape[1] for color in given)
    kinds = {color.dtype for color in given}
    kind = kinds.pop() if len(kinds) == 1 else np.dtype(np.float32)
    if kind.kind not in "uf" or width not in (3, 4):
        notes.append("The glTF COLOR_0 attributes were not read: they are not RGB or RGBA colours.")
        return None
    full = np.iinfo(kind.str).max if kind.kind == "u" else 1.0
    joined = np.full((sum(sizes), width), full, dtype=kind)
    start = 0
    for color, size in zip(colors, sizes, strict=True):
        if color is not None:
            joined[start : start + size, : color.shape[1]] = _scaled(color, kind)
        start += size
    if missing := sum(color is None for color in colors):
        notes.append(
            f"{missing:,} primitive{'s' if missing > 1 else ''} without COLOR_0 "
            f"{'are' if missing > 1 else 'is'} white in the vertex colours, as glTF draws "
            f"{'them' if missing > 1 else 'it'}."
        )
    return joined


def _scaled(color: NDArray[Any], kind: np.dtype[Any]) -> NDArray[Any]:
    """``color`` in ``kind``: integers to float32 0-1 when the types differ."""
    if color.dtype == kind:
        return color
    if color.dtype.kind == "u":
        return (color / float(np.iinfo(color.dtype.str).max)).astype(kind)
    return color.astype(kind)


def _unit(vectors: NDArray[np.float64]) -> NDArray[np.float64]:
    lengths = np.linalg.norm(vectors, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(lengths > 0, vectors / lengths, 0.0)


def write_glb(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_colors: NDArray[np.generic] | None = None,
    normals: NDArray[np.float64] | None = None,
    normals_kind: str | None = None,
) -> bytes:
    """Binary glTF: see :func:`mesh_normal.files.glb_write.write_glb` (the writer lives in
    its own module; the format table looks for it here, beside the reader)."""
    from mesh_normal.files.glb_write import write_glb as glb

    return glb(points, triangles, vertex_colors, normals, normals_kind)
