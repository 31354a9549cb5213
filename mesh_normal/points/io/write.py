"""Writing a point cloud with its normals: PLY, XYZ and CSV, each read back exactly by
:func:`~mesh_normal.points.io.read.read_points`.

- ``"ply"``: binary little-endian, ``double x y z nx ny nz``, one ``vertex`` element and no
  faces. Doubles, not floats: georeferenced coordinates (UTM eastings of 500 000 m and more)
  lose millimetres in float32.
- ``"xyz"``: text, ``x y z nx ny nz`` a line, each number in Python's shortest form that reads
  back to the same double (``repr``), under a comment ``# x y z nx ny nz`` naming the columns
  (readers that skip ``#`` lines, Open3D's and CloudCompare's, read past it; ours reads the
  names, so whole-number normals are never taken for colours).
- ``"csv"``: the same numbers apart by commas, under a header row ``x,y,z,nx,ny,nz``.

Without normals the files hold ``x y z`` alone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.formats import MAKER

#: The formats :func:`write_points` writes, and the media type of each.
POINT_WRITE_FORMATS: dict[str, str] = {
    "ply": "application/octet-stream",
    "xyz": "text/plain",
    "csv": "text/csv",
}


def write_points(
    points: NDArray[np.floating],
    normals: NDArray[np.floating] | None = None,
    fmt: str = "ply",
) -> bytes:
    """The bytes of a point-cloud file holding ``points`` and, if given, ``normals``.

    Parameters
    ----------
    points : (n, 3) float
        Finite coordinates.
    normals : (n, 3) float, optional
        One normal a point, finite (zeros for a point without one).
    fmt : {"ply", "xyz", "csv"}
        Binary little-endian PLY of doubles, or text that reads back to the same doubles.

    Returns
    -------
    bytes
        The file.

    Raises
    ------
    ValueError
        For another format, arrays of the wrong shape, or a value that is not finite (a point
        without a normal is written with zeros, say, not NaN, which no reader takes back).
    """
    xyz = _checked(points, "points")
    if normals is not None and len(normals) != len(xyz):
        raise ValueError(f"{len(normals)} normals for {len(xyz)} points.")
    columns = xyz if normals is None else np.hstack([xyz, _checked(normals, "normals")])
    names = _NAMES[: columns.shape[1]]
    if fmt == "ply":
        return _ply(columns)
    if fmt == "xyz":
        return ("# " + " ".join(names) + "\n").encode() + _text(columns, " ")
    if fmt == "csv":
        return (",".join(names) + "\n").encode() + _text(columns, ",")
    raise ValueError(f"Point clouds are written as {', '.join(POINT_WRITE_FORMATS)}, not {fmt!r}.")


_NAMES = ("x", "y", "z", "nx", "ny", "nz")


def _checked(array: NDArray[np.floating], what: str) -> NDArray[np.float64]:
    result = np.asarray(array, dtype=np.float64)
    if result.ndim != 2 or result.shape[1] != 3:
        raise ValueError(f"The {what} must be an (n, 3) array, not {result.shape}.")
    if not np.all(np.isfinite(result)):
        raise ValueError(f"The {what} hold a value that is not a finite number.")
    return result


def _ply(columns: NDArray[np.float64]) -> bytes:
    names = _NAMES[: columns.shape[1]]
    properties = "".join(f"property double {name}\n" for name in names)
    header = (
        f"ply\nformat binary_little_endian 1.0\ncomment written by {MAKER}\n"
        f"element vertex {len(columns)}\n{properties}end_header\n"
    )
    return header.encode() + np.ascontiguousarray(columns, dtype="<f8").tobytes()


def _text(columns: NDArray[np.float64], separator: str) -> bytes:
    # repr is the shortest text that reads back to the same double; -0.0 keeps its sign.
    lines = (separator.join(map(repr, row)) for row in columns.tolist())
    return "".join(line + "\n" for line in lines).encode()
