"""Point-cloud files: which format a file is in, and the one entry point that reads any of them.

:func:`read_points` reads PLY (vertices, with or without faces), XYZ-like text tables
(:mod:`mesh_normal.points.io.xyz`), PCD (:mod:`mesh_normal.points.io.pcd`), LAS and LAZ
(:mod:`mesh_normal.points.io.las`), and any mesh file :func:`~mesh_normal.files.read_mesh` reads,
as the cloud of its vertices (:mod:`mesh_normal.points.io.vertices`, which also reads an OBJ file
of ``v`` lines without faces). It keeps the points in file order, the normals the file stores
(as stored, not normalised) and colours as ``uint8``; what the file holds beyond those is named
in :attr:`PointCloud.notes`. Every problem is a :class:`~mesh_normal.files.MeshFileError` with
one sentence: a non-finite coordinate is refused with its row, except in PCD files, whose
organised clouds mark missing points with NaN: those rows are left out, counted in a note, and
:attr:`PointCloud.kept` maps the points returned to the file's rows.

Headers that promise more than the file holds (a PCD's ``POINTS``, a PLY's vertex count, a LAS
point count) are refused before anything of that size is allocated. Compressed point data (a
PCD's LZF, LAZ) are charged to the input's expansion budget before they are unpacked
(:mod:`mesh_normal.files.expansion`; one is opened here when the caller has not).
"""

from __future__ import annotations

import dataclasses
import re

from mesh_normal.files import expansion
from mesh_normal.files.errors import MeshFileError, failure_reason, unsupported
from mesh_normal.files.read import MeshSource, source_bytes

# PointCloud and its parts live in mesh_normal.points.io.cloud, which every reader imports (so
# that this module can import the readers); they are named here too, as read_points's own.
from mesh_normal.points.io.cloud import PointCloud as PointCloud
from mesh_normal.points.io.cloud import SourceKind as SourceKind
from mesh_normal.points.io.cloud import Viewpoint as Viewpoint
from mesh_normal.points.io.cloud import colors_uint8 as colors_uint8
from mesh_normal.points.io.cloud import make_cloud as make_cloud
from mesh_normal.points.io.formats import POINT_SUFFIXES as POINT_SUFFIXES

# --- which format -------------------------------------------------------------------------

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

    Parameters
    ----------
    source : str, os.PathLike, bytes or binary file object
        The file: a path, its bytes, or a file object opened in binary mode.
    filename : str, optional
        Helps tell the format and the columns of a text table (``.xyzn``, ``.xyzrgb``,
        ``.pts``); for a path or a file object with a ``name`` it defaults to it.

    Returns
    -------
    PointCloud
        The points ``(n, 3)`` and what else the file holds (normals, colours, a viewpoint).

    Raises
    ------
    MeshFileError
        With one sentence naming the problem: 400 for a broken file or bad content, 415 for a
        format that is unknown or not supported.
    OSError, TypeError
        As :func:`~mesh_normal.files.read_mesh` raises them (a path that cannot be opened, a
        source of another type).

    Examples
    --------
    >>> read_points("scan.pcd")
    >>> read_points(data, "scan.xyz")      # bytes, with the name if known
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
        with expansion.expanding(len(data)):  # the caller's budget, if it opened one
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
    from mesh_normal.points.io.vertices import mesh_vertices, read_ply_points

    if found == "ply":
        return read_ply_points(data)
    if found == "xyz":
        from mesh_normal.points.io.xyz import read_xyz

        return read_xyz(data, suffix)
    if found == "pcd":
        from mesh_normal.points.io.pcd import read_pcd

        return read_pcd(data)
    if found == "las":
        from mesh_normal.points.io.las import read_las

        return read_las(data)
    return mesh_vertices(data, found)


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
