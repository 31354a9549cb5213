"""STL, binary and ASCII: separate triangle corners, welded into shared vertices.

Binary STL is an 80-byte header, a little-endian uint32 triangle count and 50 bytes per
triangle (float32 normal, three float32 corners, a uint16 attribute). It is read with one
``np.frombuffer``; the count is checked against the length here, because trimesh's loader
falls back to parsing the bytes as ASCII when they disagree. A binary header may itself start
with ``solid``, so :func:`is_binary` (the ``84 + 50 * count`` rule) is asked before the text.

Facet normals are kept as stored. Many exporters write zeros for "not given": when every one is
zero, :attr:`LoadedMesh.file_face_normals` is ``None`` and a note says so.

ASCII keywords count in any case (``SOLID``, ``Facet Normal``), only at the start of a line
(lines end in ``\n``, ``\r\n`` or, without any ``\n``, ``\r``); a UTF-8 byte order mark
before ``solid`` is skipped. Each ``solid NAME`` line starts a solid, up
to the next one (CAD multi-body exports and concatenated files hold several); its facets are one
group of :attr:`LoadedMesh.face_groups` (one solid is one object, as one OBJ ``o`` is), named by
the rest of the line (UTF-8, else Latin-1; ``"solid 2"`` for the second solid when that is
empty; a name already taken gets `` (2)``, `` (3)``...: each solid is a body of its own, unlike
OBJ's repeated ``g``). A solid without facets makes no group, and a note says so. Binary STL
holds one object and has no groups. The welding is across the whole file, as for one solid.

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
# Keywords count only at the start of a line, so that a solid named "vertex colours" is fine;
# the patterns search the file in lower case (case-insensitive patterns take half as long again).
_VERTEX = re.compile(rb"(?m)^[ \t]*vertex" + _NUMBER)
_NORMAL = re.compile(rb"(?m)^[ \t]*facet\s+normal" + _NUMBER)
_FACET = re.compile(rb"(?m)^[ \t]*facet\b")
#: The UTF-8 byte order mark some editors put before the text.
BOM = b"\xef\xbb\xbf"


def triangle_count(data: bytes) -> int | None:
    """The count a binary header states, or ``None`` when the file is shorter than a header."""
    return int.from_bytes(data[80:HEADER], "little") if len(data) >= HEADER else None


def is_binary(data: bytes) -> bool:
    """Whether the length is exactly what the binary header's triangle count calls for."""
    count = triangle_count(data)
    return count is not None and len(data) == HEADER + RECORD.itemsize * count


