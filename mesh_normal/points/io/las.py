"""LAS and LAZ (compressed LAS) files, read with laspy and its lazrs backend.

The coordinates are the scaled ones (``X * scale + offset``, as ``las.x`` gives them), never
the stored integers. ``red green blue`` (point formats 2, 3, 5, 7, 8, 10) are 16-bit by the
specification and scaled to 8 bits (``round(v / 257)``); a file whose colour values are all
255 or below is taken to hold 8-bit values in the 16-bit fields, as many writers do, and a note
says so. Normals come from extra-bytes dimensions named ``normal_x normal_y normal_z`` or
``nx ny nz`` when the file has them. Other attributes holding anything but zeros
(``intensity``, ``classification``, ``gps_time``...) are named in a note.

The header is checked before laspy reads it: its scales and offsets (a scale of 0 would put
every point at its offset, silently), its record counts against the bytes. A LAS file whose
header promises more points than its point data hold is refused; one whose point data hold
room for more than the header says is read as the header says (as other readers do: the
count is what the writer meant, and what follows may be padding) and a note says so. LAZ is
decompressed in chunks of :data:`CHUNK_POINTS` points, after its point count, at the bytes of
a record and :data:`~mesh_normal.points.io.cloud.POINT_JOB_BYTES` a point, is charged to the
upload's expansion budget (:mod:`mesh_normal.files.expansion`): compressed points are a few
bytes each, and the header may promise billions.
"""

from __future__ import annotations

import io
import math
import struct
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files import expansion
from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.io.cloud import POINT_JOB_BYTES, PointCloud, colors_uint8, make_cloud

#: Points decompressed at once: at most 67 bytes each (point format 10), about 17 MB.
CHUNK_POINTS = 1 << 18
_COORDINATES = ("X", "Y", "Z")
_COLORS = ("red", "green", "blue")
_NORMALS = (("normal_x", "normal_y", "normal_z"), ("nx", "ny", "nz"))


def read_las(data: bytes) -> PointCloud:
    """Read a LAS or LAZ file (see the module docstring)."""
    _check_header(data)
    try:
        return _read(data)
    except (MeshFileError, MemoryError, KeyboardInterrupt, SystemExit):
        raise
    except BaseException as error:  # lazrs panics are BaseExceptions (pyo3's PanicException)
        what = "LAZ" if data[104] & 0x80 else "LAS"
        reason = str(error).strip().rstrip(".")[:80] or type(error).__name__
        raise MeshFileError(
            f"The {what} file cannot be read ({reason}): it looks truncated or broken."
        ) from error


def _read(data: bytes) -> PointCloud:
    import laspy  # type: ignore[import-untyped]  # on first use: only these files need it

    with laspy.open(io.BytesIO(data)) as reader:
        header = reader.header
        compressed = bool(header.are_points_compressed)
        count = int(header.point_count)
        size = int(header.point_format.size)
        notes = [] if compressed else _checked_count(data, count, size)
        if compressed:
            expansion.charge(
                count * (size + POINT_JOB_BYTES),
                f"the LAZ file's {count:,} compressed points",
            )
        names = list(header.point_format.dimension_names)
        normal_names = next((n for n in _NORMALS if set(n) <= set(names)), None)
        parts: dict[str, list[NDArray[Any]]] = {"points": [], "colors": [], "normals": []}
        filled: set[str] = set()
        for chunk in reader.chunk_iterator(CHUNK_POINTS):
            _take(chunk, names, normal_names, parts, filled)
    return _cloud(parts, names, normal_names, filled, compressed, count, notes)


def _checked_count(data: bytes, count: int, size: int) -> list[str]:
    """Refuse a LAS header that promises more points than the point data hold; a note when
    they have room for more (the points end where the waveform data or the extended records
    start, else at the end of the file)."""
    (start,) = struct.unpack_from("<I", data, 96)
    end = len(data)
    minor = data[25]
    if minor >= 3 and len(data) >= 235:
        (waveform,) = struct.unpack_from("<Q", data, 227)
        end = min(end, waveform) if waveform > start else end
    if minor >= 4 and len(data) >= 247:
        first, evlrs = struct.unpack_from("<QI", data, 235)
        end = min(end, first) if evlrs and first > start else end
    held = max(end - start, 0) // max(size, 1)
    if held < count:
        raise MeshFileError(
            f"The LAS header says {count:,} points, but the file holds only {held:,}: "
            "it looks truncated."
        )
    if held == count:
        return []
    return [
        f"The LAS header says {count:,} points, but its point data have room for {held:,}; "
        f"the {count:,} the header says were read, and the rest left out."
    ]


