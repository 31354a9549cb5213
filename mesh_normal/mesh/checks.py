"""Input conversion and checks, done once at the edge: :class:`CheckedMesh`.

Every public function of the core takes raw arrays (and checks them, with a clear
``ValueError`` for the first problem), a :class:`CheckedMesh` made by :func:`checked_mesh`,
which it trusts, or a mesh as people hold it (:func:`checked_mesh` converts it): a
``(vertices, faces)`` tuple, what :func:`~mesh_normal.files.read_mesh` returns, a
``trimesh.Trimesh``, an Open3D ``TriangleMesh`` or a PyVista ``PolyData`` of triangles. Those
are recognised by their attributes, so that none of their libraries is imported here. A caller
that runs several functions on one mesh checks it once. :func:`held_points` does the same for
the point functions.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import NoReturn, Protocol, TypeAlias, TypeVar

import numpy as np
from numpy.typing import ArrayLike

import mesh_normal._core as _core
from mesh_normal.types import FloatArray, IndexArray

ArrayType = TypeVar("ArrayType", bound=np.ndarray)


@dataclass(frozen=True, slots=True, eq=False)
class CheckedMesh:
    """A mesh whose arrays passed :func:`check_mesh`, with the scaling the kernels use.

    The core trusts it without checking again, and it holds the caller's arrays where they
    already had the right type and layout (no copy): do not change them afterwards. An index
    changed out of range after the check would be read out of bounds by the compiled kernels.

    Attributes
    ----------
    vertices : (n, 3) float64
        C-contiguous, finite; the input itself when it already was.
    faces : (m, 3) intp
        C-contiguous, every index in ``0 .. n - 1``.
    points : (n, 3) float64
        What the kernels read: ``vertices``, or a copy scaled by ``2**-scale`` when every
        coordinate is below 2**-1022 (see :func:`scaling`).
    factor : float
        The kernels multiply each coordinate they read by this (exact).
    scale : int
        The power of two that brings the largest |coordinate| into [0.5, 1).
    distinct_points : bool
        True when no two vertices are at one position (a reader's weld made them so; see
        :class:`~mesh_normal.files.LoadedMesh`): the search for equal points is skipped.
    """

    vertices: FloatArray
    faces: IndexArray
    points: FloatArray
    factor: float
    scale: int
    distinct_points: bool = False

    def __post_init__(self) -> None:
        # Read-only views (the caller's arrays stay as they were): nothing that is given the
        # checked mesh writes into them.
        vertices = read_only(self.vertices)
        points = vertices if self.points is self.vertices else read_only(self.points)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "faces", read_only(self.faces))


def read_only(array: ArrayType) -> ArrayType:
    """``array`` if it is read-only, else a read-only view of it."""
    if not array.flags.writeable:
        return array
    view = array.view()
    view.flags.writeable = False
    return view


class _VerticesFaces(Protocol):
    """What :func:`~mesh_normal.files.read_mesh` returns, a ``trimesh.Trimesh``."""

    @property
    def vertices(self) -> ArrayLike: ...
    @property
    def faces(self) -> ArrayLike: ...


class _VerticesTriangles(Protocol):
    """An Open3D ``TriangleMesh`` (its ``Vector3dVector`` and ``Vector3iVector``)."""

    @property
    def vertices(self) -> ArrayLike: ...
    @property
    def triangles(self) -> ArrayLike: ...


class _PointsFaces(Protocol):
    """A PyVista ``PolyData``: ``faces`` is its flat cell array ``[3, a, b, c, 3, ...]``."""

    @property
    def points(self) -> ArrayLike: ...
    @property
    def faces(self) -> ArrayLike: ...


#: A mesh as people hold it, taken without faces beside it (see :func:`checked_mesh`).
HeldMesh: TypeAlias = (
    "CheckedMesh | tuple[ArrayLike, ArrayLike] | _VerticesFaces | _VerticesTriangles | _PointsFaces"
)

#: What a mesh function takes, for the sentence that refuses anything else.
MESH_FORMS = (
    "vertices and faces arrays, a (vertices, faces) tuple, what read_mesh returns, a "
    "CheckedMesh, a trimesh.Trimesh, an Open3D TriangleMesh or a PyVista PolyData of triangles"
)


def checked_mesh(
    vertices: ArrayLike | HeldMesh, faces: ArrayLike | None = None, *, ranged: bool = True
) -> CheckedMesh:
    """Convert and check a mesh once (see :func:`check_mesh` for the rules).

    Parameters
    ----------
    vertices : (n, 3) float64, or a mesh
        Finite coordinates (any real dtype); or, without ``faces``, a mesh as people hold
        it: a ``(vertices, faces)`` tuple, what :func:`~mesh_normal.files.read_mesh` returns
        (not checked again), a ``CheckedMesh`` (returned as it is), a ``trimesh.Trimesh``, an
        Open3D ``TriangleMesh`` or a PyVista ``PolyData`` whose faces are all triangles.
    faces : (m, 3) int
        Indices into ``vertices`` (any integer dtype); only with raw vertices.
    ranged : bool
        False: the faces' indices are not checked against the vertices here. Only for a
        caller whose kernel checks every index it reads before it reads the vertex, and
        calls :func:`refuse_faces` for the error when one is out of range (one pass over the
        faces fewer).

    Returns
    -------
    CheckedMesh
        The converted arrays and their scaling; the input arrays themselves where they were
        already float64 and intp in C order, so they must not change while it is in use.

    Raises
    ------
    TypeError
        For a mesh given with ``faces``, raw vertices without them, or anything else that is
        not a mesh (the sentence says what can be passed).
    ValueError
        For the first problem of the arrays.
    """
    if faces is None:
        return held_mesh(vertices)
    kind = _mesh_kind(vertices)
    if kind is not None:
        raise TypeError(f"{kind} holds its faces: pass it without faces.")
    points, extremes = _as_vertices(vertices)  # type: ignore[arg-type]
    indices = check_faces(faces, len(points), ranged=ranged)
    return CheckedMesh(points, indices, *scaling(points, extremes))


def _mesh_kind(value: object) -> str | None:
    """How a sentence names ``value`` if it is a mesh that holds its faces, else ``None``."""
    if isinstance(value, CheckedMesh):
        return "a checked mesh"
    if hasattr(value, "faces") or hasattr(value, "triangles"):
        return f"a {type(value).__name__}"
    return None


def held_mesh(mesh: object) -> CheckedMesh:
    """The checked mesh that ``mesh`` holds (see :func:`checked_mesh`), recognised by its type
    or attributes; a ``TypeError`` that says what can be passed for anything else."""
    if isinstance(mesh, CheckedMesh):
        return mesh
    if isinstance(mesh, tuple) and len(mesh) == 2:
        return checked_mesh(mesh[0], mesh[1])
    checked = getattr(mesh, "checked", None)  # a LoadedMesh: the reader checked its arrays
    if callable(checked) and hasattr(mesh, "faces"):
        found = checked()
        if isinstance(found, CheckedMesh):
            return found
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):  # trimesh, a LoadedMesh
        return checked_mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    if hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):  # Open3D
        return checked_mesh(np.asarray(mesh.vertices), np.asarray(mesh.triangles))
    if hasattr(mesh, "points") and hasattr(mesh, "faces"):  # PyVista
        return checked_mesh(np.asarray(mesh.points), _polydata_triangles(mesh))
    raise TypeError(_not_a_mesh(mesh))


def _not_a_mesh(value: object) -> str:
    """The sentence that refuses ``value`` as a mesh, saying what can be passed."""
    if isinstance(value, str | bytes | os.PathLike):
        return f"A mesh function takes {MESH_FORMS}, not a file: read it with mn.read_mesh first."
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # ragged nested lists
        array = np.empty(0, dtype=object)
    if array.ndim == 2 and array.dtype.kind in "iuf":
        return f"faces are required with raw vertices: pass {MESH_FORMS}."
    return f"A mesh function takes {MESH_FORMS}, not {type(value).__name__}."


class _Points(Protocol):
    """What :func:`~mesh_normal.points.read_points` returns, an Open3D ``PointCloud``, a
    PyVista ``PolyData``."""

    @property
    def points(self) -> ArrayLike: ...


class _Vertices(Protocol):
    """A ``trimesh.PointCloud``, or any mesh by its vertices."""

    @property
    def vertices(self) -> ArrayLike: ...


#: A point cloud as people hold it (see :func:`held_points`).
HeldCloud: TypeAlias = "CheckedMesh | _Points | _Vertices"

#: What a point function takes, for the sentence that refuses anything else.
POINT_FORMS = (
    "an (n, 3) array of points, what read_points returns, an Open3D PointCloud, a "
    "trimesh.PointCloud, a PyVista PolyData, or a mesh (its vertices)"
)


def held_points(cloud: object) -> tuple[ArrayLike, FloatArray | None]:
    """The points that ``cloud`` holds and the normals stored with them (``None`` without),
    recognised by its attributes as :func:`checked_mesh` recognises a mesh: an array as it
    is; what :func:`~mesh_normal.points.read_points` returns, an Open3D ``PointCloud`` and a
    PyVista ``PolyData`` by their ``points`` (and ``normals``, an Open3D cloud's empty without
    any); a ``trimesh.PointCloud`` and any mesh by their ``vertices``. A path, or an object
    with none of these, gets a ``TypeError`` that says what can be passed; the points
    themselves are checked by the function that reads them."""
    if isinstance(cloud, CheckedMesh):
        return cloud.vertices, None
    if isinstance(cloud, str | bytes | os.PathLike):
        raise TypeError(
            f"A point function takes {POINT_FORMS}, not a file: read it with mn.read_points first."
        )
    if hasattr(cloud, "points"):
        points = np.asarray(cloud.points)
        normals = getattr(cloud, "normals", None)
        stored = None if normals is None else np.asarray(normals)
        if stored is None or stored.shape != points.shape or not len(stored):
            return points, None
        return points, stored.astype(np.float64, copy=False)
    if hasattr(cloud, "vertices"):
        return np.asarray(cloud.vertices), None
    if isinstance(cloud, np.ndarray | list | tuple):
        return cloud, None
    raise TypeError(f"A point function takes {POINT_FORMS}, not {type(cloud).__name__}.")


def _polydata_triangles(mesh: object) -> IndexArray:
    """(m, 3): the triangles of a PyVista ``PolyData``, from its flat cell array
    ``[3, a, b, c, 3, ...]``; a ``ValueError`` for any other cell. Polygons are refused, not
    cut into fans: a fan is right only for convex polygons, and ``triangulate()`` knows."""
    strips = getattr(mesh, "n_strips", 0)
    if isinstance(strips, int) and strips:
        raise ValueError(
            f"the PolyData has {strips:,} triangle strips: call its triangulate() first, "
            "so that every face is a triangle."
        )
    cells = np.asarray(mesh.faces)  # type: ignore[attr-defined]
    if cells.ndim == 2:  # already (m, 3)
        return cells
    whole = len(cells) - len(cells) % 4
    rows = cells[:whole].reshape(-1, 4)
    # Until the first cell of another size, every cell is four numbers long: that one is the
    # first row here whose count is not 3.
    other = np.flatnonzero(rows[:, 0] != 3)
    if len(other) or whole != len(cells):
        corners = int(rows[other[0], 0]) if len(other) else None
        found = f"a face of {corners} corners" if corners is not None else "a cut-off cell array"
        raise ValueError(
            f"the PolyData's faces must all be triangles, and it has {found}: call its "
            "triangulate() first."
        )
    return rows[:, 1:]


def check_mesh(vertices: ArrayLike, faces: ArrayLike) -> tuple[FloatArray, IndexArray]:
    """Convert and check a mesh up front, with a clear ``ValueError`` for the first problem.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates (any real dtype; converted to float64).
    faces : (m, 3) int
        Indices into ``vertices``, each in ``0 .. n - 1`` (any integer dtype).

    Returns
    -------
    vertices : (n, 3) float64
        C-contiguous; the input itself when it already is.
    faces : (m, 3) intp
        C-contiguous.
    """
    points, _ = _as_vertices(vertices)
    return points, check_faces(faces, len(points))


def _as_vertices(vertices: ArrayLike) -> tuple[FloatArray, tuple[float, float]]:
    """The vertices as C-contiguous float64, checked, and their smallest and largest
    coordinate (and 0): :func:`scaling` takes them instead of a second pass."""
    array = np.asarray(vertices)
    if array.size == 0 and array.ndim <= 2:
        array = array.reshape(0, 3)
    if array.dtype == np.bool_ or array.dtype.kind not in "iuf":
        raise ValueError(f"vertices must hold real numbers, not {array.dtype}.")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), not {array.shape}.")
    points = np.ascontiguousarray(array, dtype=np.float64)
    low, high = _coordinate_range(points)
    if not (math.isfinite(low) and math.isfinite(high)):
        row = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise ValueError(f"vertices[{row}] has a coordinate that is not a finite number.")
    return points, (low, high)


def check_faces(faces: ArrayLike, vertex_count: int, *, ranged: bool = True) -> IndexArray:
    """Convert and check faces alone, for ``vertex_count`` vertices (see :func:`check_mesh`).

    Parameters
    ----------
    faces : (m, 3) int
        Indices, each in ``0 .. vertex_count - 1`` (any integer dtype).
    vertex_count : int
        n, the number of vertices.
    ranged : bool
        False: the dtype and shape only, not the range (see :func:`checked_mesh`).

    Returns
    -------
    (m, 3) intp
        C-contiguous.
    """
    array = np.asarray(faces)
    if array.size == 0 and array.ndim <= 2:
        return np.empty((0, 3), dtype=np.intp)
    if array.dtype.kind not in "iu":
        raise ValueError(f"faces must hold integer vertex indices, not {array.dtype}.")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"faces must have shape (m, 3), not {array.shape}.")
    if not ranged and array.dtype == np.intp:
        return np.ascontiguousarray(array)
    low, high = _index_range(array)
    if low < 0:
        row, column = np.argwhere(array < 0)[0]
        raise ValueError(f"faces[{row}] has a negative vertex index, {array[row, column]}.")
    if high >= vertex_count:
        row, column = np.argwhere(array >= vertex_count)[0]
        there = (
            f"there are only {vertex_count} vertices (indices 0 to {vertex_count - 1})"
            if vertex_count
            else "there are no vertices"
        )
        raise ValueError(f"faces[{row}] refers to vertex {array[row, column]}, but {there}.")
    return np.ascontiguousarray(array, dtype=np.intp)


def refuse_faces(faces: IndexArray, vertex_count: int) -> NoReturn:
    """The ``ValueError`` of :func:`check_faces` naming the first face with an index out of
    range: for a kernel that found one as it read raw faces (see :func:`checked_mesh`)."""
    check_faces(faces, vertex_count)
    raise AssertionError("a kernel found an index out of range that the check did not")


def _index_range(array: np.ndarray) -> tuple[int, int]:
    """The smallest and largest index (and 0, for the usual dtype): for C-contiguous intp
    indices one compiled pass on every core, else NumPy's ``min`` and ``max``."""
    if array.dtype != np.intp or not array.flags.c_contiguous:
        return array.min(), array.max()
    return _core.index_range(array.reshape(-1))


