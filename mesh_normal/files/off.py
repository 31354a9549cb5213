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

import io
import re

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError, unsupported
from mesh_normal.files.formats import MAKER
from mesh_normal.files.loaded import LoadedMesh, build
from mesh_normal.files.polygons import triangulate

_KEYWORD = re.compile(r"(ST)?(C)?(N)?(4)?(n)?OFF")
_INTEGER = re.compile(r"[+-]?\d+")

Rows = list[tuple[int, list[str]]]


def read_off(data: bytes) -> LoadedMesh:
    """Read an ASCII OFF file (see the module docstring)."""
    plain = _read_plain(data)
    return plain if plain is not None else _read_rows(data)


def _read_rows(data: bytes) -> LoadedMesh:
    """Any OFF file, line by line into lists of words (about 20 times the file's size)."""
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


#: What a plain OFF body holds: numbers, spaces, line ends (the letters of nan and inf too).
_PLAIN_BYTES = b"0123456789+-.eE \t\r\nnaNAiIfFtTyY"
_INDEX_BYTES = b"0123456789+- \t\r\n"
_CHUNK = 1 << 20


def _read_plain(data: bytes) -> LoadedMesh | None:
    """The common case in a few times the file's memory, or ``None`` for :func:`_read_rows`.

    A plain ``OFF`` line, a counts line, then only numbers (no comment, colour or normal, no
    other line end than ``\\n`` or ``\\r\\n``): every number is converted in chunks of lines
    into one array, and each line's count of numbers says which are which. Anything else,
    errors included, goes to :func:`_read_rows`, so both give the same mesh and sentences.
    """
    head = _plain_head(data)
    if head is None:
        return None
    body, first_line, vertex_count, face_count = head
    if not vertex_count or not face_count:
        return None
    parsed = _numbers_by_line(data, body)
    if parsed is None:
        return None
    values, counts, lengths = parsed
    rows = np.flatnonzero(counts)
    if len(rows) < vertex_count + face_count:
        return None
    vertex_rows, face_rows = rows[:vertex_count], rows[vertex_count : vertex_count + face_count]
    if np.any(counts[vertex_rows] != 3):
        return None
    starts = np.concatenate([[0], np.cumsum(counts)])
    face_values = values[3 * vertex_count : starts[face_rows[-1] + 1]]
    ends = np.concatenate([[0], np.cumsum(lengths)]) + body
    if data[ends[face_rows[0]] : ends[face_rows[-1] + 1]].translate(None, _INDEX_BYTES):
        return None  # "3.0" or "1e2" as an index: _read_rows names it
    sizes = values[starts[face_rows]]
    if np.any(counts[face_rows] != 1 + sizes) or np.abs(face_values).max(initial=0) > 2**53:
        return None
    is_size = np.zeros(len(face_values), dtype=bool)
    is_size[starts[face_rows] - 3 * vertex_count] = True
    flat = face_values[~is_size].astype(np.intp)
    del face_values, is_size
    vertices = values[: 3 * vertex_count].reshape(-1, 3)
    polygon_counts = sizes.astype(np.intp)
    positions, source, notes = triangulate(polygon_counts, flat, vertices)
    vertex_lines = vertex_rows + first_line
    face_lines = face_rows + first_line
    return build(
        "off",
        vertices,
        flat[positions],
        source_faces=face_count,
        notes=notes,
        vertex=lambda i: f"vertex {i:,} (counting from 0, line {vertex_lines[i]:,})",
        face=lambda i: f"the face on line {face_lines[source[i]]:,}",
    )


def _plain_head(data: bytes) -> tuple[int, int, int, int] | None:
    """Where the body starts, the line number of its first line, and the counts, for a file
    that starts with an ``OFF`` line and a counts line (nothing else on either)."""
    position, number, found = 0, 0, list[list[bytes]]()
    while len(found) < 2:
        end = data.find(b"\n", position)
        if end < 0:
            return None
        words = data[position:end].split()
        position, number = end + 1, number + 1
        if words:
            found.append(words)
    keyword, counts = found
    if keyword != [b"OFF"] or len(counts) != 3:
        return None
    if not all(word.isdigit() and len(word) < 19 for word in counts):  # else int() may refuse
        return None
    return position, number + 1, int(counts[0]), int(counts[1])