def looks_ascii(data: bytes) -> bool:
    """Whether the file reads as ASCII STL: ``solid``, then text with a ``facet`` or the end."""
    head = data[:4096].removeprefix(BOM).lower()
    return (
        head.lstrip()[:5] == b"solid"
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
    # The corners where they lie in the 50-byte records, (count, 3, 3): no copy for the weld.
    return _welded(records["corners"], records["normal"], notes)


def _read_ascii(data: bytes) -> LoadedMesh:
    if data.startswith(BOM):
        data = data[len(BOM) :]
    text = data.lower()  # same length: ASCII letters only, so the positions are the file's
    if b"\n" not in text:  # old Mac line ends: each a "\r"
        text = text.replace(b"\r", b"\n")
    solids = _solid_lines(text)  # looks_ascii saw one at the start
    starts = [0] + [start for start, _, _ in solids[1:]]
    names = [_name(data[start:end]) for _, start, end in solids] or [""]
    corners: list[NDArray[np.float64]] = []
    normals: list[NDArray[np.float64]] = []
    facets: list[int] = []
    for number, (start, end) in enumerate(zip(starts, [*starts[1:], len(data)], strict=True)):
        found = _solid(text, start, end, number, names)
        corners.append(found[0])
        normals.append(found[1])
        facets.append(found[2])
    notes, groups, group_names = _solid_groups(names, facets)
    return _welded(np.concatenate(corners), np.concatenate(normals), notes, groups, group_names)


def _solid_lines(text: bytes) -> list[tuple[int, int, int]]:
    """Where each ``solid`` line starts, and its name (the rest of the line) starts and ends.

    Found with ``bytes.find`` (a regular expression would read the file a fourth time):
    ``solid`` counts with only spaces before it on its line (not ``endsolid``) and no letter,
    digit or underscore after it.
    """
    found = []
    position = text.find(b"solid")
    while position >= 0:
        line = text.rfind(b"\n", 0, position) + 1
        after = text[position + 5 : position + 6]
        if not text[line:position].strip() and not (after.isalnum() or after == b"_"):
            end = text.find(b"\n", position)
            found.append((line, position + 5, len(text) if end < 0 else end))
        position = text.find(b"solid", position + 5)
    return found


def _solid(
    data: bytes, start: int, end: int, number: int, names: list[str]
) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """The vertex and facet normal numbers and the facet count of ``data[start:end]``, the
    solid ``number`` (0-based) of ``names``."""
    corners = _matched_numbers(_VERTEX, data, start, end, "vertex")
    normals = _matched_numbers(_NORMAL, data, start, end, "facet normal")
    facets = sum(1 for _ in _FACET.finditer(data, start, end))
    if len(corners) != 3 * facets or len(normals) != facets:
        where = "The ASCII STL" if len(names) == 1 else f"Solid {_describe(number, names)}"
        short = " (is the file cut short?)" if end == len(data) else ""
        raise MeshFileError(
            f"{where} has {facets:,} facets, {len(normals):,} facet "
            f"normals and {len(corners):,} vertices; each facet needs one normal "
            f"and exactly three vertices{short}."
        )
    return corners, normals, facets


def _name(raw: bytes) -> str:
    """A solid's name as written: UTF-8 where it decodes, else Latin-1; spaces stripped."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.strip()


def _describe(number: int, names: list[str]) -> str:
    """``1 ('lid')`` or ``2`` (without a name), for error sentences and notes."""
    name = names[number]
    return f"{number + 1:,} ({name[:40]!r})" if name else f"{number + 1:,}"


def _solid_groups(
    names: list[str], facets: list[int]
) -> tuple[list[str], NDArray[np.intp] | None, list[str] | None]:
    """Notes on solids without facets, each facet's group and the groups' names (see the
    module docstring); no groups when no solid has a facet (the mesh has no faces)."""
    notes = []
    empty = [number for number, count in enumerate(facets) if not count]
    if empty and len(empty) < len(facets):
        listed = [_describe(number, names) for number in empty[:5]]
        if len(empty) > 5:
            listed.append(f"{len(empty) - 5:,} more")
        which = listed[0] if len(listed) == 1 else f"{', '.join(listed[:-1])} and {listed[-1]}"
        notes.append(
            f"Solid {which} of {len(facets):,} holds no facets, so it is no object."
            if len(empty) == 1
            else f"Solids {which} of {len(facets):,} hold no facets, so they are no objects."
        )
    kept = [number for number, count in enumerate(facets) if count]
    if not kept:
        return notes, None, None
    taken: set[str] = set()
    group_names = []
    for number in kept:
        base = names[number] or f"solid {number + 1}"
        name, copy = base, 1
        while name in taken:
            copy += 1
            name = f"{base} ({copy})"
        taken.add(name)
        group_names.append(name)
    if len(kept) > 1:
        notes.append(f"Joined {len(kept):,} ASCII STL solids into one mesh, each an object.")
    groups = np.repeat(np.arange(len(kept), dtype=np.intp), [facets[number] for number in kept])
    return notes, groups, group_names


#: Matches turned into numbers at a time: a match's three bytes objects and tuple cost about
#: 230 bytes a vertex (70 MB for a 26 MB file, all of them at once), the numbers 24.
_MATCH_BATCH = 1 << 15


def _matched_numbers(
    pattern: re.Pattern[bytes], data: bytes, start: int, end: int, keyword: str
) -> NDArray[np.float64]:
    """(k, 3) float64: the three numbers of each match of ``pattern`` in ``data[start:end]``."""
    blocks: list[NDArray[np.float64]] = []
    batch: list[tuple[bytes, ...]] = []
    for match in pattern.finditer(data, start, end):
        batch.append(match.groups())
        if len(batch) == _MATCH_BATCH:
            blocks.append(_numbers(batch, keyword))
            batch = []
    blocks.append(_numbers(batch, keyword))
    return blocks[0] if len(blocks) == 1 else np.concatenate(blocks)


def _numbers(matches: list[tuple[bytes, ...]], keyword: str) -> NDArray[np.float64]:
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
    corners: NDArray[np.floating],
    normals: NDArray[np.floating],
    notes: list[str],
    groups: NDArray[np.intp] | None = None,
    group_names: list[str] | None = None,
) -> LoadedMesh:
    # Welded first (the weld compares bits: a NaN or an infinity is a point like another),
    # then checked: a sixth as many points as corners. The first corner of the first such
    # point is the file's first such corner, as points are numbered by first appearance.
    vertices, index = weld(corners)
    bad = first_bad_vertex(vertices)
    if bad is not None:
        corner = int(np.argmax(index == bad))
        raise MeshFileError(
            f"Triangle {corner // 3 + 1:,} (counting from 1) has a corner "
            "coordinate that is not a finite number."
        )
    notes.append(
        f"Welded {len(index):,} STL corners into {len(vertices):,} vertices "
        "(identical coordinates merged, in order of first appearance)."
    )
    # As float64 in face order first (what the mesh keeps): np.any of the records' strided
    # float32 view is several times slower than of the copy.
    face_normals: NDArray[np.floating] | None = np.ascontiguousarray(normals, dtype=np.float64)
    if len(normals) and not np.any(face_normals):
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
        face_groups=groups,
        group_names=group_names,
        notes=notes,
        distinct_points=True,  # the weld's points: no two equal (-0.0 counts as 0.0 in both)
    )


def write_stl(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    normals: NDArray[np.float64] | None = None,
    normals_kind: str | None = None,
) -> bytes:
    """Binary STL: float32 corners and our face normals as facet normals (zero for a
    degenerate face), or the face normals given (``normals_kind`` ``"face"``).

    Parameters
    ----------
    points : (n, 3) float64
        Checked; a coordinate beyond float32's range is a :class:`MeshFileError` (422).
    triangles : (m, 3) intp
    """
    # Imported here: reading STL needs no compiled kernel, only writing its normals does.
    from mesh_normal.mesh.faces import face_geometry

    largest = float(np.abs(points).max(initial=0.0))
    if largest > float(np.finfo(np.float32).max):
        raise MeshFileError(
            f"Coordinates up to {largest:.3g} do not fit in STL, which stores "
            "32-bit floats (up to about 3.4e38); choose PLY or OBJ.",
            422,
        )
    given = normals if normals_kind == "face" else None
    geometry = face_geometry(points, triangles) if given is None else None
    # The records written in place, a block at a time: the file's bytes once and a block of
    # normals and corners, not the whole mesh's of each and two copies of the bytes.
    out = bytearray(HEADER + RECORD.itemsize * len(triangles))
    out[: HEADER - 4] = f"binary STL written by {MAKER}".encode().ljust(HEADER - 4, b" ")
    out[HEADER - 4 : HEADER] = len(triangles).to_bytes(4, "little")
    records = np.frombuffer(out, RECORD, len(triangles), HEADER)
    for start in range(0, len(triangles), _WRITE_BLOCK):
        rows = slice(start, start + _WRITE_BLOCK)
        block = geometry.unit_normals(rows) if geometry is not None else given[rows]  # type: ignore[index]
        records["normal"][rows] = block
        records["corners"][rows] = points[triangles[rows]]
    del records  # the view: bytes() copies the buffer once
    return bytes(out)


#: Faces written at a time.
_WRITE_BLOCK = 1 << 16
