"""3MF: a zip package (OPC) whose model part (``3D/3dmodel.model``) is XML, read as one mesh.

Parsed here rather than by trimesh, whose 3MF reader needs lxml and merges what we keep apart.
Every build ``<item>`` is placed in file order; an object made of ``<components>`` places each
component's object in turn, its 3x4 transform composed with the item's, so an object used twice
appears twice. Each object's ``<vertex>`` elements keep their file order and its
``<triangle v1 v2 v3>`` their winding; a placement whose transform mirrors (negative
determinant) has its winding reversed, so faces that pointed outwards still do.

Colours: a triangle's ``pid`` and ``p1`` (or its object's ``pid`` and ``pindex``) naming a
``<basematerials>`` ``displaycolor`` or a ``<m:colorgroup>`` ``color`` (``#RRGGBB[AA]``)
become its face colour, uint8 RGBA. They are kept when every placed triangle has one; a
triangle with a colour per corner (``p2``, ``p3``) keeps its first corner's, and a note says so.

The package is opened with the guards of :mod:`mesh_normal.files.archive` (member count, names
outside the archive), and everything it expands into is charged to the input's one budget
(:mod:`mesh_normal.files.expansion`): the parts as they unpack, the XML as it is parsed, the
triangles the build places before they are placed. XML that declares a DTD is refused, in any
encoding (:mod:`defusedxml`), which rules out entity expansion. The model is parsed as a
stream: each ``<vertex>`` and ``<triangle>`` becomes numbers as it is read and is dropped, so
the tree keeps only the small elements around them.
"""

from __future__ import annotations

import functools
import io
import posixpath
import xml.etree.ElementTree as ET
import zipfile
from array import array
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

import numpy as np
from defusedxml import DefusedXmlException
from defusedxml.ElementTree import iterparse
from numpy.typing import NDArray

from mesh_normal.files.archive import UNPACK_ERRORS, open_zip, opened_zip, unpack
from mesh_normal.files.errors import MeshFileError, unsupported
from mesh_normal.files.expansion import ExpansionTooLarge, charge, megabytes
from mesh_normal.files.loaded import MAX_TRIANGLES, LoadedMesh, build

#: Where a 3MF package keeps its model unless ``_rels/.rels`` says otherwise.
MODEL_PART = "3D/3dmodel.model"
#: The content type ``[Content_Types].xml`` gives the model part.
MODEL_TYPE = "application/vnd.ms-package.3dmanufacturing-3dmodel+xml"
_MODEL_RELATION = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"
#: Deepest nesting of components (a cycle would be infinite).
MAX_DEPTH = 32

#: Memory per byte of XML, charged before it is parsed: the numbers of its vertices and
#: triangles (24 bytes each in arrays, from at least 28 bytes of XML each).
XML_PER_BYTE = 1
#: Memory of each element the parse keeps (all but vertices and triangles; a triangle's colour
#: attributes count as one): tracemalloc counts 330 to 430 bytes for an element with
#: one to four attributes, and the object or component it becomes.
KEPT_BYTES = 640
#: Kept elements charged at a time.
KEPT_BATCH = 4096
#: Memory of each triangle and each vertex the build places, in the mesh's arrays and the
#: report's: about 250 bytes a triangle, with its share of vertices.
PLACED_TRIANGLE_BYTES = 250
PLACED_VERTEX_BYTES = 100

#: Where objects and meshes are, by local names below the root, and what the elements below
#: a mesh hold.
_OBJECT = ["resources", "object"]
_MESH = ["resources", "object", "mesh"]
_LEAVES = {"vertices": "vertex", "triangles": "triangle"}
_COLOUR_KEYS = ("pid", "p1", "p2", "p3")


def is_3mf(data: bytes) -> bool:
    """Whether a zip archive's bytes are a 3MF package (its members name the model part)."""
    try:
        with open_zip(data) as archive:
            names = {info.filename.lower().lstrip("/") for info in archive.infolist()}
            if MODEL_PART.lower() in names:
                return True
            types = next(
                (i for i in archive.infolist() if i.filename == "[Content_Types].xml"), None
            )
            if types is None:
                return False
            with archive.open(types) as file:  # bounded: a content-types part is tiny
                return MODEL_TYPE.encode() in file.read(1 << 16)
    except (MeshFileError, *UNPACK_ERRORS, OSError):  # a damaged zip is no 3MF; the reader says why
        return False


