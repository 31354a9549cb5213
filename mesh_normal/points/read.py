"""Point-cloud files: which format a file is in, and the one entry point that reads any of them.

:func:`read_points` reads PLY (vertices, with or without faces), XYZ-like text tables
(:mod:`mesh_normal.points.xyz`), PCD (:mod:`mesh_normal.points.pcd`), LAS and LAZ
(:mod:`mesh_normal.points.las`), and any mesh file :func:`~mesh_normal.files.read_mesh` reads,
as the cloud of its vertices (:mod:`mesh_normal.points.vertices`, which also reads an OBJ file
of ``v`` lines without faces). It keeps the points in file order, the normals the file stores
(as stored, not normalised) and colours as ``uint8``; what the file holds beyond those is named
in :attr:`PointCloud.notes`. Every problem is a :class:`~mesh_normal.files.MeshFileError` with
one sentence: a non-finite coordinate is refused with its row, except in PCD files, whose
organised clouds mark missing points with NaN: those rows are left out, counted in a note, and
:attr:`PointCloud.kept` maps the points returned to the file's rows.

Headers that promise more than the file holds (a PCD's ``POINTS``, a PLY's vertex count, a LAS
point count) are refused before anything of that size is allocated.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mesh_normal.files.errors import MeshFileError, failure_reason, unsupported
from mesh_normal.files.loaded import first_bad_vertex
from mesh_normal.files.read import MeshSource, source_bytes
from mesh_normal.types import FloatArray

#: ``(origin (3,) float64, orientation (4,) float64 as w x y z)``: a PCD ``VIEWPOINT``.
Viewpoint = tuple[FloatArray, FloatArray]
SourceKind = Literal["points", "mesh vertices"]
_Item = TypeVar("_Item", bound=np.generic)

#: Describes row ``i`` (0-based) of the arrays for an error sentence, e.g. "the point on line 12".
Describe = Callable[[int], str]


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


# --- which format -------------------------------------------------------------------------

#: Extension (lower case, with the dot) to the point format it names.
POINT_SUFFIXES: dict[str, str] = {
    ".ply": "ply",
    ".pcd": "pcd",
    ".las": "las",
    ".laz": "las",
    **dict.fromkeys((".xyz", ".xyzn", ".xyzrgb", ".pts", ".txt", ".csv", ".asc"), "xyz"),
}

_PCD = re.compile(rb"\s*(?:#[^\n]*\n\s*)*(?:VERSION|FIELDS)\b")
_NUMBER_ROW = re.compile(rb"\s*[-+.\d]")


def sniff_points(data: bytes) -> str | None:
    """The point format the bytes show: ``"ply"``, ``"pcd"``, ``"las"``, a mesh format, or
    ``None``; text tables are told by name or by :func:`looks_like_table`."""
    from mesh_normal.files.read import sniff

    head = data[:4096]
    if head.startswith(b"LASF"):
        return "las"
    if re.match(rb"ply\r?\n", head):
        return "ply"
    if _PCD.match(head):
        return "pcd"
    return sniff(data)


def looks_like_table(data: bytes) -> bool:
    """Whether the file starts as a text table of points: no NUL, and its first line that is
    not a comment starts like a number or names x, y and z (a header row)."""
    head = data[:4096]
    if b"\0" in head:
        return False
    for line in head.splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith((b"#", b"//")):
            names = set(stripped.lower().replace(b",", b" ").split())
            return bool(_NUMBER_ROW.match(stripped)) or {b"x", b"y", b"z"} <= names
    return False


def _suffix(filename: str | None) -> str | None:
    if not filename or "." not in filename:
        return None
    return "." + filename.rsplit(".", 1)[-1].lower()


def read_points(source: MeshSource, filename: str | None = None) -> PointCloud:
    """Read a point-cloud file (or a mesh file, as its vertices); the format comes from the
    bytes, else from the file name's extension.

    >>> read_points("scan.pcd")
    >>> read_points(data, "scan.xyz")      # bytes, with the name if known

    ``filename`` helps tell the format and the columns of a text table (``.xyzn``,
    ``.xyzrgb``, ``.pts``); for a path or a file object with a ``name`` it defaults to it.

    Raises
    ------
    MeshFileError
        With one sentence naming the problem: 400 for a broken file or bad content, 415 for a
        format that is unknown or not supported.
    OSError, TypeError
        As :func:`~mesh_normal.files.read_mesh` raises them (a path that cannot be opened, a
        source of another type).
    """
    data, filename = source_bytes(source, filename)
    if not data:
        raise MeshFileError("The file is empty (0 bytes).")
    if data.startswith(b"\xef\xbb\xbf"):  # a UTF-8 byte order mark: text formats only
        data = data[3:]
    suffix = _suffix(filename)
    found = sniff_points(data)
    if found is None:
        from mesh_normal.files.formats import SUFFIXES

        if suffix in POINT_SUFFIXES:
            found = POINT_SUFFIXES[suffix]
        elif suffix in SUFFIXES:
            found = SUFFIXES[suffix]
        elif looks_like_table(data):
            found = "xyz"
        else:
            raise _unknown(filename)
    try:
        cloud = _read(found, data, suffix)
    except (MeshFileError, MemoryError):
        raise
    except Exception as error:  # a library's own exception (laspy's): never a 500
        raise MeshFileError(
            f"The file could not be read as {_title(found)}: {failure_reason(error)}."
        ) from error
    named = _named(suffix)
    if named is not None and named != found:
        note = (
            f"The file is named as {_title(named)} but holds {_title(found)}; "
            f"it was read as {_title(found)}."
        )
        cloud = dataclasses.replace(cloud, notes=(note, *cloud.notes))
    return cloud


def _named(suffix: str | None) -> str | None:
    from mesh_normal.files.formats import SUFFIXES

    return POINT_SUFFIXES.get(suffix or "") or SUFFIXES.get(suffix or "")


def _title(found: str) -> str:
    from mesh_normal.files.formats import FORMATS

    if found in FORMATS:
        return FORMATS[found].title
    return _TITLES.get(found, found.upper())


_TITLES = {"pcd": "PCD", "las": "LAS or LAZ", "xyz": "a text table of points"}


def _read(found: str, data: bytes, suffix: str | None) -> PointCloud:
    from mesh_normal.points import vertices

    if found == "ply":
        return vertices.read_ply_points(data)
    if found == "xyz":
        from mesh_normal.points.xyz import read_xyz

        return read_xyz(data, suffix)
    if found == "pcd":
        from mesh_normal.points.pcd import read_pcd

        return read_pcd(data)
    if found == "las":
        from mesh_normal.points.las import read_las

        return read_las(data)
    return vertices.mesh_vertices(data, found)


def _unknown(filename: str | None) -> MeshFileError:
    from mesh_normal.files.formats import SUFFIXES

    names = ", ".join(sorted({*POINT_SUFFIXES, *SUFFIXES}))
    if filename and "." in filename:
        suffix = filename.rsplit(".", 1)[-1][:20]
        return unsupported(
            f"The format of this .{suffix} file is not supported; the formats are {names}."
        )
    return unsupported(
        "The file's format was not recognised from its content; the formats are "
        f"{names} (a file name with its extension helps)."
    )
