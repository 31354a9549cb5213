"""What reading a file gives: :class:`LoadedMesh`, checked once for all formats by :func:`build`."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from mesh_normal.choices import MeshFormat, ReportFormat
from mesh_normal.files.errors import MeshFileError
from mesh_normal.mesh.checks import _coordinate_range, _index_range
from mesh_normal.types import FloatArray, IndexArray

if TYPE_CHECKING:
    from mesh_normal.mesh.checks import CheckedMesh

#: Most triangles a file may place once its instances (glTF nodes, 3MF components) are
#: expanded: a few kilobytes of placements must not become gigabytes of triangles.
MAX_TRIANGLES = 50_000_000

#: Describes item ``i`` (0-based) of the built arrays for an error sentence, e.g. "the face on
#: line 12". The default names the 0-based index.
Describe = Callable[[int], str]


@dataclass(frozen=True, slots=True)
class LoadedMesh:
    """A mesh as its file holds it, triangulated.

    Attributes
    ----------
    vertices : (n, 3) float64
        In file order; for STL, the welded corners in order of first appearance.
    faces : (m, 3) intp
        Triangles in file order; a polygon becomes ``k - 2`` consecutive fan triangles, and
        PLY triangle strips follow the faces as their triangles.
    format : str
        ``"stl"``, ``"obj"``, ``"ply"``, ``"off"``, ``"glb"``, ``"gltf"`` or ``"3mf"``;
        ``"memory"`` for a mesh made from arrays or another library's mesh (see
        :func:`~mesh_normal.analyse`).
    source_faces : int
        Faces as written in the file, before triangulation (and before skipping any with fewer
        than three corners); a PLY triangle strip record counts as one.
    file_face_normals : (m, 3) float64 or None
        Normals the file stores per face (STL facet normals, PLY face ``nx ny nz``), repeated
        for each triangle of a polygon; as stored, not normalised. ``None`` when the file has
        none, or when every STL facet normal is zero (exporters write zeros for "not given").
    file_vertex_normals : (n, 3) float64 or None
        PLY vertex ``nx ny nz``, OBJ ``vn`` when every vertex has one consistent ``vn``, glTF
        ``NORMAL`` (transformed with its node, normalised).
    file_corner_normals : (m, 3, 3) float64 or None
        OBJ ``f v//vn`` normals per corner of each triangle, when every corner has one.
    face_groups : (m,) intp or None
        The group of each triangle, an index into ``group_names``; ``None`` when the file has
        no groups (OBJ ``o`` and ``g``, ASCII STL ``solid`` blocks, glTF nodes' primitives and
        3MF build items make them).
    group_names : tuple of str or None
        Names of the groups, in order of their first triangle (each named group has one);
        ``None`` exactly when ``face_groups`` is.
    vertex_colors : (n, 3) or (n, 4) array or None
        Vertex ``red green blue [alpha]`` as the file stores them, with their type: integers
        span their type's whole range (``uint8`` 0-255, ``uint16`` 0-65535), floats 0-1. PLY
        properties in their declared type (``uchar``, ``float``, ...), OBJ ``v x y z r g b``
        (float64), OFF ``COFF`` (uint8 when written as integers, else float64), glTF
        ``COLOR_0`` (uint8, uint16 or float32 as its accessor stores it); read-only. ``None``
        when the file has none.
    face_colors : (m, 3) or (m, 4) array or None
        The colour of each triangle, by the same rules: PLY face ``red green blue [alpha]``,
        OFF colours after a face's corners, 3MF ``colorgroup`` and ``basematerials`` colours
        (uint8 RGBA); each triangle of a polygon has its polygon's colour. ``None`` when the
        file has none.
    notes : tuple of str
        Plain sentences about what reading did (welding, triangulation, skipped elements).
    unkept : tuple of str
        What the file holds that these arrays do not carry, so that no file written from them
        can keep it, in words: OBJ texture coordinates, materials and smoothing groups. Every
        writer of the mesh names them as left out.
    files : tuple of str
        For a ``.zip`` or several files: the names of those read, the mesh file first, then
        the files it named (a ``.gltf``'s buffers). Empty for one file read alone.
    from_reader : bool
        True when :func:`~mesh_normal.files.read_mesh` built it: its arrays passed the checks
        and are read-only, so :meth:`checked` need not check them again.
    distinct_points : bool
        True when the reader made every vertex a different position (an STL's weld of its
        corners), so that looking for vertices at one position again finds none. A mesh with
        other vertices (``dataclasses.replace``) must not keep it.
    """

    vertices: FloatArray
    faces: IndexArray
    format: ReportFormat
    source_faces: int
    file_face_normals: FloatArray | None = None
    file_vertex_normals: FloatArray | None = None
    file_corner_normals: FloatArray | None = None
    face_groups: IndexArray | None = None
    group_names: tuple[str, ...] | None = None
    vertex_colors: NDArray[np.generic] | None = None
    face_colors: NDArray[np.generic] | None = None
    notes: tuple[str, ...] = ()
    unkept: tuple[str, ...] = ()
    files: tuple[str, ...] = ()
    from_reader: bool = field(default=False, repr=False, compare=False)
    distinct_points: bool = field(default=False, repr=False, compare=False)

    def checked(self) -> CheckedMesh:
        """The mesh as the core takes it (:class:`~mesh_normal.mesh.checks.CheckedMesh`).

        A mesh the reader built is not checked again: :func:`build` checked its arrays by the
        rules of :func:`~mesh_normal.mesh.checks.check_mesh` and made them read-only. One built by
        hand is checked now, with a ``ValueError`` for the first problem, and so is a reader's
        mesh whose arrays were replaced by views in another layout (the compiled core reads
        C-contiguous rows only).
        """
        from mesh_normal.mesh.checks import CheckedMesh, checked_mesh, scaling  # numpy only

        laid_out = self.vertices.flags.c_contiguous and self.faces.flags.c_contiguous
        if not self.from_reader or not laid_out:
            return checked_mesh(self.vertices, self.faces)
        return CheckedMesh(self.vertices, self.faces, *scaling(self.vertices), self.distinct_points)


def build(
    file_format: MeshFormat,
    vertices: NDArray[np.floating],
    faces: NDArray[np.integer],
    *,
    source_faces: int,
    face_normals: NDArray[np.floating] | None = None,
    vertex_normals: NDArray[np.floating] | None = None,
    corner_normals: NDArray[np.floating] | None = None,
    face_groups: NDArray[np.integer] | None = None,
    group_names: Sequence[str] | None = None,
    vertex_colors: NDArray[np.generic] | None = None,
    face_colors: NDArray[np.generic] | None = None,
    notes: Sequence[str] = (),
    unkept: Sequence[str] = (),
    vertex: Describe | None = None,
    face: Describe | None = None,
    distinct_points: bool = False,
) -> LoadedMesh:
    """Check the arrays a reader produced and freeze them into a :class:`LoadedMesh`.

    Raises :class:`MeshFileError` for the first non-finite vertex, the first face with an index
    outside ``0 .. n - 1``, or a mesh without faces. ``vertex`` and ``face`` describe an item
    for that sentence (with a line number where the reader knows it). ``distinct_points``:
    the reader made no two vertices equal (see :class:`LoadedMesh`).
    """
    points = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    triangles = np.ascontiguousarray(faces, dtype=np.intp).reshape(-1, 3)
    _check_finite(points, vertex or _nth("vertex"))
    if len(triangles) == 0:
        raise MeshFileError(
            "The file holds no faces."
            if len(points)
            else "The file holds no vertices and no faces."
        )
    _check_indices(triangles, len(points), face or _nth("face"))
    for checked in (points, triangles):  # what was checked stays as it was checked
        checked.setflags(write=False)
    return LoadedMesh(
        vertices=points,
        faces=triangles,
        format=file_format,
        source_faces=source_faces,
        file_face_normals=_optional(face_normals, (len(triangles), 3)),
        file_vertex_normals=_optional(vertex_normals, (len(points), 3)),
        file_corner_normals=_optional(corner_normals, (len(triangles), 3, 3)),
        face_groups=_groups(face_groups, group_names, len(triangles)),
        group_names=None if group_names is None else tuple(group_names),
        vertex_colors=_colors(vertex_colors, len(points), "vertices"),
        face_colors=_colors(face_colors, len(triangles), "triangles"),
        notes=tuple(notes),
        unkept=tuple(unkept),
        from_reader=True,
        distinct_points=distinct_points,
    )


def _nth(kind: str) -> Describe:
    return lambda index: f"{kind} {index:,} (counting from 0)"


def first_bad_vertex(points: NDArray[np.floating]) -> int | None:
    """The index of the first row (of 3 coordinates, in order) with a NaN or infinite
    coordinate, or ``None``. ``points`` is (k, 3), or (f, c, 3) (its f * c rows in order)."""
    if not points.size:
        return None
    if points.dtype == np.float64 and points.flags.c_contiguous:
        extremes = _coordinate_range(np.asarray(points, np.float64))
        if math.isfinite(extremes[0]) and math.isfinite(extremes[1]):
            return None
    elif np.isfinite(points.min()) and np.isfinite(points.max()):
        return None  # NaN propagates through min and max: two fast passes settle most files
    finite = np.isfinite(points).all(axis=-1).ravel()
    return None if finite.all() else int(np.argmin(finite))


def _check_finite(points: FloatArray, describe: Describe) -> None:
    row = first_bad_vertex(points)
    if row is not None:
        value = points[row][~np.isfinite(points[row])][0]
        raise MeshFileError(
            f"The coordinates of {describe(row)} include {value}, which is not a finite number."
        )


def _check_indices(triangles: IndexArray, count: int, describe: Describe) -> None:
    low, high = (int(value) for value in _index_range(triangles))
    if low >= 0 and high < count:
        return
    bad = (triangles < 0) | (triangles >= count)
    row, column = np.argwhere(bad)[0]
    index = int(triangles[row, column])
    if index < 0:
        raise MeshFileError(
            f"{_capital(describe(int(row)))} refers to vertex {index}; vertex "
            "indices cannot be negative."
        )
    there = f"the file has only {count:,}" if count else "the file has none"
    raise MeshFileError(
        f"{_capital(describe(int(row)))} refers to vertex {index:,} (counting from 0), but {there}."
    )


def _capital(text: str) -> str:
    return text[:1].upper() + text[1:]


def _optional(array: NDArray[np.floating] | None, shape: tuple[int, ...]) -> FloatArray | None:
    if array is None:
        return None
    result = np.ascontiguousarray(array, dtype=np.float64)
    if result.shape != shape:  # a reader's bug, not the file's: fail loudly in tests
        raise AssertionError(f"file normals of shape {result.shape}, expected {shape}")
    return result


def _groups(
    groups: NDArray[np.integer] | None, names: Sequence[str] | None, count: int
) -> IndexArray | None:
    """The group index of every triangle, read-only; a reader's mistake fails loudly."""
    if groups is None or names is None:
        if groups is not None or names is not None:
            raise AssertionError("face_groups and group_names come together")
        return None
    if len(names) == 1 and np.shape(groups) == (count,) and not np.any(groups):
        # One object (a single glTF primitive, STL solid or OBJ group): every face is in group
        # 0, a read-only view of one zero rather than 8 bytes a face.
        return np.broadcast_to(np.intp(0), (count,))
    result = np.ascontiguousarray(groups, dtype=np.intp)
    if result.shape != (count,) or (count and not 0 <= result.min() <= result.max() < len(names)):
        raise AssertionError(f"face groups of shape {result.shape} for {len(names)} names")
    result.setflags(write=False)
    return result


def _colors(
    colors: NDArray[np.generic] | None, count: int, what: str
) -> NDArray[np.generic] | None:
    """Colours read-only, in the type the file stores them; a reader's mistake fails loudly."""
    if colors is None:
        return None
    result = np.array(colors, order="C")  # a copy: freezing it leaves the caller's alone
    if result.ndim != 2 or result.shape[0] != count or result.shape[1] not in (3, 4):
        raise AssertionError(f"colours of shape {result.shape} for {count} {what}")
    if result.dtype.kind not in "uif":
        raise AssertionError(f"colours of type {result.dtype}")
    result.setflags(write=False)
    return result