@dataclass(frozen=True, slots=True)
class _Object:
    """One ``<object>``: a mesh, or components ``(object id, 4x4 transform)``."""

    number: int
    vertices: NDArray[np.float64] | None
    triangles: NDArray[np.intp] | None
    components: tuple[tuple[str, NDArray[np.float64]], ...] = ()
    #: (t, 4) uint8 RGBA of each triangle, None without one; (t,) whether it has one
    colors: NDArray[np.uint8] | None = None
    colored: NDArray[np.bool_] | None = None
    corner_colored: int = 0  # triangles whose corners have colours of their own


def read_3mf(data: bytes) -> LoadedMesh:
    """Read a 3MF package (see the module docstring)."""
    root, meshes = _parse(_model_bytes(data))
    palettes = _palettes(root)
    objects = {
        obj.get("id", ""): _object(obj, number, palettes, meshes)
        for number, obj in enumerate(root.iterfind("{*}resources/{*}object"), start=1)
    }
    items = list(root.iterfind("{*}build/{*}item"))
    if not items:
        raise MeshFileError("The 3MF file's build names no objects to make.")
    # Counted before anything is placed: components that place components can multiply a few
    # kilobytes into billions of placements.
    memo: dict[str, tuple[int, int]] = {}
    costs = [_cost(objects, item.get("objectid", ""), memo, 0) for item in items]
    triangles, vertices = sum(cost[0] for cost in costs), sum(cost[1] for cost in costs)
    if triangles > MAX_TRIANGLES:
        raise MeshFileError(f"The 3MF file's build makes more than {MAX_TRIANGLES:,} triangles.")
    charge(
        triangles * PLACED_TRIANGLE_BYTES + vertices * PLACED_VERTEX_BYTES,
        f"the 3MF file's build, placing {triangles:,} triangles and {vertices:,} vertices,",
    )
    placed: list[tuple[_Object, NDArray[np.float64]]] = []
    owner: list[int] = []  # the build item of each placed mesh: one object of the report each
    triangles = 0
    for index, item in enumerate(items):
        for obj, transform in _placements(objects, item.get("objectid", ""), _transform(item), 0):
            placed.append((obj, transform))
            owner.append(index)
            triangles += len(obj.triangles) if obj.triangles is not None else 0
            if triangles > MAX_TRIANGLES:
                raise MeshFileError(
                    f"The 3MF file's build makes more than {MAX_TRIANGLES:,} triangles."
                )
    names = [
        f"build item {i + 1} (object {item.get('objectid', '')})" for i, item in enumerate(items)
    ]
    return _join(placed, len(items), owner, names)


def _model_bytes(data: bytes) -> bytes:
    with opened_zip(data, "3MF file") as (archive, members):
        by_lower = {name.lower(): info for name, info in members.items()}  # OPC: no case
        part = _model_part_name(archive, by_lower)
        info = by_lower.get(part.lower())
        if info is None:
            raise MeshFileError(f"The 3MF file has no model part ({part}).")
        return unpack(archive, info, "3MF file")


def _model_part_name(archive: zipfile.ZipFile, members: dict[str, zipfile.ZipInfo]) -> str:
    """The model part ``_rels/.rels`` names, else the usual ``3D/3dmodel.model``."""
    rels = members.get("_rels/.rels")
    if rels is None:
        return MODEL_PART
    try:
        root, _ = _parse(unpack(archive, rels, "3MF file"))
    except ExpansionTooLarge:
        raise
    except MeshFileError:
        return MODEL_PART  # a broken relationships part: the model may still be where usual
    for relation in root.iterfind("{*}Relationship"):
        if relation.get("Type") == _MODEL_RELATION and relation.get("Target"):
            return posixpath.normpath(relation.get("Target", "").lstrip("/"))
    return MODEL_PART


@dataclass(slots=True)
class _Leaves:
    """The numbers of one ``<mesh>``'s vertices and triangles, and the colour attributes of
    the triangles that have some (by row), read as the parser passes them."""

    vertices: array[float] = field(default_factory=lambda: array("d"))
    triangles: array[int] = field(default_factory=lambda: array("q"))
    colours: dict[int, dict[str, str]] = field(default_factory=dict)