def _numbers_by_line(
    data: bytes, body: int
) -> tuple[NDArray[np.float64], NDArray[np.int32], NDArray[np.int64]] | None:
    """Every number after ``body``, how many each line holds and each line's length in bytes
    (its ``\\n`` included); ``None`` when a word is not a number."""
    chunks, counts, lengths = [], [], []
    position = body
    while position < len(data):
        end = data.find(b"\n", position + _CHUNK)
        end = len(data) if end < 0 else end + 1
        chunk = data[position:end]
        if chunk.translate(None, _PLAIN_BYTES) or chunk.count(b"\r") != chunk.count(b"\r\n"):
            return None
        lines = chunk.split(b"\n")
        if lines[-1] == b"":
            lines.pop()  # after the last line end
        words = [line.split() for line in lines]
        counts.append(np.fromiter(map(len, words), np.int32, len(words)))
        lengths.append(np.fromiter((len(line) + 1 for line in lines), np.int64, len(lines)))
        try:
            chunks.append(np.array([word for row in words for word in row], dtype=np.float64))
        except ValueError:
            return None
        position = end
    if not chunks:
        return np.zeros(0), np.zeros(0, np.int32), np.zeros(0, np.int64)
    return np.concatenate(chunks), np.concatenate(counts), np.concatenate(lengths)


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


def write_off(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_colors: NDArray[np.generic] | None = None,
    face_colors: NDArray[np.generic] | None = None,
    normals: NDArray[np.float64] | None = None,
    normals_kind: str | None = None,
) -> bytes:
    """ASCII OFF: coordinates in the shortest text that reads back as the same float64,
    ``NOFF`` vertex normals after them, ``COFF`` colours after those (uint8 as integers
    0-255, anything else as floats 0-1), and face colours after each face's corners.

    Parameters
    ----------
    points : (n, 3) float64
    triangles : (m, 3) intp
    vertex_colors : (n, 3) or (n, 4), optional
    face_colors : (m, 3) or (m, 4), optional
    normals : (n, 3) float64, optional
        Vertex normals (``normals_kind`` ``"vertex"``, the only kind OFF holds).
    """
    columns = [points]
    if normals is not None and normals_kind == "vertex":
        columns.append(normals)
    keyword = ("C" if vertex_colors is not None else "") + ("N" if len(columns) > 1 else "")
    # A chunk of rows at a time into one buffer: the text of every line at once, as strings,
    # is several times the file.
    out = io.BytesIO()
    out.write(f"{keyword}OFF\n# written by {MAKER}\n{len(points)} {len(triangles)} 0\n".encode())
    for start in range(0, len(points), _CHUNK):
        part = slice(start, start + _CHUNK)
        rows = _rows(np.concatenate([column[part] for column in columns], axis=1))
        _write_lines(out, rows, None if vertex_colors is None else vertex_colors[part])
    for start in range(0, len(triangles), _CHUNK):
        part = slice(start, start + _CHUNK)
        rows = [f"3 {a} {b} {c}" for a, b, c in triangles[part].tolist()]
        _write_lines(out, rows, None if face_colors is None else face_colors[part])
    return out.getvalue()


#: Rows written at once by :func:`write_off`.
_CHUNK = 1 << 16


def _write_lines(out: io.BytesIO, rows: list[str], colors: NDArray[np.generic] | None) -> None:
    """``rows``, each with its colour after it when there are colours, a line each."""
    if colors is not None:
        rows = [f"{row} {color}" for row, color in zip(rows, _color_rows(colors), strict=True)]
    out.write(("\n".join(rows) + "\n").encode())


def _rows(values: NDArray[np.float64]) -> list[str]:
    return [" ".join(map(repr, row)) for row in values.tolist()]


def _color_rows(colors: NDArray[np.generic]) -> list[str]:
    """Colours as OFF text: uint8 as integers, the rest as floats 0-1."""
    if colors.dtype == np.uint8:
        return [" ".join(map(str, row)) for row in colors.tolist()]
    from mesh_normal.files.obj import unit_colors

    return _rows(unit_colors(colors))
