"""PCD, the Point Cloud Library's format: ``DATA ascii``, ``binary`` and ``binary_compressed``.

The header (``FIELDS SIZE TYPE COUNT WIDTH HEIGHT VIEWPOINT POINTS DATA``) is checked line by
line, and the size it promises against the bytes there before anything is allocated. Used
fields: ``x y z``, ``normal_x normal_y normal_z``, and ``rgb`` or ``rgba`` (packed ``0xAARRGGBB``
in a float's or a uint32's bits, as PCL stores them); others (``curvature``, ``intensity``...)
are named in a note, and ``_`` padding is read past.

ASCII numbers in float fields are kept as written (float64), not rounded to the declared
``SIZE 4``: writers print more digits than a float32 holds, as Open3D does, and Open3D reads
them so.

Points with a NaN (or infinite) coordinate are how organised clouds (``HEIGHT`` > 1, from depth
cameras) mark missing pixels: they are left out, a note counts them, and ``kept`` maps the
points returned to the file's rows. A NaN normal (PCL's "no normal") stays NaN.

``binary_compressed`` is LZF (Marc Lehmann's format, as PCL writes it) over the fields one after
another (all the points' ``x``, then all their ``y``...); :func:`lzf_decompress` unpacks it
with a small compiled loop (``cpp/points.cpp``) that checks every offset and length it reads
and never writes past the size the header states. Before that, the unpacked bytes and what the
points will cost in the job (:data:`POINT_JOB_BYTES` each) are charged to the upload's
expansion budget (:mod:`mesh_normal.files.expansion`): a few hundred kilobytes of LZF can hold
millions of points.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

import mesh_normal._core as _core
from mesh_normal.files import expansion
from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.io.cloud import POINT_JOB_BYTES, PointCloud, make_cloud
from mesh_normal.points.io.xyz import read_rows

#: Most bytes one LZF byte can become: a 3-byte back reference copies up to 264 bytes.
LZF_MAX_RATIO = 88
_KINDS = {("F", 4): "f4", ("F", 8): "f8"} | {
    (letter, size): f"{letter.lower()}{size}" for letter in "IU" for size in (1, 2, 4, 8)
}
_NORMAL = ("normal_x", "normal_y", "normal_z")
_USED = frozenset({"x", "y", "z", *_NORMAL, "rgb", "rgba", "_"})


@dataclass(frozen=True, slots=True)
class _Header:
    fields: list[tuple[str, str, int]]  # (name, NumPy type code, count)
    width: int
    height: int
    points: int
    viewpoint: tuple[float, ...] | None
    data: str  # ascii, binary or binary_compressed
    body: int  # where the data start
    lines: int  # header lines, for the line numbers of ASCII rows

    def record(self) -> np.dtype[np.void]:
        return np.dtype(
            [
                (_unique(name, i), "<" + kind, (count,))
                for i, (name, kind, count) in enumerate(self.fields)
            ]
        )


def _unique(name: str, index: int) -> str:
    return f"_{index}" if name == "_" else name  # padding fields may come several times


def read_pcd(data: bytes) -> PointCloud:
    """Read a PCD file (see the module docstring)."""
    header = _header(data)
    if not header.points:
        raise MeshFileError("The file holds no points.")
    record = header.record()
    if header.data == "ascii":
        columns, describe = _ascii(data, header, record)
    elif header.data == "binary":
        columns, describe = _binary(data, header, record), _nth
    else:
        columns, describe = _compressed(data, header, record), _nth
    return _cloud(header, columns, describe)


def _nth(row: int) -> str:
    return f"point {row:,} (counting from 0)"


#: A PCD header is a dozen short lines: a file that has not reached its DATA line after these
#: is not PCD, and is not read line by line to its end.
_MAX_HEADER_LINES, _MAX_LINE = 1000, 1 << 16


def _header(data: bytes) -> _Header:
    values: dict[str, list[str]] = {}
    position, number = 0, 0
    while "DATA" not in values:
        end = data.find(b"\n", position, position + _MAX_LINE)
        if end < 0 or number == _MAX_HEADER_LINES:
            raise MeshFileError(
                "The PCD header has no 'DATA' line: the file is cut short or not PCD."
            )
        number += 1
        words = data[position:end].decode("latin-1").split()
        position = end + 1
        if words and not words[0].startswith("#"):
            values[words[0].upper()] = words[1:]
    return _checked(values, position, number)


def _checked(values: dict[str, list[str]], body: int, lines: int) -> _Header:
    names = values.get("FIELDS") or values.get("COLUMNS")
    if not names or "SIZE" not in values or "TYPE" not in values:
        raise MeshFileError("The PCD header lacks its FIELDS, SIZE or TYPE line.")
    sizes = _integers(values, "SIZE", len(names))
    types = values["TYPE"]
    counts = _integers(values, "COUNT", len(names)) if "COUNT" in values else [1] * len(names)
    if len(types) != len(names):
        raise MeshFileError(
            f"The PCD header names {len(names)} fields but gives {len(types)} TYPE values."
        )
    fields = []
    for name, letter, size, count in zip(names, types, sizes, counts, strict=True):
        kind = _KINDS.get((letter.upper(), size))
        if kind is None:
            raise MeshFileError(
                f"The PCD field {name[:30]!r} has TYPE {letter[:10]} and SIZE {size}, "
                "which is not a number type (I or U of 1, 2, 4 or 8 bytes, F of 4 or 8)."
            )
        if count < 1:
            raise MeshFileError(f"The PCD field {name[:30]!r} has a COUNT below 1.")
        fields.append((name, kind, count))
    taken = [name for name, _, _ in fields if name != "_"]
    if len(set(taken)) != len(taken):
        raise MeshFileError("The PCD header names a field twice.")
    if not {"x", "y", "z"} <= set(taken):
        raise MeshFileError("The PCD file has no x, y and z fields.")
    if any(name in "xyz" and count != 1 for name, _, count in fields):
        raise MeshFileError("The PCD file's x, y and z fields must have a COUNT of 1.")
    return _sized(values, fields, body, lines)


def _sized(
    values: dict[str, list[str]], fields: list[tuple[str, str, int]], body: int, lines: int
) -> _Header:
    points = _integers(values, "POINTS", 1)[0] if "POINTS" in values else None
    height = _integers(values, "HEIGHT", 1)[0] if "HEIGHT" in values else 1
    width = _integers(values, "WIDTH", 1)[0] if "WIDTH" in values else None
    width = width if width is not None else (points or 0) // max(height, 1)
    points = width * height if points is None else points
    if width * height != points:
        raise MeshFileError(
            f"The PCD header's WIDTH {width:,} and HEIGHT {height:,} make {width * height:,} "
            f"points, but its POINTS says {points:,}."
        )
    viewpoint = None
    if "VIEWPOINT" in values:
        try:
            viewpoint = tuple(float(value) for value in values["VIEWPOINT"])
        except ValueError:
            viewpoint = ()
        if len(viewpoint) != 7 or not np.all(np.isfinite(viewpoint)):
            raise MeshFileError(
                "The PCD header's VIEWPOINT is not 7 finite numbers (tx ty tz qw qx qy qz)."
            )
    kind = (values["DATA"] or [""])[0].lower()
    if kind not in ("ascii", "binary", "binary_compressed"):
        raise MeshFileError(
            f"The PCD DATA {kind[:30]!r} is not ascii, binary or binary_compressed."
        )
    return _Header(fields, width, height, points, viewpoint, kind, body, lines)


def _integers(values: dict[str, list[str]], key: str, count: int) -> list[int]:
    words = values[key]
    if len(words) != count or not all(word.isdigit() for word in words):
        what = "a whole number" if count == 1 else f"{count} whole numbers, one a field"
        raise MeshFileError(f"The PCD header's {key} line is not {what}.")
    return [int(word) for word in words]


def _ascii(
    data: bytes, header: _Header, record: np.dtype[np.void]
) -> tuple[dict[str, NDArray[np.generic]], object]:
    width = sum(count for _, _, count in header.fields)
    text = data[header.body :]
    if header.points * width > (len(text) + 1) // 2:  # each number: a character and a space
        raise _truncated(header.points, "the file is too short to hold them")
    rows, lines = read_rows(text, header.lines + 1, width, "the header's fields call for")
    if len(rows) != header.points:
        if len(rows) < header.points:
            raise _truncated(header.points, f"the file holds only {len(rows):,}")
        raise MeshFileError(
            f"The PCD header says {header.points:,} points, but the file holds {len(rows):,}."
        )
    columns, start = {}, 0
    for (name, kind, count), key in zip(header.fields, record.names or (), strict=True):
        part = rows[:, start : start + count]
        if kind[0] in "iu" and not np.all(part == np.round(part)):  # NaN included
            raise MeshFileError(
                f"The PCD field {name[:30]!r} holds a value that is not a whole number."
            )
        # Floats as written, not rounded to a declared SIZE 4: writers (Open3D) print more
        # digits than a float32 holds, and georeferenced coordinates need them. A packed
        # rgb float is the float32 nearest to its text, as its bits are the colour.
        keep = kind[0] == "f" and name not in ("rgb", "rgba")
        columns[key] = part if keep else part.astype(kind)
        start += count
    return columns, lambda row: f"the point on line {lines[row]:,}"


def _binary(
    data: bytes, header: _Header, record: np.dtype[np.void]
) -> dict[str, NDArray[np.generic]]:
    held = (len(data) - header.body) // max(record.itemsize, 1)
    if held < header.points:
        raise _truncated(header.points, f"the file holds only {held:,}")
    records = np.frombuffer(data, record, header.points, header.body)
    return {name: records[name] for name in record.names or ()}


def _compressed(
    data: bytes, header: _Header, record: np.dtype[np.void]
) -> dict[str, NDArray[np.generic]]:
    sizes = data[header.body : header.body + 8]
    if len(sizes) < 8:
        raise MeshFileError("The compressed PCD file ends before its data sizes: it is truncated.")
    packed, size = struct.unpack("<II", sizes)
    expected = record.itemsize * header.points
    if size != expected:
        raise MeshFileError(
            f"The compressed PCD data unpack to {size:,} bytes, but {header.points:,} points "
            f"of its fields take {expected:,}."
        )
    source = data[header.body + 8 : header.body + 8 + packed]
    if len(source) < packed:
        raise MeshFileError(
            f"The compressed PCD data are {packed:,} bytes, but the file holds only "
            f"{len(source):,} of them: it is truncated."
        )
    if size > LZF_MAX_RATIO * packed:
        raise MeshFileError(
            f"The compressed PCD data ({packed:,} bytes) cannot unpack to the {size:,} bytes "
            "the header says."
        )
    expansion.charge(
        size + POINT_JOB_BYTES * header.points,
        f"the PCD file's LZF data, {header.points:,} points ({expansion.megabytes(size)} "
        "unpacked),",
    )
    raw = lzf_decompress(source, size)
    columns, offset = {}, 0
    for name in record.names or ():
        field = record.fields[name][0]  # type: ignore[index]
        base, shape = field.base, field.shape
        columns[name] = np.frombuffer(raw, base, header.points * shape[0], offset).reshape(
            header.points, *shape
        )
        offset += field.itemsize * header.points
    return columns


def lzf_decompress(source: bytes, size: int) -> NDArray[np.uint8]:
    """The ``size`` bytes that LZF data ``source`` unpack to; refuses data that break the
    format (a back reference before the start, a run past either end) or unpack to another
    size."""
    out = np.empty(size, dtype=np.uint8)
    written = _core.lzf(np.frombuffer(source, dtype=np.uint8), out)
    if written == _PAST_THE_END:
        raise MeshFileError(
            f"The compressed PCD data unpack to more than the {size:,} bytes the file says."
        )
    if written < 0:
        raise MeshFileError("The compressed PCD data are broken (not valid LZF).")
    if written != size:
        raise MeshFileError(
            f"The compressed PCD data unpack to {written:,} bytes, not the {size:,} the file says."
        )
    return out


#: What ``_core.lzf`` returns for data that would write past the end of its output.
_PAST_THE_END = -2


def _truncated(points: int, held: str) -> MeshFileError:
    return MeshFileError(f"The PCD header says {points:,} points, but {held}: it looks truncated.")


def _cloud(
    header: _Header, columns: dict[str, NDArray[np.generic]], describe: object
) -> PointCloud:
    names = {name for name, _, _ in header.fields}
    scalar = {key: column.reshape(header.points, -1) for key, column in columns.items()}
    points = np.hstack([scalar[axis].astype(np.float64) for axis in "xyz"])
    finite = np.isfinite(points).all(axis=1)
    kept = np.flatnonzero(finite)
    notes = []
    if len(kept) < header.points:
        missing = header.points - len(kept)
        notes.append(
            f"{missing:,} of the file's {header.points:,} points have no coordinates (NaN), as "
            "organised clouds mark missing points; they were left out."
        )
        if not len(kept):
            raise MeshFileError("The file holds no points with finite coordinates.")
    normals = None
    if set(_NORMAL) <= names:
        normals = np.hstack([scalar[axis][:, :1].astype(np.float64) for axis in _NORMAL])[kept]
    colors = _colors(scalar, names)
    unused = [
        name for name in dict.fromkeys(name for name, _, _ in header.fields) if name not in _USED
    ]
    if normals is None:
        unused += [name for name in _NORMAL if name in names]
    if unused:
        notes.append(f"The file's {', '.join(unused)} fields are not used.")
    viewpoint = header.viewpoint
    return make_cloud(
        "pcd",
        points[kept],
        normals=normals,
        colors=None if colors is None else colors[kept],
        viewpoint=None if viewpoint is None else (np.array(viewpoint[:3]), np.array(viewpoint[3:])),
        kept=kept,
        file_points=header.points,
        notes=notes,
        describe=describe,  # type: ignore[arg-type]
        nan_normals=True,
    )


def _colors(scalar: dict[str, NDArray[np.generic]], names: set[str]) -> NDArray[np.uint8] | None:
    """``rgb``/``rgba`` as PCL packs them, ``0xAARRGGBB`` in the bits of a 4-byte field."""
    name = "rgb" if "rgb" in names else "rgba" if "rgba" in names else None
    if name is None:
        return None
    column = np.ascontiguousarray(scalar[name][:, 0])
    if column.dtype.itemsize != 4:
        raise MeshFileError(f"The PCD field {name} is not 4 bytes, as packed colours are.")
    bits = column.view(np.uint32)
    return np.stack([(bits >> 16) & 255, (bits >> 8) & 255, bits & 255], axis=1).astype(np.uint8)
