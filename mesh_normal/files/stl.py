"""STL, binary and ASCII: separate triangle corners, welded into shared vertices.

Binary STL is an 80-byte header, a little-endian uint32 triangle count and 50 bytes per
triangle (float32 normal, three float32 corners, a uint16 attribute). It is read with one
``np.frombuffer``; the count is checked against the length here, because trimesh's loader
falls back to parsing the bytes as ASCII when they disagree. A binary header may itself start
with ``solid``, so :func:`is_binary` (the ``84 + 50 * count`` rule) is asked before the text.

Facet normals are kept as stored. Many exporters write zeros for "not given": when every one is
zero, :attr:`LoadedMesh.file_face_normals` is ``None`` and a note says so.

:func:`write_stl` writes binary STL: float32 corners, our face normals as facet normals.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.formats import MAKER
from mesh_normal.files.loaded import LoadedMesh, build, first_bad_vertex
from mesh_normal.files.weld import weld

HEADER = 84
RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])

_NUMBER = rb"\s+(\S+)\s+(\S+)\s+(\S+)"
# Keywords count only at the start of a line, so that a solid named "vertex colours" is fine.
_VERTEX = re.compile(rb"(?m)^[ \t]*vertex" + _NUMBER)
_NORMAL = re.compile(rb"(?m)^[ \t]*facet\s+normal" + _NUMBER)
_FACET = re.compile(rb"(?m)^[ \t]*facet\b")


def triangle_count(data: bytes) -> int | None:
    """The count a binary header states, or ``None`` when the file is shorter than a header."""
    return int.from_bytes(data[80:HEADER], "little") if len(data) >= HEADER else None


def is_binary(data: bytes) -> bool:
    """Whether the length is exactly what the binary header's triangle count calls for."""
    count = triangle_count(data)
    return count is not None and len(data) == HEADER + RECORD.itemsize * count


def looks_ascii(data: bytes) -> bool:
    """Whether the file reads as ASCII STL: ``solid``, then text with a ``facet`` or the end."""
    head = data[:4096]
    return (
        head.lstrip()[:5].lower() == b"solid"
        and b"\0" not in head
        and (b"facet" in head or b"endsolid" in head)
    )


def read_stl(data: bytes) -> LoadedMesh:
    """Read binary or ASCII STL (see the module docstring)."""
    if not is_binary(data) and looks_ascii(data):
        return _read_ascii(data)
    return _read_binary(data)


def _read_binary(data: bytes) -> LoadedMesh:
    count = triangle_count(data)
    if count is None:
        raise MeshFileError(
            f"The file is {len(data)} bytes long, too short for a binary STL "
            f"(its header alone is {HEADER} bytes)."
        )
    held, extra = divmod(len(data) - HEADER, RECORD.itemsize)
    notes = []
    if count > held:
        raise MeshFileError(
            f"The binary STL header says {count:,} triangles, but the file holds "
            f"only {held:,}: it looks truncated."
        )
    if count == 0 and held and not extra:
        count = held
        notes.append(f"The binary STL header says 0 triangles; read the {held:,} the file holds.")
    elif count < held or extra:
        notes.append(
            f"Ignored {len(data) - HEADER - RECORD.itemsize * count:,} bytes after the "
            f"last of the {count:,} triangles the header announces."
        )
    records = np.frombuffer(data, RECORD, count, HEADER)
    return _welded(records["corners"].reshape(-1, 3), records["normal"], notes)


def _read_ascii(data: bytes) -> LoadedMesh:
    corners = _numbers(_VERTEX.findall(data), "vertex")
    normals = _numbers(_NORMAL.findall(data), "facet normal")
    facets = len(_FACET.findall(data))
    if len(corners) != 3 * facets or len(normals) != facets:
        raise MeshFileError(
            f"The ASCII STL has {facets:,} facets, {len(normals):,} facet "
            f"normals and {len(corners):,} vertices; each facet needs one normal "
            "and exactly three vertices (is the file cut short?)."
        )
    return _welded(corners, normals, [])


def _numbers(matches: list[tuple[bytes, bytes, bytes]], keyword: str) -> NDArray[np.float64]:
    try:
        return np.array(matches, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        for number in (value for row in matches for value in row):
            try:
                float(number)
            except ValueError:
                text = number[:40].decode("ascii", "replace")
                raise MeshFileError(
                    f"The ASCII STL has {text!r} after '{keyword}' where a number should be."
                ) from None
        raise


def _welded(
    corners: NDArray[np.floating], normals: NDArray[np.floating], notes: list[str]
) -> LoadedMesh:
    bad = first_bad_vertex(corners)
    if bad is not None:
        raise MeshFileError(
            f"Triangle {bad // 3 + 1:,} (counting from 1) has a corner "
            "coordinate that is not a finite number."
        )
    vertices, index = weld(corners)
    notes.append(
        f"Welded {len(corners):,} STL corners into {len(vertices):,} vertices "
        "(identical coordinates merged, in order of first appearance)."
    )
    face_normals: NDArray[np.floating] | None = normals
    if len(normals) and not np.any(normals):
        face_normals = None
        notes.append(
            'Every facet normal in the file is zero (meaning "not given"), so there '
            "are none to compare with."
        )
    return build(
        "stl",
        vertices,
        index.reshape(-1, 3),
        source_faces=len(normals),
        face_normals=face_normals,
        notes=notes,
    )


def write_stl(points: NDArray[np.float64], triangles: NDArray[np.intp]) -> bytes:
    """Binary STL: float32 corners and our face normals as facet normals (zero for a
    degenerate face).

    Parameters
    ----------
    points : (n, 3) float64
        Checked; a coordinate beyond float32's range is a :class:`MeshFileError` (422).
    triangles : (m, 3) intp
    """
    # Imported here: reading STL needs no compiled kernel, only writing its normals does.
    from mesh_normal.faces import face_normals

    largest = float(np.abs(points).max(initial=0.0))
    if largest > float(np.finfo(np.float32).max):
        raise MeshFileError(
            f"Coordinates up to {largest:.3g} do not fit in STL, which stores "
            "32-bit floats (up to about 3.4e38); choose PLY or OBJ.",
            422,
        )
    records = np.zeros(len(triangles), dtype=RECORD)
    records["normal"] = face_normals(points, triangles).normals
    records["corners"] = points[triangles]
    header = f"binary STL written by {MAKER}".encode().ljust(HEADER - 4, b" ")
    return header + len(triangles).to_bytes(4, "little") + records.tobytes()