#: Bytes of the smallest LAS header (1.0-1.2), of a VLR's header and of an EVLR's.
_HEADER, _VLR, _EVLR = 227, 54, 60


def _check_header(data: bytes) -> None:
    """Refuse record counts the bytes cannot hold before laspy reads them: it reads as many
    VLRs as the header says, past the end of the file (4 billion of them, for a bad count)."""
    if not data.startswith(b"LASF"):
        raise MeshFileError("The file does not start with 'LASF', as LAS and LAZ files do.")
    if len(data) < _HEADER:
        raise MeshFileError(
            f"The file is {len(data):,} bytes, too short for a LAS header ({_HEADER} bytes)."
        )
    minor = data[25]
    _check_scales(data)
    header_size, point_offset, vlrs = struct.unpack_from("<HII", data, 94)
    if not header_size <= point_offset <= len(data):
        raise MeshFileError(
            f"The LAS header puts the points at byte {point_offset:,}, outside the file's "
            f"{len(data):,} bytes or inside its {header_size:,}-byte header."
        )
    if vlrs * _VLR > point_offset - header_size:
        raise MeshFileError(
            f"The LAS header says {vlrs:,} variable-length records, but only "
            f"{point_offset - header_size:,} bytes lie between the header and the points."
        )
    if data[104] & 0x80:  # LAZ: the chunk table's count, which lazrs allocates for
        _check_chunks(data, point_offset, vlrs, header_size)
    if minor >= 4 and len(data) >= 247:
        first, evlrs = struct.unpack_from("<QI", data, 235)
        if evlrs and (first > len(data) or evlrs * _EVLR > len(data) - first):
            raise MeshFileError(
                f"The LAS header says {evlrs:,} extended variable-length records, but the "
                "file is too short to hold them."
            )


def _check_scales(data: bytes) -> None:
    """Coordinates are ``X * scale + offset``: a scale of 0 or anything not finite would put
    every point at one place, or nowhere, without a word."""
    scales = struct.unpack_from("<3d", data, 131)
    offsets = struct.unpack_from("<3d", data, 155)
    for axis, scale, offset in zip("xyz", scales, offsets, strict=True):
        if not math.isfinite(scale):
            raise MeshFileError(f"The LAS file's {axis} scale is {scale}, not a finite number.")
        if scale == 0:
            raise MeshFileError(
                f"The LAS file's {axis} scale is 0; every point would sit at its offset."
            )
        if not math.isfinite(offset):
            raise MeshFileError(f"The LAS file's {axis} offset is {offset}, not a finite number.")


def _check_chunks(data: bytes, point_offset: int, vlrs: int, header_size: int) -> None:
    """What lazrs allocates for before reading a point: a buffer of a whole chunk (its size in
    the ``laszip encoded`` VLR) and the chunk table (its offset is the first 8 bytes of the
    point data), which must not count more chunks than the file has bytes."""
    _check_chunk_size(data, vlrs, header_size)
    if point_offset + 8 > len(data):
        raise MeshFileError("The LAZ file ends where its points should start: it is truncated.")
    (table,) = struct.unpack_from("<q", data, point_offset)
    if point_offset + 8 <= table <= len(data) - 8:
        (chunks,) = struct.unpack_from("<I", data, table + 4)
        if chunks > len(data):
            raise MeshFileError(
                f"The LAZ file's chunk table counts {chunks:,} chunks, more than the file "
                "could hold: it is broken."
            )


#: The most points a LAZ chunk may hold (100 times the 50,000 writers use): lazrs allocates
#: a whole chunk at once, up to 335 MB at this size.
MAX_CHUNK_POINTS = 5_000_000
_VARIABLE_CHUNKS = 0xFFFFFFFF


def _check_chunk_size(data: bytes, vlrs: int, position: int) -> None:
    for _ in range(vlrs):
        if position + _VLR > len(data):
            return  # laspy says what is wrong
        user, record, length = struct.unpack_from("<16sHH", data, position + 2)
        start = position + _VLR
        if user.rstrip(b"\0") == b"laszip encoded" and record == 22204 and start + 16 <= len(data):
            (size,) = struct.unpack_from("<I", data, start + 12)
            if MAX_CHUNK_POINTS < size != _VARIABLE_CHUNKS:
                raise MeshFileError(
                    f"The LAZ file's chunks hold {size:,} points each, more than this reader "
                    f"takes ({MAX_CHUNK_POINTS:,})."
                )
        position = start + length


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
    notes: list[str],
) -> PointCloud:
    points = np.concatenate(parts["points"]) if parts["points"] else np.zeros((0, 3))
    if len(points) != count:
        raise MeshFileError(
            f"The LAS header says {count:,} points, but the file holds {len(points):,}."
        )
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
