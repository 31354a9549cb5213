"""3MF: a zip package (OPC) whose model part (``3D/3dmodel.model``) is XML, read as one mesh.

Parsed here rather than by trimesh, whose 3MF reader needs lxml and merges what we keep apart.
Every build ``<item>`` is placed in file order; an object made of ``<components>`` places each
component's object in turn, its 3x4 transform composed with the item's, so an object used twice
appears twice. Each object's ``<vertex>`` elements keep their file order and its
``<triangle v1 v2 v3>`` their winding; a placement whose transform mirrors (negative
determinant) has its winding reversed, so faces that pointed outwards still do.

The package is opened with the guards of :mod:`mesh_normal.files.archive` (member count, unpack
limit, names outside the archive); documents with a DTD are refused, which rules out entity
expansion.
"""

from __future__ import annotations

import io
import posixpath
import re
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.archive import UNPACK_ERRORS, Budget, opened_zip
from mesh_normal.files.errors import MeshFileError, unsupported
from mesh_normal.files.loaded import MAX_TRIANGLES, LoadedMesh, build

#: Where a 3MF package keeps its model unless ``_rels/.rels`` says otherwise.
MODEL_PART = "3D/3dmodel.model"
#: The content type ``[Content_Types].xml`` gives the model part.
MODEL_TYPE = "application/vnd.ms-package.3dmanufacturing-3dmodel+xml"
_MODEL_RELATION = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"
#: Deepest nesting of components (a cycle would be infinite).
MAX_DEPTH = 32

_DOCTYPE = re.compile(rb"<!DOCTYPE|<!ENTITY", re.IGNORECASE)


def is_3mf(data: bytes) -> bool:
    """Whether a zip archive's bytes are a 3MF package (its members name the model part)."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
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
    except (*UNPACK_ERRORS, OSError):  # a damaged zip (names that are not UTF-8 too) is no 3MF
        return False


@dataclass(frozen=True, slots=True)
class _Object:
    """One ``<object>``: a mesh, or components ``(object id, 4x4 transform)``."""

    number: int
    vertices: NDArray[np.float64] | None
    triangles: NDArray[np.intp] | None
    components: tuple[tuple[str, NDArray[np.float64]], ...] = ()


def read_3mf(data: bytes) -> LoadedMesh:
    """Read a 3MF package (see the module docstring)."""
    root = _parse(_model_bytes(data))
    objects = {
        obj.get("id", ""): _object(obj, number)
        for number, obj in enumerate(root.iterfind("{*}resources/{*}object"), start=1)
    }
    items = list(root.iterfind("{*}build/{*}item"))
    if not items:
        raise MeshFileError("The 3MF file's build names no objects to make.")
    # Counted before anything is placed: components that place components can multiply a few
    # kilobytes into billions of placements.
    memo: dict[str, int] = {}
    if sum(_cost(objects, item.get("objectid", ""), memo, 0) for item in items) > MAX_TRIANGLES:
        raise MeshFileError(f"The 3MF file's build makes more than {MAX_TRIANGLES:,} triangles.")
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
    with opened_zip(data, "The 3MF file could not be opened as a zip") as (
        archive,
        members,
        budget,
    ):
        by_lower = {name.lower(): info for name, info in members.items()}  # OPC: no case
        part = _model_part_name(archive, by_lower, budget)
        info = by_lower.get(part.lower())
        if info is None:
            raise MeshFileError(f"The 3MF file has no model part ({part}).")
        return budget.read(archive, info)


def _model_part_name(
    archive: zipfile.ZipFile, members: dict[str, zipfile.ZipInfo], budget: Budget
) -> str:
    """The model part ``_rels/.rels`` names, else the usual ``3D/3dmodel.model``."""
    rels = members.get("_rels/.rels")
    if rels is None:
        return MODEL_PART
    try:
        root = _parse(budget.read(archive, rels))
    except MeshFileError:
        return MODEL_PART  # a broken relationships part: the model may still be where usual
    for relation in root.iterfind("{*}Relationship"):
        if relation.get("Type") == _MODEL_RELATION and relation.get("Target"):
            return posixpath.normpath(relation.get("Target", "").lstrip("/"))
    return MODEL_PART


def _parse(xml: bytes) -> ET.Element:
    if _DOCTYPE.search(xml[:4096]) or _DOCTYPE.search(xml):
        raise MeshFileError("The 3MF file's XML declares a DTD, which this reader refuses.")
    try:
        return ET.fromstring(xml)
    except ET.ParseError as error:
        raise MeshFileError(f"The 3MF file's XML is broken: {error}.") from error


def _object(obj: ET.Element, number: int) -> _Object:
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
    vertices = _numbers(mesh.iterfind("{*}vertices/{*}vertex"), ("x", "y", "z"), float, number)
    triangles = _numbers(mesh.iterfind("{*}triangles/{*}triangle"), ("v1", "v2", "v3"), int, number)
    points = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(triangles, dtype=np.intp).reshape(-1, 3)
    _check_indices(faces, len(points), number)
    return _Object(number, points, faces)


def _numbers(
    elements: Iterator[ET.Element],
    names: tuple[str, str, str],
    kind: Callable[[str], float],
    number: int,
) -> list[float]:
    """The attributes ``names`` of every element, flat, as ``kind``; one sentence if one lacks."""
    values: list[float] = []
    tag = "vertex" if kind is float else "triangle"
    for index, element in enumerate(elements):
        try:
            values.extend(kind(element.attrib[name]) for name in names)
        except (KeyError, ValueError) as error:
            raise MeshFileError(
                f"The {tag} {index:,} (counting from 0) of object {number} has a missing or "
                f"non-numeric {'/'.join(names)} attribute."
            ) from error
    return values


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


def _cost(objects: dict[str, _Object], object_id: str, memo: dict[str, int], depth: int) -> int:
    """The triangles ``object_id`` places (each placement at least one), counted once per object."""
    if object_id in memo:
        return memo[object_id]
    obj = _object_at(objects, object_id, depth)
    if obj.triangles is not None:
        cost = max(len(obj.triangles), 1)
    else:
        cost = sum(_cost(objects, child, memo, depth + 1) for child, _ in obj.components)
    memo[object_id] = min(cost, MAX_TRIANGLES + 1)  # bounded: the sums stay small integers
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
    notes = []
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
        notes=notes,
    )
