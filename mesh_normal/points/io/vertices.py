"""Clouds of vertices: a PLY file's vertex element, and the vertices of any mesh file.

A PLY file is read by :func:`mesh_normal.files.ply.read_elements` (its faces, if any, are not
used: "mesh vertices"). Other mesh files go through :func:`~mesh_normal.files.read_mesh`, which
refuses a file without faces; an OBJ file without faces (``v`` lines alone, as some scanners
write clouds) is read here line by line instead: ``v x y z [r g b]`` and, when there are as
many, ``vn`` lines as the normals of the ``v`` lines in order.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.io.cloud import PointCloud, colors_uint8, make_cloud

_OBJ_ELEMENT = re.compile(rb"^[ \t]*(?:f|l|p|curv|surf)[ \t]", re.MULTILINE)


def mesh_vertices(data: bytes, found: str) -> PointCloud:
    """The vertices of a mesh file (read by :func:`~mesh_normal.files.read_mesh`), with the
    vertex normals and colours it stores."""
    from mesh_normal.files.read import read_mesh

    if found == "obj" and not _OBJ_ELEMENT.search(data):
        return obj_vertices(data)
    mesh = read_mesh(data, f"mesh.{found}")
    colors = mesh.vertex_colors
    notes = [*mesh.notes]
    triangles = f"{len(mesh.faces):,} triangle" + ("" if len(mesh.faces) == 1 else "s")
    notes.append(f"The file is a mesh: its {triangles} are not used.")
    return make_cloud(
        mesh.format,
        mesh.vertices,
        normals=mesh.file_vertex_normals,
        colors=None if colors is None else colors_uint8(colors[:, :3]),
        source_kind="mesh vertices",
        notes=notes,
        describe=lambda row: f"vertex {row:,} (counting from 0)",
    )


#: PLY vertex properties a cloud uses.
_PLY_USED = frozenset({"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"})


def read_ply_points(data: bytes) -> PointCloud:
    """The vertex element of a PLY file, with ``nx ny nz`` and ``red green blue`` if there;
    faces (when there are any) are not used, and ``source_kind`` says "mesh vertices"."""
    from mesh_normal.files.ply import read_elements

    elements, notes = read_elements(data)
    vertex = next((element for element in elements if element.name == "vertex"), None)
    if vertex is None or not {"x", "y", "z"} <= vertex.data.keys():
        raise MeshFileError("The PLY file has no vertex element with x, y and z.")
    columns = vertex.data
    declared = dict(vertex.scalars)
    normals = _stack(columns, ("nx", "ny", "nz"), declared)
    colors = _stack(columns, ("red", "green", "blue"), declared)
    unused = [name for name in vertex.order if name not in _PLY_USED]
    if unused:
        notes.append(f"The file's vertex {', '.join(unused)} values are not used.")
    faces = sum(element.count for element in elements if element.name in ("face", "tristrips"))
    others = [f"{e.name} ({e.count:,})" for e in elements if e.name not in ("vertex",) and e.count]
    if others:
        notes.append(f"The file's other elements are not used: {', '.join(others)}.")
    return make_cloud(
        "ply",
        _stack(columns, ("x", "y", "z"), declared),  # type: ignore[arg-type]
        normals=normals,
        colors=None if colors is None else colors_uint8(colors),
        source_kind="mesh vertices" if faces else "points",
        notes=notes,
        describe=lambda row: f"vertex {row:,} (counting from 0)",
    )


def _stack(
    columns: dict[str, object], names: tuple[str, ...], declared: dict[str, str]
) -> NDArray[np.generic] | None:
    """The named scalar columns side by side in their common declared type, or ``None``."""
    if not all(name in declared and name in columns for name in names):
        return None
    kind = np.result_type(*(np.dtype(declared[name]) for name in names))
    return np.stack([np.asarray(columns[name]).astype(kind) for name in names], axis=1)


def obj_vertices(data: bytes) -> PointCloud:
    """The ``v`` lines of an OBJ file without faces, with its ``vn`` lines as their normals
    when there are as many, and ``v x y z r g b`` colours."""
    rows: list[list[bytes]] = []
    lines: list[int] = []
    normals: list[list[bytes]] = []
    normal_lines: list[int] = []
    for number, line in enumerate(data.splitlines(), 1):
        words = line.split()
        if words and words[0] == b"v":
            rows.append(words[1:])
            lines.append(number)
        elif words and words[0] == b"vn":
            normals.append(words[1:])
            normal_lines.append(number)
    widths = {len(row) for row in rows}
    if len(widths) > 1 or not widths <= {3, 4, 6, 7}:
        row = next(
            i for i, r in enumerate(rows) if len(r) != len(rows[0]) or len(r) not in (3, 4, 6, 7)
        )
        raise MeshFileError(
            f"The OBJ vertex on line {lines[row]:,} has {len(rows[row])} numbers; every "
            "vertex takes x y z, with r g b after them or not."
        )
    values = _floats(rows, lines)
    notes = []
    if values.shape[1] == 4:
        notes.append("The file's vertex weights (w) are not used.")
    stored = None
    if normals and len(normals) == len(rows):
        if any(len(normal) != 3 for normal in normals):
            row = next(i for i, normal in enumerate(normals) if len(normal) != 3)
            raise MeshFileError(f"The OBJ normal on line {normal_lines[row]:,} is not 3 numbers.")
        stored = _floats(normals, normal_lines)
    elif normals:
        notes.append(
            f"The file's {len(normals):,} vn normals are not used: without faces they "
            f"follow the {len(rows):,} vertices only when there are as many."
        )
    colors = values[:, 3:6] if values.shape[1] == 6 else None
    return make_cloud(
        "obj",
        values[:, :3] if len(rows) else np.zeros((0, 3)),
        normals=stored,
        colors=None if colors is None else colors_uint8(colors),
        notes=notes,
        describe=lambda row: f"the vertex on line {lines[row]:,}",
    )


def _floats(rows: list[list[bytes]], lines: list[int]) -> NDArray[np.float64]:
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), -1)
    except ValueError:
        for line, row in zip(lines, rows, strict=False):
            for word in row:
                try:
                    float(word)
                except ValueError:
                    raise MeshFileError(
                        f"Line {line:,} has {word[:40].decode('latin-1')!r} where a number "
                        "should be."
                    ) from None
        raise AssertionError("a row that is not a number, found again") from None
