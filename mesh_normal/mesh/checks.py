"""Input conversion and checks, done once at the edge: :class:`CheckedMesh`.

Every public function of the core takes raw arrays (and checks them, with a clear
``ValueError`` for the first problem) or a :class:`CheckedMesh` made by :func:`checked_mesh`,
which it trusts. A caller that runs several functions on one mesh checks it once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NoReturn, TypeVar

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


def checked_mesh(vertices: ArrayLike, faces: ArrayLike, *, ranged: bool = True) -> CheckedMesh:
    """Convert and check a mesh once (see :func:`check_mesh` for the rules).

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates (any real dtype).
    faces : (m, 3) int
        Indices into ``vertices`` (any integer dtype).
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
    """
    points, extremes = _as_vertices(vertices)
    indices = check_faces(faces, len(points), ranged=ranged)
    return CheckedMesh(points, indices, *scaling(points, extremes))


def as_checked(vertices: ArrayLike | CheckedMesh, faces: ArrayLike | None) -> CheckedMesh:
    """``vertices`` itself when it is a :class:`CheckedMesh`, else the checked arrays.

    The two ways to call the core: ``f(vertices, faces)`` or ``f(checked)``.
    """
    if isinstance(vertices, CheckedMesh):
        if faces is not None:
            raise TypeError("a checked mesh holds its faces: pass it without faces.")
        return vertices
    if faces is None:
        raise TypeError("faces are required with raw vertices.")
    return checked_mesh(vertices, faces)


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
