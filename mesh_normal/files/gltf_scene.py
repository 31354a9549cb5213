"""A glTF's node tree checked, and what its scene makes charged, before trimesh makes an array.

The glTF specification makes the nodes disjoint strict trees: no node is its own descendant
and none has two parents (the Khronos validator's ``NODE_LOOP`` and ``NODE_PARENT_OVERRIDE``
errors). Both are refused with a sentence naming the nodes; trimesh would place a node's
faces once for each way to reach it. A mesh may still be placed by many nodes (instancing,
which the specification allows): a few kilobytes of nodes can place one mesh millions of
times. So what the scene makes is counted from the accessors' declared counts, which trimesh
holds the arrays to, and charged against the upload's expansion budget
(:mod:`mesh_normal.files.expansion`) before trimesh reads the buffers.
"""

from __future__ import annotations

from collections import Counter
from typing import Any, TypeGuard

from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.expansion import charge
from mesh_normal.files.gltf_buffers import ITEM_BYTES, WIDTH
from mesh_normal.files.loaded import MAX_TRIANGLES

#: Memory per placed triangle and per placed vertex in the job (trimesh's arrays, the joined
#: copy, the report): with the usual two triangles a vertex, the 250 bytes a placed triangle
#: takes in a mesh report.
TRIANGLE_BYTES = 200
VERTEX_BYTES = 100

_TRIANGLES, _STRIP = 4, 5


def check_scene(header: dict[str, Any]) -> None:
    """Refuse a node tree the specification forbids; charge what the scene will make.

    Raises
    ------
    MeshFileError
        A node that is its own descendant or has two parents (400), a scene that places more
        than :data:`~mesh_normal.files.loaded.MAX_TRIANGLES` triangles, or
        :class:`~mesh_normal.files.expansion.ExpansionTooLarge` (413).
    """
    children = _children(header)
    _check_tree(children)
    charge(_copied_accessors(header), "the glTF file's accessors")
    triangles, cost = _placed(header, children)
    if triangles > MAX_TRIANGLES:
        raise MeshFileError(f"The glTF file's nodes place more than {MAX_TRIANGLES:,} triangles.")
    charge(cost, f"the glTF file's nodes, placing {triangles:,} triangles,")


def _is_index(value: object, size: int) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value < size


def _list(header: dict[str, Any], key: str) -> list[Any]:
    """``header[key]`` when it is a list, else empty (trimesh refuses what is not)."""
    found = header.get(key)
    return found if isinstance(found, list) else []


def _children(header: dict[str, Any]) -> list[list[int]]:
    """Each node's children, checked to be indices of nodes."""
    nodes = header.get("nodes") or []
    if not isinstance(nodes, list):
        raise MeshFileError("The glTF file's nodes are not a list.")
    children = []
    for index, node in enumerate(nodes):
        found = node.get("children") or [] if isinstance(node, dict) else None
        if not isinstance(found, list) or not all(_is_index(child, len(nodes)) for child in found):
            raise MeshFileError(
                f"The glTF file's node {index} is not an object whose children are among its "
                f"{len(nodes):,} nodes."
            )
        children.append(found)
    return children


def _check_tree(children: list[list[int]]) -> None:
    """Refuse a node with two parents, then a node that is its own descendant."""
    parent: dict[int, int] = {}
    for index, found in enumerate(children):
        for child in found:
            if parent.setdefault(child, index) != index:
                raise MeshFileError(
                    f"The glTF file's node {child} has two parents (nodes {parent[child]} and "
                    f"{index}); the glTF specification allows one."
                )
    done: set[int] = set()
    for start in range(len(children)):
        path: list[int] = []  # start, its parent, its grandparent...
        on_path: set[int] = set()
        node: int | None = start
        while node is not None and node not in done:
            if node in on_path:
                loop = path[path.index(node) :]
                raise MeshFileError(
                    f"The glTF file's node {node} is its own descendant ({_shown(loop)}); "
                    "the glTF specification forbids cycles."
                )
            path.append(node)
            on_path.add(node)
            node = parent.get(node)
        done.update(path)


