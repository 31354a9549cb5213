"""The point cloud as read from a file, and the one checker every reader builds it with."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mesh_normal.choices import SourceKind as SourceKind
from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.loaded import first_bad_vertex
from mesh_normal.types import FloatArray

#: ``(origin (3,) float64, orientation (4,) float64 as w x y z)``: a PCD ``VIEWPOINT``.
Viewpoint = tuple[FloatArray, FloatArray]
_Item = TypeVar("_Item", bound=np.generic)

#: Describes row ``i`` (0-based) of the arrays for an error sentence, e.g. "the point on line 12".
Describe = Callable[[int], str]

#: Bytes of memory a point takes in the point-normals job, measured over the whole job (the
#: k-d tree queries' neighbour lists, the orientation, the report; see the server's
#: ``app.points.estimates``): what readers charge for points they unpack from compressed data.
POINT_JOB_BYTES = 213


@dataclass(frozen=True, slots=True, eq=False)
class PointCloud:
    """A point cloud as its file holds it; every array is read-only. Compared by identity
    (``==`` on arrays has no single truth value).

    Attributes
    ----------
    points : (n, 3) float64
        In file order (LAS: the scaled coordinates, never the stored integers).
    normals : (n, 3) float64 or None
        As stored, not normalised: PLY ``nx ny nz``, PCD ``normal_x normal_y normal_z``, text
        columns, mesh vertex normals. ``None`` when the file has none. In a PCD file a point
        whose normal is NaN (PCL's "no normal") keeps NaN here, and a note counts them.
    colors : (n, 3) uint8 or None
        ``red green blue``: 16-bit colours scaled to 8 bits (``round(v / 257)``), float
        colours in 0-1 scaled by 255; alpha is not kept.
    viewpoint : tuple of (3,) float64 and (4,) float64, or None
        A PCD ``VIEWPOINT``: the sensor's origin and its orientation as a quaternion
        ``w x y z``; ``None`` for other formats.
    format : str
        ``"ply"``, ``"xyz"`` (any text table), ``"pts"`` (a text table whose first line is its
        point count), ``"pcd"``, ``"las"``, ``"laz"``, or a mesh format (``"stl"``, ``"obj"``,
        ``"off"``, ``"glb"``, ``"gltf"``, ``"3mf"``).
    source_kind : str
        ``"points"``, or ``"mesh vertices"`` for a mesh file (a PLY with faces included).
    kept : (n,) int64
        The file row (0-based, in the file's point order) of each point; ``arange(n)`` unless
        rows were left out (PCD NaN points).
    file_points : int
        Points (rows) the file holds, those left out included.
    notes : tuple of str
        Plain sentences about what was not used or left out.
    """

    points: FloatArray
    normals: FloatArray | None
    colors: NDArray[np.uint8] | None
    viewpoint: Viewpoint | None
    format: str
    source_kind: SourceKind
    kept: NDArray[np.int64]
    file_points: int
    notes: tuple[str, ...] = ()


def make_cloud(
    file_format: str,
    points: ArrayLike,
    *,
    normals: ArrayLike | None = None,
    colors: NDArray[np.uint8] | None = None,
    viewpoint: Viewpoint | None = None,
    kept: ArrayLike | None = None,
    file_points: int | None = None,
    source_kind: SourceKind = "points",
    notes: Sequence[str] = (),
    describe: Describe | None = None,
    nan_normals: bool = False,
) -> PointCloud:
    """Check a reader's arrays and freeze them into a :class:`PointCloud`.

    Refuses a cloud without points and the first non-finite coordinate (and normal, unless
    ``nan_normals``), naming the row with ``describe``.
    """
    describe = describe or (lambda row: f"point {row:,} (counting from 0)")
    xyz = _frozen(points, np.float64)
    if xyz.ndim != 2 or xyz.shape[1] != 3:  # a reader's bug: fail loudly
        raise AssertionError(f"points of shape {xyz.shape}")
    if not len(xyz):
        raise MeshFileError("The file holds no points.")
    _refuse_nonfinite(xyz, "coordinates", describe)
    normal = None if normals is None else _frozen(normals, np.float64)
    notes = list(notes)
    if normal is not None:
        if not nan_normals:
            _refuse_nonfinite(normal, "normal", describe)
        elif first_bad_vertex(normal) is not None:
            missing = int(np.sum(~np.isfinite(normal).all(axis=1)))
            verb = "has" if missing == 1 else "have"
            notes.append(f"{_count(missing, 'point')} in the file {verb} no normal (NaN).")
    order = _frozen(np.arange(len(xyz)) if kept is None else kept, np.int64)
    for array in (normal, colors):
        if array is not None and array.shape != xyz.shape:  # a reader's bug: fail loudly
            raise AssertionError(f"an array of shape {array.shape} for {len(xyz)} points")
    if viewpoint is not None:
        viewpoint = (_frozen(viewpoint[0], np.float64), _frozen(viewpoint[1], np.float64))
    return PointCloud(
        points=xyz,
        normals=normal,
        colors=None if colors is None else _frozen(colors, np.uint8),
        viewpoint=viewpoint,
        format=file_format,
        source_kind=source_kind,
        kept=order,
        file_points=len(xyz) if file_points is None else file_points,
        notes=tuple(notes),
    )


def _frozen(array: ArrayLike, dtype: type[_Item]) -> NDArray[_Item]:
    result = np.array(array, dtype=dtype, order="C")  # a copy: freezing leaves the caller's
    result.setflags(write=False)
    return result


def _refuse_nonfinite(values: FloatArray, what: str, describe: Describe) -> None:
    row = first_bad_vertex(values)
    if row is not None:
        value = values[row][~np.isfinite(values[row])][0]
        text = describe(row)
        raise MeshFileError(
            f"The {what} of {text} include {value}, which is not a finite number."
            if what == "coordinates"
            else f"The {what} of {text} includes {value}, which is not a finite number."
        )


def _count(count: int, noun: str) -> str:
    return f"{count:,} {noun}" + ("" if count == 1 else "s")


def colors_uint8(values: NDArray[np.generic], what: str = "colour") -> NDArray[np.uint8]:
    """``(n, 3)`` colours in any type as ``uint8``: ``uint8`` as they are, 16-bit ones scaled
    (``round(v / 257)``), floats in 0-1 scaled by 255 and rounded; whole numbers from text
    (stored as floats) that exceed 1 are taken as 0-255. Values outside those ranges are
    refused."""
    if values.dtype == np.uint8:
        return values.astype(np.uint8)  # the same type, for the type checker
    if values.dtype == np.uint16:
        return np.round(values.astype(np.float64) / 257).astype(np.uint8)
    floats = values.astype(np.float64)
    if floats.size == 0:
        return floats.astype(np.uint8)
    low, high = float(floats.min()), float(floats.max())
    if values.dtype.kind in "ui" or (high > 1 and np.all(floats == np.round(floats))):
        if low < 0 or high > 255:
            raise MeshFileError(f"A {what} value of {low if low < 0 else high:g} is outside 0-255.")
        return floats.astype(np.uint8)
    if not (low >= 0 and high <= 1):  # also NaN
        bad = low if not low >= 0 else high
        raise MeshFileError(
            f"A {what} value of {bad:g} is outside 0-1 (or 0-255 in whole numbers)."
        )
    return np.round(floats * 255).astype(np.uint8)
