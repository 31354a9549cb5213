"""LAS and LAZ (compressed LAS) files, read with laspy and its lazrs backend.

The coordinates are the scaled ones (``X * scale + offset``, as ``las.x`` gives them), never
the stored integers. ``red green blue`` (point formats 2, 3, 5, 7, 8, 10) are 16-bit by the
specification and scaled to 8 bits (``round(v / 257)``); a file whose colour values are all
255 or below is taken to hold 8-bit values in the 16-bit fields, as many writers do, and a note
says so. Normals come from extra-bytes dimensions named ``normal_x normal_y normal_z`` or
``nx ny nz`` when the file has them. Other attributes holding anything but zeros
(``intensity``, ``classification``, ``gps_time``...) are named in a note.

The header's point count is checked against the bytes first (LAS), and LAZ is decompressed
in chunks of :data:`CHUNK_POINTS` points, so a header promising more points than the file
holds costs one chunk, not the promise.
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.read import PointCloud, colors_uint8, make_cloud

#: Points decompressed at once: at most 67 bytes each (point format 10), about 17 MB.
CHUNK_POINTS = 1 << 18
_COORDINATES = ("X", "Y", "Z")
_COLORS = ("red", "green", "blue")
_NORMALS = (("normal_x", "normal_y", "normal_z"), ("nx", "ny", "nz"))


def read_las(data: bytes) -> PointCloud:
    """Read a LAS or LAZ file (see the module docstring)."""
    import laspy  # type: ignore[import-untyped]  # on first use: only these files need it

    with laspy.open(io.BytesIO(data)) as reader:
        header = reader.header
        compressed = bool(header.are_points_compressed)
        count = int(header.point_count)
        size = int(header.point_format.size)
        if not compressed and header.offset_to_point_data + count * size > len(data):
            held = max(len(data) - header.offset_to_point_data, 0) // max(size, 1)
            raise MeshFileError(
                f"The LAS header says {count:,} points, but the file holds only {held:,}: "
                "it looks truncated."
            )
        names = list(header.point_format.dimension_names)
        normal_names = next((n for n in _NORMALS if set(n) <= set(names)), None)
        parts: dict[str, list[NDArray[Any]]] = {"points": [], "colors": [], "normals": []}
        filled: set[str] = set()
        try:
            for chunk in reader.chunk_iterator(CHUNK_POINTS):
                _take(chunk, names, normal_names, parts, filled)
        except MeshFileError:
            raise
        except Exception as error:  # lazrs: "failed to fill whole buffer" and the like
            raise MeshFileError(
                f"The {'LAZ' if compressed else 'LAS'} file's points cannot be read "
                f"({str(error)[:80]}): it looks truncated or broken."
            ) from error
    return _cloud(parts, names, normal_names, filled, compressed, count)


def _take(
    chunk: Any,
    names: list[str],
    normal_names: tuple[str, ...] | None,
    parts: dict[str, list[NDArray[Any]]],
    filled: set[str],
) -> None:
    parts["points"].append(np.stack([np.asarray(chunk[axis.lower()]) for axis in "XYZ"], axis=1))
    if set(_COLORS) <= set(names):
        parts["colors"].append(np.stack([np.asarray(chunk[c]) for c in _COLORS], axis=1))
    if normal_names is not None:
        parts["normals"].append(np.stack([np.asarray(chunk[n]) for n in normal_names], axis=1))
    for name in names:
        if name not in filled and np.any(np.asarray(chunk[name])):
            filled.add(name)


def _cloud(
    parts: dict[str, list[NDArray[Any]]],
    names: list[str],
    normal_names: tuple[str, ...] | None,
    filled: set[str],
    compressed: bool,
    count: int,
) -> PointCloud:
    points = np.concatenate(parts["points"]) if parts["points"] else np.zeros((0, 3))
    if len(points) != count:
        raise MeshFileError(
            f"The LAS header says {count:,} points, but the file holds {len(points):,}."
        )
    notes = []
    colors = None
    if parts["colors"]:
        wide = np.concatenate(parts["colors"]).astype(np.uint16)
        if wide.size and int(wide.max()) <= 255:
            notes.append(
                "The file's colours are all 255 or below: they were read as 8-bit values "
                "(as many writers store them), not scaled from 16 bits."
            )
            colors = wide.astype(np.uint8)
        else:
            colors = colors_uint8(wide)
    used = {*_COORDINATES, *_COLORS, *(normal_names or ())}
    unused = [name for name in names if name in filled and name not in used]
    if unused:
        notes.append(f"The file's {', '.join(unused)} values are not used.")
    return make_cloud(
        "laz" if compressed else "las",
        points,
        normals=np.concatenate(parts["normals"]) if parts["normals"] else None,
        colors=colors,
        notes=notes,
    )