def _shown(loop: list[int]) -> str:
    """``node 3 -> 5 -> 3``: a loop of ancestors (each the parent of the one before) shown
    from its first node down through its descendants."""
    down = [loop[0], *reversed(loop[1:]), loop[0]]
    if len(down) > 8:
        down = [*down[:3], "...", *down[-2:]]  # type: ignore[list-item]
    return "node " + " -> ".join(str(node) for node in down)


def _placements(header: dict[str, Any], children: list[list[int]]) -> Counter[int]:
    """How many times each node is placed, walking the scene as trimesh does: each
    (parent, child) edge once, from the scene's roots."""
    scenes, chosen = header.get("scenes"), header.get("scene", 0)
    scene = scenes[chosen] if isinstance(scenes, list) and _is_index(chosen, len(scenes)) else {}
    roots = scene.get("nodes") or [] if isinstance(scene, dict) else []
    roots = roots if isinstance(roots, list) else []
    pending = [(-1, root) for root in roots if _is_index(root, len(children))]
    seen: set[tuple[int, int]] = set()
    placed: Counter[int] = Counter()
    while pending:
        edge = pending.pop()
        if edge not in seen:
            seen.add(edge)
            placed[edge[1]] += 1
            pending.extend((edge[1], child) for child in children[edge[1]])
    return placed


def _placed(header: dict[str, Any], children: list[list[int]]) -> tuple[int, int]:
    """The triangles the scene places and the bytes its primitives take: each primitive once
    for each node placing its mesh, once at least (trimesh reads every primitive)."""
    meshes, nodes = _list(header, "meshes"), _list(header, "nodes")
    uses: Counter[int] = Counter()
    for node, count in _placements(header, children).items():
        mesh = nodes[node].get("mesh")
        if _is_index(mesh, len(meshes)):
            uses[mesh] += count
    accessors = _list(header, "accessors")
    triangles = cost = 0
    for index, mesh in enumerate(meshes):
        primitives = mesh.get("primitives") if isinstance(mesh, dict) else None
        for primitive in primitives if isinstance(primitives, list) else []:
            faces, vertices = _primitive_size(primitive, accessors)
            triangles += faces * uses[index]
            cost += (TRIANGLE_BYTES * faces + VERTEX_BYTES * vertices) * max(uses[index], 1)
    return triangles, cost


def _primitive_size(primitive: object, accessors: list[Any]) -> tuple[int, int]:
    """(triangles, vertices) of a primitive by its accessors' counts; points and lines make
    no triangles, and trimesh skips fans."""
    if not isinstance(primitive, dict) or not isinstance(primitive.get("attributes"), dict):
        return 0, 0
    vertices = _count(accessors, primitive["attributes"].get("POSITION"))
    corners = _count(accessors, primitive["indices"]) if "indices" in primitive else vertices
    mode = primitive.get("mode", _TRIANGLES)
    faces = corners // 3 if mode == _TRIANGLES else max(corners - 2, 0) if mode == _STRIP else 0
    return faces, vertices


def _count(accessors: list[Any], index: object) -> int:
    """An accessor's declared count; 0 when it is not there (trimesh refuses those)."""
    if _is_index(index, len(accessors)) and isinstance(accessors[index], dict):
        count = accessors[index].get("count")
        if _is_index(count, 2**63):
            return count
    return 0


def _copied_accessors(header: dict[str, Any]) -> int:
    """The bytes of the accessors trimesh makes new arrays for rather than views of the
    buffer: those with no buffer view (zeros of their declared count), sparse ones, and
    those of a view with a stride."""
    accessors, views = _list(header, "accessors"), _list(header, "bufferViews")
    total = 0
    for index, accessor in enumerate(accessors):
        if not isinstance(accessor, dict):
            continue
        view = accessor.get("bufferView")
        strided = _is_index(view, len(views)) and "byteStride" in (views[view] or ())
        if view is None or strided or "sparse" in accessor:
            kind = accessor.get("componentType")
            item = ITEM_BYTES.get(kind, 4) if isinstance(kind, int) else 4
            total += _count(accessors, index) * WIDTH.get(str(accessor.get("type")), 1) * item
    return total