def _coordinate_range(points: FloatArray) -> tuple[float, float]:
    """The smallest and largest coordinate and 0, NaN where one is not finite: for
    C-contiguous float64 points one compiled pass on every core (a third of the time of
    NumPy's ``min`` and ``max``), else those two (through which a NaN or an infinity goes)."""
    if points.dtype != np.float64 or not points.flags.c_contiguous:
        return float(points.min(initial=0.0)), float(points.max(initial=0.0))
    return _core.coordinate_range(points.reshape(-1))


def scaling(
    vertices: FloatArray, extremes: tuple[float, float] | None = None
) -> tuple[FloatArray, float, int]:
    """The power of two 2**scale that brings the largest |coordinate| into [0.5, 1).

    Products of up to four edge coordinates then neither over- nor underflow unless the
    edges are shorter than about 2**-237 (1e-71) times that coordinate. Wherever the
    unscaled values stay in the double range, scaling by a power of two changes no digit of
    any normal. The kernels multiply each coordinate they read by ``factor`` = 2**-scale,
    which rounds exactly as ``ldexp`` does; only when that factor is not a double (all
    coordinates below 2**-1022) are the points scaled here, into a copy.
    """
    # max(-min, max) is the largest |coordinate|, without the temporary of np.abs; the
    # extremes (with 0) come from the check when it took them.
    if extremes is None:
        extremes = float(vertices.min(initial=0.0)), float(vertices.max(initial=0.0))
    largest = max(-extremes[0], extremes[1])
    if largest == 0.0:
        return vertices, 1.0, 0
    scale = math.frexp(largest)[1]
    if scale < -1000:
        return np.ldexp(vertices, -scale), 1.0, scale
    return vertices, math.ldexp(1.0, -scale), scale