def _parse(xml: bytes) -> tuple[ET.Element, dict[ET.Element, _Leaves]]:
    """The XML's tree without its vertices and triangles, and those of each ``<mesh>``; XML
    that declares a DTD or entities is refused, whatever its encoding."""
    charge(len(xml) * XML_PER_BYTE, f"parsing the 3MF file's XML ({megabytes(len(xml))})")
    try:
        return _streamed(xml)
    except DefusedXmlException:
        raise MeshFileError(
            "The 3MF file's XML declares a DTD (or entities), which this reader refuses."
        ) from None
    except ET.ParseError as error:
        raise MeshFileError(f"The 3MF file's XML is broken: {error}.") from None
    except MeshFileError:
        raise
    except ValueError:  # expat's "multi-byte encodings are not supported"
        raise MeshFileError(
            "The 3MF file's XML is in an encoding this reader does not support."
        ) from None


def _streamed(xml: bytes) -> tuple[ET.Element, dict[ET.Element, _Leaves]]:
    meshes: dict[ET.Element, _Leaves] = {}
    names: list[str] = []  # the local names of the open elements, root first
    opened: list[ET.Element] = []
    leaves: _Leaves | None = None  # the mesh whose <vertices> or <triangles> is open
    leaf = ""  # "vertex" or "triangle": what that element holds
    objects = kept = 0
    root = None
    for event, element in iterparse(io.BytesIO(xml), ("start", "end"), forbid_dtd=True):
        if event == "start":
            names.append(element.tag.rpartition("}")[2])
            opened.append(element)
            if len(names) == 3 and names[1:] == _OBJECT:
                objects += 1
            elif len(names) == 5 and names[1:4] == _MESH and names[4] in _LEAVES:
                leaves, leaf = meshes.setdefault(opened[3], _Leaves()), _LEAVES[names[4]]
            continue
        name = names.pop()
        opened.pop()
        root = element
        if leaves is not None and len(names) == 5 and name == leaf:
            kept += _leaf(leaves, element, leaf, objects)
            opened[-1].clear()  # the <vertices> or <triangles> keeps none of them
            continue
        if len(names) == 4:
            leaves = None
        kept += 1
        if kept >= KEPT_BATCH:
            charge(kept * KEPT_BYTES, "the 3MF file's XML elements")
            kept = 0
    assert root is not None  # the parser raises for XML without an element
    return root, meshes


def _leaf(leaves: _Leaves, element: ET.Element, tag: str, number: int) -> int:
    """Add a ``<vertex>`` or ``<triangle>`` to its mesh's numbers; 1 when its colour
    attributes are kept, else 0."""
    attrib = element.attrib
    vertex = tag == "vertex"
    keys = ("x", "y", "z") if vertex else ("v1", "v2", "v3")
    target: array[float] | array[int] = leaves.vertices if vertex else leaves.triangles
    row = len(target) // 3
    kind = float if vertex else int
    try:
        values = (kind(attrib[keys[0]]), kind(attrib[keys[1]]), kind(attrib[keys[2]]))
    except (KeyError, ValueError) as error:
        raise MeshFileError(
            f"The {tag} {row:,} (counting from 0) of object {number} has a missing or "
            f"non-numeric {'/'.join(keys)} attribute."
        ) from error
    try:
        target.extend(values)  # type: ignore[arg-type]
    except OverflowError:
        raise MeshFileError(
            f"The triangle {row:,} (counting from 0) of object {number} refers to a vertex "
            "number too large to be one."
        ) from None
    if vertex:
        return 0
    colour = {key: attrib[key] for key in _COLOUR_KEYS if key in attrib}
    if colour:
        leaves.colours[row] = colour
    return len(colour) > 0


#: Colour resources by id: the text of each one's colours, in order (read when a triangle
#: uses one, so that a broken colour nobody uses breaks nothing).
Palettes = dict[str, list[str]]


def _palettes(root: ET.Element) -> Palettes:
    """Every ``<basematerials>`` and ``<m:colorgroup>`` of the resources, by id."""
    palettes: Palettes = {}
    for tag, child, key in (
        ("basematerials", "base", "displaycolor"),
        ("colorgroup", "color", "color"),
    ):
        for group in root.iterfind(f"{{*}}resources/{{*}}{tag}"):
            palettes[group.get("id", "")] = [
                item.get(key, "") for item in group.iterfind(f"{{*}}{child}")
            ]
    return palettes


