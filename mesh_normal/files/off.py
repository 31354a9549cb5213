"""OFF (Object File Format), ASCII, by our own small parser.

The keyword may be ``OFF``, ``COFF``, ``NOFF``, ``CNOFF``, ``STOFF`` and the like: each vertex
line then holds x y z, after ``N`` nx ny nz (kept as vertex normals), after ``C`` a colour
(kept as vertex colours), after ``ST`` texture coordinates (ignored), in that order. A face
line may end with a colour (kept as face colours, each triangle of a polygon with its
polygon's). A colour is 3 or 4 numbers (red green blue [alpha]): integers 0-255, kept as
uint8, or floats 0-1, kept as float64; a file's colours count only when every vertex (or
every face) has one of the same width, and a note says why those that do not were left out.
``#`` starts a comment. Vertices keep their order; polygons are triangulated in file order.
Binary OFF is not supported.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError, unsupported
from mesh_normal.files.loaded import LoadedMesh, build
from mesh_normal.files.polygons import triangulate

_KEYWORD = re.compile(r"(ST)?(C)?(N)?(4)?(n)?OFF")
_INTEGER = re.compile(r"[+-]?\d+")

Rows = list[tuple[int, list[str]]]


def read_off(data: bytes) -> LoadedMesh:
    """Read an ASCII OFF file (see the module docstring)."""
    rows = [
        (number, line.split("#", 1)[0].split())
        for number, line in enumerate(data.decode("latin-1").splitlines(), 1)
    ]
    rows = [(number, words) for number, words in rows if words]
    match = _KEYWORD.match(rows[0][1][0]) if rows else None
    if match is None or not _keyword_ends(rows[0][1][0], match.end()):
        raise MeshFileError("The file does not start with OFF (or COFF, NOFF, ...).")
    if match.group(4) or match.group(5):
        raise unsupported("OFF files in 4D or n dimensions are not supported.")
    glued = rows[0][1][0][match.end() :]  # "OFF8 6 12": the counts start inside the keyword
    rest = ([glued] if glued else []) + rows[0][1][1:]
    if rest and rest[0].upper() == "BINARY":
        raise unsupported("Binary OFF files are not supported; save it as ASCII OFF.")
    if rest:  # counts on the keyword line
        rows[0] = (rows[0][0], rest)
    else:
        rows = rows[1:]
    if not rows:
        raise MeshFileError("The OFF file has no line with its vertex and face counts.")
    number, counts = rows[0]
    try:
        vertex_count, face_count = int(counts[0]), int(counts[1])
    except (ValueError, IndexError):
        raise MeshFileError(
            f"Line {number}: the OFF counts line must start with the number of "
            "vertices and of faces."
        ) from None
    if vertex_count < 0 or face_count < 0:
        raise MeshFileError(f"Line {number}: the OFF counts cannot be negative.")
    vertex_rows = rows[1 : 1 + vertex_count]
    face_rows = rows[1 + vertex_count : 1 + vertex_count + face_count]
    if len(vertex_rows) < vertex_count or len(face_rows) < face_count:
        raise MeshFileError(
            f"The OFF header says {vertex_count:,} vertices and {face_count:,} "
            f"faces, but the file holds only {len(vertex_rows):,} vertex and "
            f"{len(face_rows):,} face lines: it looks truncated."
        )
    width = 6 if match.group(3) else 3
    table = _table(vertex_rows, width)
    polygon_counts, flat, face_extra = _faces(face_rows)
    positions, source, notes = triangulate(polygon_counts, flat, table[:, :3])
    texture = 2 if match.group(1) else 0  # ST: s t end each vertex line
    vertex_extra = [words[width : len(words) - texture] for _, words in vertex_rows]
    vertex_colors = _colors(vertex_extra, "vertex", notes) if match.group(2) else None
    face_colors = _colors(face_extra, "face", notes)
    lines = np.array([number for number, _ in face_rows], dtype=np.intp)
    return build(
        "off",
        table[:, :3],
        flat[positions],
        source_faces=face_count,
        vertex_normals=table[:, 3:6] if width == 6 else None,
        vertex_colors=vertex_colors,
        face_colors=None if face_colors is None else face_colors[source],
        notes=notes,
        vertex=lambda i: f"vertex {i:,} (counting from 0, line {vertex_rows[i][0]:,})",
        face=lambda i: f"the face on line {lines[source[i]]:,}",
    )


def _keyword_ends(word: str, end: int) -> bool:
    """Whether the keyword ends at ``end``: the word ends there or a count follows it."""
    return end == len(word) or word[end:].isdigit() or word[end:].upper() == "BINARY"


def _table(rows: Rows, width: int) -> NDArray[np.float64]:
    for number, words in rows:
        if len(words) < width:
            raise MeshFileError(
                f"Line {number}: an OFF vertex needs {width} numbers, but has {len(words)}."
            )
    try:
        return np.array([words[:width] for _, words in rows], dtype=np.float64).reshape(-1, width)
    except ValueError:
        for number, words in rows:
            for word in words[:width]:
                _number(word, number, float)
        raise


def _faces(rows: Rows) -> tuple[NDArray[np.intp], NDArray[np.intp], list[list[str]]]:
    """Corner counts, the flat corner indices and the words after each face's corners."""
    counts = np.zeros(len(rows), dtype=np.intp)
    flat: list[int] = []
    extra: list[list[str]] = []
    for row, (number, words) in enumerate(rows):
        size = _number(words[0], number, int)
        if size < 0 or len(words) < 1 + size:
            raise MeshFileError(
                f"Line {number}: the face says it has {size} corners, but "
                f"{len(words) - 1} numbers follow."
            )
        counts[row] = size
        flat += [_number(word, number, int) for word in words[1 : 1 + size]]
        extra.append(words[1 + size :])
    return counts, np.array(flat, dtype=np.intp), extra


def _colors(words: list[list[str]], kind: str, notes: list[str]) -> NDArray[np.generic] | None:
    """The colours ``words`` hold (one row per vertex or face), or ``None`` with a note on why
    they were left out (nothing when no row has any)."""
    widths = {len(row) for row in words}
    if not words or widths == {0}:
        return None
    width = widths.pop() if len(widths) == 1 else 0
    if width not in (3, 4):
        notes.append(
            f"The OFF {kind} colours were not read: only some {kind}s have one, or they are "
            "not all 3 or 4 numbers (colour-map indices, say, which this reader does not "
            "resolve)."
        )
        return None
    try:
        values = np.array(words, dtype=np.float64)
    except ValueError:
        notes.append(f"The OFF {kind} colours were not read: some are not numbers.")
        return None
    if all(_INTEGER.fullmatch(word) for row in words for word in row):
        if values.min() < 0 or values.max() > 255:
            notes.append(f"The OFF {kind} colours were not read: integers must be 0 to 255.")
            return None
        return values.astype(np.uint8)
    return values


def _number(word: str, line: int, kind: type[int] | type[float]) -> int:
    try:
        return kind(word)  # type: ignore[return-value]
    except ValueError:
        what = "a whole number" if kind is int else "a number"
        raise MeshFileError(f"Line {line}: {word[:40]!r} is not {what}.") from None