@functools.cache
def _rgba(text: str) -> tuple[int, int, int, int]:
    """``#RRGGBB`` or ``#RRGGBBAA`` as four bytes."""
    digits = text.strip().lstrip("#")
    try:
        if len(digits) not in (6, 8):
            raise ValueError(digits)
        value = bytes.fromhex(digits + "FF" * (len(digits) == 6))
    except ValueError:
        raise MeshFileError(
            f"The 3MF file has a colour that is not #RRGGBB[AA]: {text[:40]!r}."
        ) from None
    return value[0], value[1], value[2], value[3]


def _object(
    obj: ET.Element, number: int, palettes: Palettes, meshes: dict[ET.Element, _Leaves]
) -> _Object:
    mesh = obj.find("{*}mesh")
    if mesh is None:
        if any(
            key.endswith("}path")
            for component in obj.iterfind("{*}components/{*}component")
            for key in component.attrib
        ):
            raise unsupported(
                "The 3MF file's components refer to other model parts (the production "
                "extension), which are not supported."
            )
        components = tuple(
            (component.get("objectid", ""), _transform(component))
            for component in obj.iterfind("{*}components/{*}component")
        )
        return _Object(number, None, None, components)
    leaves = meshes.get(mesh, _Leaves())
    points = np.frombuffer(leaves.vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.frombuffer(leaves.triangles, dtype=np.int64).astype(np.intp).reshape(-1, 3)
    _check_indices(faces, len(points), number)
    colors, colored, corners = _triangle_colors(obj, len(faces), leaves.colours, palettes, number)
    return _Object(number, points, faces, colors=colors, colored=colored, corner_colored=corners)


def _triangle_colors(
    obj: ET.Element,
    count: int,
    attributes: dict[int, dict[str, str]],
    palettes: Palettes,
    number: int,
) -> tuple[NDArray[np.uint8], NDArray[np.bool_], int]:
    """Each of the ``count`` triangles' colour from its ``pid``/``p1`` (its colour
    ``attributes``, by row) or its object's ``pid``/``pindex``, whether it has one, and how
    many have a colour per corner."""
    colors = np.zeros((count, 4), dtype=np.uint8)
    colored = np.zeros(count, dtype=bool)
    corners = 0
    default_group, default_index = obj.get("pid"), obj.get("pindex")
    # Without an object's colour, only the triangles with attributes can have one.
    rows: Iterable[int] = attributes if default_group is None else range(count)
    for row in rows:
        triangle = attributes.get(row, {})
        group = triangle.get("pid", default_group)
        index = triangle.get("p1", default_index if "pid" not in triangle else None)
        palette = palettes.get(group or "")
        if palette is None or index is None:
            continue
        try:
            position = int(index)
            if position < 0:
                raise IndexError(position)
            text = palette[position]
        except (ValueError, IndexError):
            raise MeshFileError(
                f"Triangle {row:,} (counting from 0) of object {number} names colour "
                f"{index[:20]!r} of group {group!r}, which has {len(palette)}."
            ) from None
        colors[row] = _rgba(text)
        colored[row] = True
        corners += any(triangle.get(key, index) != index for key in ("p2", "p3"))
    return colors, colored, corners


def _check_indices(faces: NDArray[np.intp], count: int, number: int) -> None:
    """Indices are the object's own: checked before the objects are joined."""
    if not len(faces) or (faces.min() >= 0 and faces.max() < count):
        return
    row, column = np.argwhere((faces < 0) | (faces >= count))[0]
    raise MeshFileError(
        f"Triangle {int(row):,} (counting from 0) of object {number} refers to vertex "
        f"{int(faces[row, column]):,}, but the object has {count:,} vertices."
    )


def _transform(element: ET.Element) -> NDArray[np.float64]:
    """The 4x4 column-vector matrix of a ``transform="m00 m01 ... m32"`` attribute.

    3MF multiplies row vectors: ``[x y z 1] @ M`` with ``M`` the twelve numbers as four rows
    of three, so the linear part is the transpose of the first nine read row by row.
    """
    text = element.get("transform")
    matrix = np.eye(4)
    if text is None:
        return matrix
    try:
        values = np.array([float(value) for value in text.split()], dtype=np.float64)
    except ValueError:
        values = np.empty(0)
    if values.shape != (12,) or not np.isfinite(values).all():
        raise MeshFileError(f"The 3MF file has a transform that is not 12 numbers: {text[:80]}.")
    matrix[:3, :3] = values[:9].reshape(3, 3).T
    matrix[:3, 3] = values[9:]
    return matrix


def _object_at(objects: dict[str, _Object], object_id: str, depth: int) -> _Object:
    """The object ``object_id`` names at nesting ``depth``, or the sentence why there is none."""
    obj = objects.get(object_id)
    if obj is None:
        raise MeshFileError(f"The 3MF file refers to object {object_id[:40]!r}, which it lacks.")
    if depth > MAX_DEPTH:
        raise MeshFileError(f"The 3MF file nests components deeper than {MAX_DEPTH} (a cycle?).")
    return obj


def _cost(
    objects: dict[str, _Object], object_id: str, memo: dict[str, tuple[int, int]], depth: int
) -> tuple[int, int]:
    """The triangles (each placement at least one) and vertices ``object_id`` places, counted
    once per object."""
    if object_id in memo:
        return memo[object_id]
    obj = _object_at(objects, object_id, depth)
    if obj.triangles is not None and obj.vertices is not None:
        triangles, vertices = max(len(obj.triangles), 1), len(obj.vertices)
    else:
        costs = [_cost(objects, child, memo, depth + 1) for child, _ in obj.components]
        triangles, vertices = sum(cost[0] for cost in costs), sum(cost[1] for cost in costs)
    # bounded: the sums stay small integers
    memo[object_id] = (min(triangles, MAX_TRIANGLES + 1), min(vertices, 3 * MAX_TRIANGLES + 1))
    return memo[object_id]


def _placements(
    objects: dict[str, _Object], object_id: str, transform: NDArray[np.float64], depth: int
) -> Iterator[tuple[_Object, NDArray[np.float64]]]:
    """Every mesh object ``object_id`` places, with its world transform, depth first."""
    obj = _object_at(objects, object_id, depth)
    if obj.triangles is not None:
        yield obj, transform
        return
    for child, matrix in obj.components:
        yield from _placements(objects, child, transform @ matrix, depth + 1)


def _join(
    placed: list[tuple[_Object, NDArray[np.float64]]],
    items: int,
    owner: list[int],
    names: list[str],
) -> LoadedMesh:
    parts: list[tuple[NDArray[np.float64], NDArray[np.intp]]] = []
    mirrored = 0
    notes: list[str] = []
    face_colors = _placed_colors([obj for obj, _ in placed], notes)
    for obj, transform in placed:
        assert obj.vertices is not None and obj.triangles is not None
        linear = transform[:3, :3]
        faces = obj.triangles
        if np.linalg.det(linear) < 0:
            faces, mirrored = faces[:, ::-1], mirrored + 1
        parts.append((obj.vertices @ linear.T + transform[:3, 3], faces))
    if not parts:
        raise MeshFileError("The 3MF file's build holds no meshes.")
    offsets = np.cumsum([0] + [len(part[0]) for part in parts])
    vertices = np.concatenate([part[0] for part in parts])
    faces = np.concatenate([part[1] + offset for part, offset in zip(parts, offsets, strict=False)])
    if len(parts) > 1:
        notes.append(
            f"Joined {len(parts):,} 3MF meshes from {items:,} build items, "
            "with their transforms applied."
        )
    if mirrored:
        notes.append(
            f"Reversed the winding of {mirrored:,} mirrored 3MF meshes, so fronts stay fronts."
        )
    # Build items numbered by their first triangle; items that make no triangle get no group.
    item_of_face = np.repeat(owner, [len(part[1]) for part in parts])
    used, groups = np.unique(item_of_face, return_inverse=True)
    return build(
        "3mf",
        vertices,
        faces,
        source_faces=len(faces),
        face_groups=groups.ravel(),
        group_names=[names[i] for i in used.tolist()],
        face_colors=face_colors,
        notes=notes,
    )


def _placed_colors(objects: list[_Object], notes: list[str]) -> NDArray[np.uint8] | None:
    """The face colours of the placed meshes joined, when every triangle has one."""
    colored = [obj.colored for obj in objects if obj.colored is not None]
    have = sum(int(flags.sum()) for flags in colored)
    if not have:
        return None
    total = sum(len(flags) for flags in colored)
    if have < total:
        notes.append(
            f"The 3MF colours were not kept: {total - have:,} of {total:,} triangles have no "
            "colour of their own or of their object (a texture, say, or none given)."
        )
        return None
    if corners := sum(obj.corner_colored for obj in objects):
        notes.append(
            f"{corners:,} 3MF triangles have a colour per corner; each keeps its first "
            "corner's as its face colour."
        )
    return np.concatenate([obj.colors for obj in objects if obj.colors is not None])
