"""OBJ, read by our own parser (every ``v`` kept, in file order) and written exactly.

trimesh's OBJ loader, even with ``process=False``, drops vertices no face uses and splits
vertices where texture coordinates differ (a seam), so its arrays no longer line up with the
file's. Here ``v x y z [w]`` keeps x, y, z, and ``v x y z r g b`` (MeshLab, ZBrush) the
colours too when every ``v`` line has them; ``f`` takes ``v``, ``v/vt``, ``v//vn`` and
``v/vt/vn`` corners with 1-based or negative (relative) indices, polygons fan-triangulated;
``vt`` is only counted; ``l`` and ``p`` are skipped with a note; ``s``, ``usemtl``,
``mtllib`` and other statements are ignored; a backslash at a line's end continues it. Errors
name the line.

Groups: each face belongs to the latest ``o`` (object) and ``g`` (group) before it, named
``"object"``, ``"group"`` or ``"object/group"`` when both are given (an ``o`` ends the group
before it, and so does a ``g`` without a name; ``g`` with several names keeps them, ``"a b"``).
Faces before any are in ``"default"``, as the OBJ specification names it; the same name again
is the same group. A file without ``o`` and ``g`` has no groups.

Normals: per corner when every face corner names a ``vn``; per vertex as well when each vertex
is always given the same normal vector.
"""

from __future__ import annotations

import os
from collections import Counter, deque
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal._core import scan_obj
from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.formats import MAKER
from mesh_normal.files.loaded import LoadedMesh, build
from mesh_normal.files.polygons import triangulate

if TYPE_CHECKING:
    from concurrent.futures import Future, ThreadPoolExecutor

_IGNORED = {
    "s",
    "usemtl",
    "mtllib",
    "vp",
    "cstype",
    "deg",
    "curv",
    "surf",
    "parm",
    "end",
    "mg",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "shadow_obj",
    "trace_obj",
}


#: Statements the mesh does not carry, which every file written from it leaves out.
_UNKEPT = {
    "vt": "texture coordinates",
    "mtllib": "material libraries",
    "usemtl": "materials",
    "s": "smoothing groups",
}

_KINDS = {"v ": 1, "vn": 2, "vt": 3, "f ": 4, "o ": 5, "g ": 6, "": 0}
_KEYS = {"v": 1, "vn": 2, "vt": 3, "f": 4, "o": 5, "g": 6, "l": 7, "p": 8}
IGNORE, VERTEX, NORMAL, TEXTURE, FACE, OBJECT, GROUP, LINE, POINT, OTHER = range(10)
_DEFAULT_GROUP = "default"


@dataclass(frozen=True, slots=True)
class _Statements:
    """The file's ``v``, ``vn`` and ``f`` statements, with their line numbers.

    Attributes
    ----------
    vertices : (n, 3) float64
    vertex_lines : (n,) intp
    colors : (n, 3) float64 or None
        ``r g b`` after the coordinates, when every ``v`` line has exactly six numbers.
    normals : (k, 3) float64
    vertex_fields : (c,) int64
        The vertex index of every face corner as written (1-based or negative).
    normal_fields : (c,) int64 or None
        Its normal index, when every corner has one.
    counts : (p,) intp
        Corners of each face.
    face_lines : (p,) intp
    vertices_before, normals_before : (p,) intp
        How many ``v`` and ``vn`` statements come before each face (for negative indices).
    face_labels : (p,) intp or None
        Each face's group, an index into ``labels``; ``None`` without ``o`` and ``g``.
    labels : list of str
    notes : list of str
    unkept : list of str
        What the mesh will not carry (texture coordinates, materials, smoothing groups).
    """

    vertices: NDArray[np.float64]
    vertex_lines: NDArray[np.intp]
    colors: NDArray[np.float64] | None
    normals: NDArray[np.float64]
    vertex_fields: NDArray[np.int64]
    normal_fields: NDArray[np.int64] | None
    counts: NDArray[np.intp]
    face_lines: NDArray[np.intp]
    vertices_before: NDArray[np.intp]
    normals_before: NDArray[np.intp]
    face_labels: NDArray[np.intp] | None
    labels: list[str]
    notes: list[str]
    unkept: list[str]


def read_obj(data: bytes) -> LoadedMesh:
    """Read an OBJ file (see the module docstring)."""
    found = _scan(data)
    vertices, counts = found.vertices, found.counts
    vertex_ids, normal_ids = _corner_indices(found)
    positions, source, notes = triangulate(counts, vertex_ids, vertices)
    faces = vertex_ids[positions]
    face_line = found.face_lines[source]
    face_groups, group_names = _triangle_groups(found, source)
    corner_normals = vertex_normals = None
    if normal_ids is not None and len(faces):
        corner_normals = found.normals[normal_ids[positions]]
        vertex_normals = _per_vertex(faces, corner_normals, len(vertices))
    return build(
        "obj",
        vertices,
        faces,
        source_faces=len(counts),
        corner_normals=corner_normals,
        vertex_normals=vertex_normals,
        face_groups=face_groups,
        group_names=group_names,
        vertex_colors=found.colors,
        notes=[*notes, *found.notes],
        unkept=found.unkept,
        vertex=lambda i: f"vertex {i + 1:,} (line {found.vertex_lines[i]:,})",
        face=lambda i: f"the face on line {face_line[i]:,}",
    )


def _logical_lines(text: str) -> tuple[list[str], NDArray[np.intp], int]:
    """The lines, with backslash continuations joined, and each one's 1-based line number
    (of its first physical line), and the count of physical lines.

    Spaces after the backslash still continue (editors leave them and nobody sees them). A
    comment line ending in a backslash does not: it would silently swallow the statement
    after it, and comments end in one innocently (``# saved in C:\\models\\``).
    """
    lines = text.splitlines()
    if "\\" not in text:
        return lines, np.arange(1, len(lines) + 1), len(lines)
    joined: list[str] = []
    numbers: list[int] = []
    pending: list[str] = []
    for number, line in enumerate(lines, 1):
        end = line.rstrip()
        if end.endswith("\\") and (pending or not end.lstrip().startswith("#")):
            pending.append(end[:-1])
            continue
        numbers.append(number - len(pending))
        joined.append(" ".join([*pending, line]))
        pending = []
    if pending:
        numbers.append(len(lines) - len(pending) + 1)
        joined.append(" ".join(pending))
    return joined, np.asarray(numbers, dtype=np.intp), len(lines)


#: Bytes of the file scanned at once (cut at a line end): the lines and words of a chunk, not
#: of the file, are held as strings (several times their text).
_TEXT_CHUNK = 1 << 20


def _text_chunks(data: bytes) -> Iterator[tuple[int, int]]:
    """The file in chunks of about ``_TEXT_CHUNK`` bytes, ``(start, end)``, each ending at a
    line end whose line does not end in a backslash (so a continued line stays in one chunk)."""
    position = 0
    while position < len(data):
        end = data.find(b"\n", position + _TEXT_CHUNK)
        while end >= 0 and data[data.rfind(b"\n", 0, end) + 1 : end].rstrip().endswith(b"\\"):
            end = data.find(b"\n", end + 1)
        end = len(data) if end < 0 else end + 1
        yield position, end
        position = end


@dataclass
class _Groups:
    """The ``o`` and ``g`` state carried from chunk to chunk (see :func:`_face_labels`)."""

    labels: list[str]
    index: dict[str, int]
    thing: str = ""
    group: str = ""
    latest: int = 0  # the label of the last statement so far ("default" before any)
    seen: bool = False


def _scan(data: bytes) -> _Statements:
    """Every statement of the file, a chunk of text at a time (see :func:`_scan_chunk`)."""
    groups = _Groups([_DEFAULT_GROUP], {_DEFAULT_GROUP: 0})
    other: Counter[str] = Counter()
    ignored: Counter[str] = Counter()
    chunks: list[_Chunk] = []
    offset = vertices = normals = 0
    spans = list(_text_chunks(data))
    with _prescans(data, spans) as scans:
        for (start, end), read in zip(spans, scans, strict=True):
            chunk = None
            if read is not None:
                chunk = _scan_fast(read, offset, vertices, normals, groups, other, ignored)
            if chunk is None:
                text = data[start:end].decode("latin-1")
                chunk = _scan_chunk(text, offset, vertices, normals, groups, other, ignored)
                del text
            offset, vertices, normals = (
                chunk.lines_after,
                vertices + len(chunk.vertices),
                normals + len(chunk.normals),
            )
            chunks.append(chunk)
    faced = [chunk for chunk in chunks if len(chunk.counts)]
    colored = [chunk.colors for chunk in chunks if len(chunk.vertices)]
    normal_fields = [chunk.normal_fields for chunk in faced]
    return _Statements(
        vertices=_joined([chunk.vertices for chunk in chunks], (0, 3), np.float64),
        vertex_lines=_joined([chunk.vertex_lines for chunk in chunks], (0,), np.intp),
        colors=None
        if not colored or any(part is None for part in colored)
        else np.concatenate(colored),  # type: ignore[arg-type]
        normals=_joined([chunk.normals for chunk in chunks], (0, 3), np.float64),
        vertex_fields=_joined([chunk.vertex_fields for chunk in faced], (0,), np.int64),
        normal_fields=None
        if not faced or any(part is None for part in normal_fields)
        else np.concatenate(normal_fields),  # type: ignore[arg-type]
        counts=_joined([chunk.counts for chunk in faced], (0,), np.intp),
        face_lines=_joined([chunk.face_lines for chunk in chunks], (0,), np.intp),
        vertices_before=_joined([chunk.vertices_before for chunk in chunks], (0,), np.intp),
        normals_before=_joined([chunk.normals_before for chunk in chunks], (0,), np.intp),
        face_labels=None
        if not groups.seen
        else _joined(
            [
                np.zeros(len(chunk.counts), np.intp) if chunk.labels is None else chunk.labels
                for chunk in chunks
            ],
            (0,),
            np.intp,
        ),
        labels=groups.labels if groups.seen else [],
        notes=_skipped(other),
        unkept=[
            f"{words} ({count:,} {key})"
            for key, words in _UNKEPT.items()
            if (count := ignored[key])
        ],
    )


def _joined(parts: list[NDArray[Any]], empty: tuple[int, ...], dtype: type) -> NDArray[Any]:
    """The chunks' arrays as one (a chunk's own when there is one)."""
    if not parts:
        return np.zeros(empty, dtype)
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


@dataclass(frozen=True, slots=True)
class _Chunk:
    """One chunk's statements (see :class:`_Statements`); ``labels`` ``None`` before any
    ``o`` or ``g``."""

    lines_after: int
    vertices: NDArray[np.float64]
    vertex_lines: NDArray[np.intp]
    colors: NDArray[np.float64] | None
    normals: NDArray[np.float64]
    vertex_fields: NDArray[np.int64]
    normal_fields: NDArray[np.int64] | None
    counts: NDArray[np.intp]
    face_lines: NDArray[np.intp]
    vertices_before: NDArray[np.intp]
    normals_before: NDArray[np.intp]
    labels: NDArray[np.intp] | None


def _scan_chunk(
    text: str,
    offset: int,
    vertex_total: int,
    normal_total: int,
    groups: _Groups,
    other: Counter[str],
    ignored: Counter[str],
) -> _Chunk:
    """The statements of one chunk of text whose first line is line ``offset + 1``, after
    ``vertex_total`` ``v`` and ``normal_total`` ``vn`` statements; ``other`` and ``ignored``
    count what is skipped."""
    lines, numbers, physical = _logical_lines(text)
    del text  # the lines hold it now
    numbers += offset
    # Most lines start "v ", "vn", "vt" or "f ": classify those by their first two characters,
    # and only the rest (comments, groups, indented or tab-separated lines) by splitting.
    kinds = np.fromiter((_KINDS.get(line[:2], -1) for line in lines), np.int8, len(lines))
    chunk_ignored: Counter[str] = Counter()
    for row in np.flatnonzero(kinds < 0):
        kinds[row] = _split_kind(lines[row], other, chunk_ignored)
    chunk_ignored["vt"] = int(np.count_nonzero(kinds == TEXTURE))
    ignored.update(chunk_ignored)
    rows = {kind: np.flatnonzero(kinds == kind) for kind in (VERTEX, NORMAL, FACE)}
    labels = _face_labels(
        lines, np.flatnonzero(np.isin(kinds, (OBJECT, GROUP))), rows[FACE], groups
    )
    vertex_text = [lines[row] for row in rows[VERTEX]]
    vertices = _numbers(vertex_text, numbers[rows[VERTEX]], "v")
    normals = _numbers([lines[row] for row in rows[NORMAL]], numbers[rows[NORMAL]], "vn")
    colors = _vertex_colors(vertex_text)
    del vertex_text
    vertex_fields, normal_fields, counts = _face_fields(lines, rows[FACE], numbers)
    return _Chunk(
        lines_after=offset + physical,
        vertices=vertices,
        vertex_lines=numbers[rows[VERTEX]],
        colors=colors,
        normals=normals,
        vertex_fields=vertex_fields,
        normal_fields=normal_fields,
        counts=counts,
        face_lines=numbers[rows[FACE]],
        vertices_before=vertex_total + np.searchsorted(rows[VERTEX], rows[FACE]),
        normals_before=normal_total + np.searchsorted(rows[NORMAL], rows[FACE]),
        labels=labels,
    )


def _split_kind(line: str, other: Counter[str], unkept: Counter[str]) -> int:
    """The kind of a line that its first two characters do not settle, by its first word;
    ``other`` counts the statements skipped with a note, ``unkept`` those the mesh drops."""
    parts = line.split(None, 1)
    key = parts[0] if parts else ""
    kind = _KEYS.get(key, IGNORE if not key or key[0] == "#" or key in _IGNORED else OTHER)
    if kind >= LINE:
        other[key] += 1
    elif key in _UNKEPT:
        unkept[key] += 1
    return kind


#: The most threads that scan an OBJ file's chunks at once (:func:`_prescans`).
SCAN_THREADS = 4

#: What the compiled scan reads in a chunk (:func:`_prescan`): each line's kind (those it
#: leaves to Python marked -1), the ``v`` coordinates, their colours (when every ``v`` has six
#: numbers), the ``vn`` vectors, each corner's vertex index and normal index (when every corner
#: has one), the corners of each face, and the text of each line left to Python by its row.
ObjChunk = tuple[
    NDArray[np.int8],
    NDArray[np.float64],
    NDArray[np.float64] | None,
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.int64] | None,
    NDArray[np.intp],
    dict[int, str],
]


@contextmanager
def _prescans(data: bytes, spans: list[tuple[int, int]]) -> Iterator[Iterator[ObjChunk | None]]:
    """What the compiled scan reads in each chunk, in order (``None`` for a chunk it declines:
    those are read in Python).

    The chunks are scanned ahead on up to ``SCAN_THREADS`` threads (the scan releases the
    GIL), while the caller takes each result in turn: a chunk depends on the ones before only
    for its line and vertex numbers, which the caller adds. At most twice as many chunks as
    threads are scanned ahead of the caller, so the scans' results cost no more memory than
    the chunks they replace."""
    threads = max(1, min(SCAN_THREADS, len(spans), len(os.sched_getaffinity(0))))

    def scan(span: tuple[int, int]) -> ObjChunk | None:
        return _prescan(data, *span)

    if threads == 1:
        yield map(scan, spans)
        return
    from concurrent.futures import ThreadPoolExecutor  # here: 6 ms of imports, for large files

    with ThreadPoolExecutor(threads, thread_name_prefix="mesh-normal-obj") as pool:
        yield _ahead(pool, scan, spans, 2 * threads)


def _prescan(data: bytes, start: int, end: int) -> ObjChunk | None:
    """What the compiled scan (:func:`mesh_normal._core.scan_obj`) reads in the whole lines
    ``data[start:end]``, or ``None`` where it declines: a number or corner it does not read
    exactly as the Python path does, a character at which Python splits lines and it does not,
    or a continued line, which the Python path joins."""
    if data.find(b"\\", start, end) >= 0:
        return None
    read = scan_obj(np.frombuffer(data, np.uint8, end - start, start))
    if read is None:
        return None
    kinds, vertices, colors, normals, vertex_ids, normal_ids, counts, unknown = read
    texts = {row: data[start + a : start + b].decode("latin-1") for row, a, b in unknown.tolist()}
    return kinds, vertices, colors, normals, vertex_ids, normal_ids, counts, texts


def _ahead(
    pool: ThreadPoolExecutor,
    scan: Callable[[tuple[int, int]], ObjChunk | None],
    spans: list[tuple[int, int]],
    depth: int,
) -> Iterator[ObjChunk | None]:
    """The results of ``scan`` over ``spans`` in order, with ``depth`` of them running ahead."""
    waiting: deque[Future[ObjChunk | None]] = deque()
    for span in spans:
        waiting.append(pool.submit(scan, span))
        if len(waiting) >= depth:
            yield waiting.popleft().result()
    while waiting:
        yield waiting.popleft().result()


def _scan_fast(
    read: ObjChunk,
    offset: int,
    vertex_total: int,
    normal_total: int,
    groups: _Groups,
    other: Counter[str],
    ignored: Counter[str],
) -> _Chunk | None:
    """What :func:`_scan_chunk` finds in a chunk, read by the compiled scan (:func:`_prescan`);
    ``None`` (nothing counted, nothing changed) where it cannot certify the chunk: a line
    continued, a number or corner it does not read exactly as the Python path does, an
    indented ``v``, a character that Python splits lines or words at and the scan does not.
    ``read`` is what the scan read there (see :func:`_prescans`)."""
    kinds, vertices, colors, normals, vertex_fields, normal_fields, counts, texts = read
    chunk_other: Counter[str] = Counter()
    chunk_ignored: Counter[str] = Counter()
    statements: dict[int, str] = {}
    for row, text in texts.items():
        kind = _KINDS.get(text[:2], -1)
        if kind < 0:
            kind = _split_kind(text, chunk_other, chunk_ignored)
        if kind in (VERTEX, NORMAL, TEXTURE, FACE):
            return None  # "v\t1 2 3", " f 1 2 3": the Python path reads those
        if kind in (OBJECT, GROUP):
            statements[row] = text
        kinds[row] = kind
    chunk_ignored["vt"] = int(np.count_nonzero(kinds == TEXTURE))
    other.update(chunk_other)
    ignored.update(chunk_ignored)
    numbers = np.arange(offset + 1, offset + 1 + len(kinds), dtype=np.intp)
    rows = {kind: np.flatnonzero(kinds == kind) for kind in (VERTEX, NORMAL, FACE)}
    labels = _face_labels(statements, np.array(sorted(statements), np.intp), rows[FACE], groups)
    return _Chunk(
        lines_after=offset + len(kinds),
        vertices=vertices,
        vertex_lines=numbers[rows[VERTEX]],
        colors=colors,
        normals=normals,
        vertex_fields=vertex_fields,
        normal_fields=normal_fields,
        counts=counts,
        face_lines=numbers[rows[FACE]],
        vertices_before=vertex_total + np.searchsorted(rows[VERTEX], rows[FACE]),
        normals_before=normal_total + np.searchsorted(rows[NORMAL], rows[FACE]),
        labels=labels,
    )


def _face_labels(
    lines: Mapping[int, str] | list[str],
    statements: NDArray[np.intp],
    faces: NDArray[np.intp],
    groups: _Groups,
) -> NDArray[np.intp] | None:
    """Each face's group (see the module docstring), from the rows of the ``o`` and ``g``
    statements and of the faces in a chunk, ``groups`` the state before it (updated);
    ``None`` before any statement."""
    if not len(statements):
        return None if not groups.seen else np.full(len(faces), groups.latest, dtype=np.intp)
    before = groups.latest
    current = np.empty(len(statements), dtype=np.intp)
    for position, row in enumerate(statements.tolist()):
        keyword, *names = lines[row].partition("#")[0].split()
        name = " ".join(names)
        if keyword == "o":
            groups.thing, groups.group = name, ""
        else:
            groups.group = name
        label = "/".join(part for part in (groups.thing, groups.group) if part) or _DEFAULT_GROUP
        current[position] = groups.index.setdefault(label, len(groups.labels))
        if len(groups.labels) < len(groups.index):
            groups.labels.append(label)
    groups.latest, groups.seen = int(current[-1]), True
    latest = np.searchsorted(statements, faces) - 1  # the last statement before each face
    return np.where(latest >= 0, current[np.maximum(latest, 0)], before)


def _triangle_groups(
    found: _Statements, source: NDArray[np.intp]
) -> tuple[NDArray[np.intp] | None, list[str] | None]:
    """Each triangle's group, numbered by first triangle, and the names of groups with one."""
    if found.face_labels is None:
        return None, None
    used, first, numbered = np.unique(
        found.face_labels[source], return_index=True, return_inverse=True
    )
    order = np.argsort(first, kind="stable")  # number groups by their first triangle
    renumber = np.empty_like(order)
    renumber[order] = np.arange(len(order))
    return renumber[numbered.ravel()], [_utf8(found.labels[label]) for label in used[order]]


def _utf8(name: str) -> str:
    """A name read as Latin-1 (one character a byte) decoded as UTF-8, which nearly every
    writer uses today (``o Würfel``); as Latin-1 when its bytes are not UTF-8."""
    try:
        return name.encode("latin-1").decode("utf-8")
    except UnicodeDecodeError:
        return name


#: Lines converted at once: the words of a chunk, not of the file, are held as strings.
_CHUNK = 1 << 16


def _numbers(lines: list[str], numbers: NDArray[np.intp], key: str) -> NDArray[np.float64]:
    """The first three numbers after the keyword of each line, a chunk of lines at a time."""
    values = np.empty((len(lines), 3))
    for start in range(0, len(lines), _CHUNK):
        end = start + _CHUNK
        values[start:end] = _chunk_numbers(lines[start:end], numbers[start:end], key)
    return values


def _face_fields(
    lines: list[str], rows: NDArray[np.intp], numbers: NDArray[np.intp]
) -> tuple[NDArray[np.int64], NDArray[np.int64] | None, NDArray[np.intp]]:
    """Vertex and normal index of every corner (see :func:`_fields`) and the corners of each
    face, from the face lines ``rows``, a chunk of lines at a time."""
    vertex_parts: list[NDArray[np.int64]] = []
    normal_parts: list[NDArray[np.int64]] = []
    count_parts: list[NDArray[np.intp]] = []
    has_normals = True
    for start in range(0, len(rows), _CHUNK):
        chunk = rows[start : start + _CHUNK]
        # A comment may follow a face's corners: "f 1 2 3 # the lid".
        corners, counts = _face_corners(
            [lines[row].partition("#")[0] if "#" in lines[row] else lines[row] for row in chunk]
        )
        try:
            fields = _fields(corners)
        except _BadCorner as bad:
            face = int(np.searchsorted(np.cumsum(counts), bad.position, side="right"))
            raise _BadCorner(bad.corner, bad.position, int(numbers[chunk[face]])) from None
        del corners
        vertex_parts.append(fields[0])
        count_parts.append(counts)
        if fields[2] is None:
            has_normals = False
        elif has_normals:
            normal_parts.append(fields[2])
    if not rows.size:
        return np.zeros(0, np.int64), None, np.zeros(0, np.intp)
    normals = np.concatenate(normal_parts) if has_normals else None
    return np.concatenate(vertex_parts), normals, np.concatenate(count_parts)


def _chunk_numbers(lines: list[str], numbers: NDArray[np.intp], key: str) -> NDArray[np.float64]:
    tokens = " ".join(lines).split()
    width = len(tokens) // len(lines) if lines else 4
    try:
        if (
            width >= 4
            and len(tokens) == width * len(lines)  # all as wide: slice columns
            and tokens[::width].count(key) == len(lines)
        ):
            return np.stack(
                [np.array(tokens[column::width], dtype=np.float64) for column in (1, 2, 3)], axis=1
            )
        values = np.array([line.split()[1:4] for line in lines], dtype=np.float64)
        if values.shape == (len(lines), 3) or not lines:
            return values.reshape(-1, 3)
    except ValueError:
        pass
    for line, number in zip(lines, numbers, strict=True):
        words = line.split()[1:4]
        if len(words) < 3:
            raise MeshFileError(f"Line {number:,}: '{key}' needs 3 numbers, but has {len(words)}.")
        for value in words:
            try:
                float(value)
            except ValueError:
                raise MeshFileError(f"Line {number:,}: {value[:40]!r} is not a number.") from None
    raise AssertionError("unreachable: a line failed to convert")


def _vertex_colors(lines: list[str]) -> NDArray[np.float64] | None:
    """``r g b`` of ``v x y z r g b`` lines (MeshLab, ZBrush), when every ``v`` line has
    exactly six numbers; a file mixing widths, or ``v x y z w``, has no colours."""
    if not lines or len(lines[0].partition("#")[0].split()) != 7:
        return None  # the first line settles most files without a list of every line's words
    rows = [line.partition("#")[0].split()[4:] for line in lines]
    if any(len(row) != 3 for row in rows):
        return None
    try:
        return np.array(rows, dtype=np.float64)
    except ValueError:
        return None


def _face_corners(lines: list[str]) -> tuple[list[str], NDArray[np.intp]]:
    """Every corner token, and how many each face has (the ``f`` keywords split the faces)."""
    tokens = " ".join(lines).split()
    width = len(tokens) // len(lines) if lines else 4
    if len(tokens) == width * len(lines) and tokens[::width].count("f") == len(lines):
        del tokens[::width]
        return tokens, np.full(len(lines), width - 1, dtype=np.intp)
    # Line by line: a line continued into another "f" has that "f" as a corner (an error).
    words = [line.split() for line in lines]
    counts = np.array([len(line) - 1 for line in words], dtype=np.intp)
    return [word for line in words for word in line[1:]], counts


def _corner_indices(found: _Statements) -> tuple[NDArray[np.intp], NDArray[np.intp] | None]:
    """0-based vertex index of every corner, and normal index when every corner has one."""
    face_of_corner = np.repeat(np.arange(len(found.counts)), found.counts)
    vertex_ids = _resolve(
        found.vertex_fields,
        face_of_corner,
        found.vertices_before,
        found.face_lines,
        "vertex",
        len(found.vertices),
    )
    normal_ids = None
    if found.normal_fields is not None:
        normal_ids = _resolve(
            found.normal_fields,
            face_of_corner,
            found.normals_before,
            found.face_lines,
            "normal",
            len(found.normals),
        )
    return vertex_ids, normal_ids


#: Vertex, texture and normal index of every corner.
_Fields = tuple[NDArray[np.int64], NDArray[np.int64] | None, NDArray[np.int64] | None]


def _fields(corners: list[str]) -> _Fields:
    """Vertex, texture and normal index of every corner as written (0 where a field is empty,
    ``None`` for the normal unless every corner has one, and for texture indices when the
    form is uniform: they are not used).

    When every corner has the same form (``v``, ``v/vt``, ``v/vt/vn``, ``v//vn`` or ``v//``),
    all are split at once; anything else, corner by corner.
    """
    text = " ".join(corners)
    slashes, count = text.count("/"), len(corners)
    try:
        if not slashes:
            return _ints(text.split()), None, None
        per_corner = slashes // count if slashes in (count, 2 * count) else 0
        if per_corner and _same_slashes(text, per_corner, count):
            # Now each corner is a/b (one slash) or a/b/c (two); empty fields show as fewer
            # numbers, and "//" (an empty b) in every corner or in none settles which.
            tokens, doubles = text.replace("/", " ").split(), text.count("//")
            if per_corner == 1 and len(tokens) == 2 * count:  # v/vt
                return _ints(tokens[0::2]), None, None
            if not doubles and len(tokens) == 3 * count:  # v/vt/vn
                return _ints(tokens[0::3]), None, _ints(tokens[2::3])
            if doubles == count and len(tokens) == 2 * count:  # v//vn
                return _ints(tokens[0::2]), None, _ints(tokens[1::2])
            # v//: "//5 1//" has one number a corner too, so every corner must end "//".
            if doubles == count and len(tokens) == count and _every_corner_ends(text, "//"):
                return _ints(tokens), None, None
    except ValueError:
        pass
    return _mixed_fields(corners)


def _same_slashes(text: str, slashes: int, count: int) -> bool:
    """Whether each of the ``count`` space-separated corners in ``text`` has ``slashes``."""
    separators = text.encode("latin-1").translate(None, _NOT_SEPARATORS)
    return separators == (b"/" * slashes + b" ") * (count - 1) + b"/" * slashes


#: Every byte but the space and the slash, for :func:`_same_slashes` to delete.
_NOT_SEPARATORS = bytes(code for code in range(256) if code not in b" /")


def _every_corner_ends(text: str, end: str) -> bool:
    """Whether every space-separated corner in ``text`` ends with ``end``."""
    return text.endswith(end) and text.count(end + " ") == text.count(" ")


def _ints(tokens: list[str]) -> NDArray[np.int64]:
    return np.array(tokens, dtype=np.int64)


def _mixed_fields(corners: list[str]) -> _Fields:
    """Corner by corner: any field may be empty (``1/``, ``1//``, ``1//3``, ``1/2/``), as
    other readers allow; a corner without a normal drops the normals of the whole file."""
    columns: list[list[int]] = [[], [], []]
    has_normal = True
    for position, corner in enumerate(corners):
        parts = corner.split("/")
        if len(parts) > 3 or not parts[0]:
            raise _BadCorner(corner, position)
        parts += [""] * (3 - len(parts))
        has_normal = has_normal and parts[2] != ""
        for column, part in zip(columns, parts, strict=True):
            try:
                column.append(int(part) if part else 0)
            except ValueError:
                raise _BadCorner(corner, position) from None
    arrays = [np.array(column, dtype=np.int64) for column in columns]
    return arrays[0], arrays[1], arrays[2] if has_normal else None


class _BadCorner(MeshFileError):
    """A corner that is not ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``; :func:`_corner_indices`
    adds its line from ``position`` (its place among all corners)."""

    def __init__(self, corner: str, position: int, line: int | None = None) -> None:
        self.corner, self.position = corner, position
        where = f" (line {line:,})" if line is not None else ""
        super().__init__(
            f"The face corner {corner[:40]!r} is not an index, nor index/texture, "
            f"index//normal or index/texture/normal{where}."
        )


def _resolve(
    written: NDArray[np.int64],
    face_of_corner: NDArray[np.intp],
    defined_before: NDArray[np.intp],
    face_lines: NDArray[np.intp],
    kind: str,
    total: int,
) -> NDArray[np.intp]:
    """1-based or negative (relative to what is defined so far) indices to 0-based ones."""
    before = defined_before[face_of_corner]
    resolved = np.where(written < 0, before + written, written - 1)
    bad = (written == 0) | (resolved < 0) | (resolved >= total)
    if bad.any():
        corner = int(np.argmax(bad))
        line = int(face_lines[face_of_corner[corner]])
        value = int(written[corner])
        if value == 0:
            raise MeshFileError(f"Line {line:,}: {kind} index 0 is not valid; OBJ counts from 1.")
        if value < 0:
            raise MeshFileError(
                f"Line {line:,}: {kind} index {value} reaches back before the "
                f"first {kind}; only {int(before[corner]):,} come before it."
            )
        raise MeshFileError(
            f"Line {line:,}: {kind} index {value:,} is out of range; the file "
            f"has {total:,} {kind} statements."
        )
    return resolved.astype(np.intp)


def _per_vertex(
    faces: NDArray[np.intp], corner_normals: NDArray[np.float64], count: int
) -> NDArray[np.float64] | None:
    """One normal per vertex, if every vertex is used and always given the same vector."""
    flat, normals = faces.ravel(), corner_normals.reshape(-1, 3)
    result = np.full((count, 3), np.nan)
    result[flat] = normals
    if np.isnan(result).any() or not np.array_equal(result[flat], normals):
        return None
    return result


def _skipped(other: Counter[str]) -> list[str]:
    notes = []
    lines, points = other.pop("l", 0), other.pop("p", 0)
    if lines or points:
        parts = [
            f"{count:,} {name}"
            for count, name in ((lines, "line ('l')"), (points, "point ('p')"))
            if count
        ]
        notes.append(f"Skipped {' and '.join(parts)} elements: only faces are read.")
    if other:
        names = ", ".join(f"'{key[:20]}' ({count:,})" for key, count in other.most_common(5))
        notes.append(f"Ignored statements this reader does not use: {names}.")
    return notes


def write_obj(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_colors: NDArray[np.generic] | None = None,
    normals: NDArray[np.float64] | None = None,
    normals_kind: str | None = None,
    face_groups: NDArray[np.intp] | None = None,
    group_names: tuple[str, ...] | None = None,
) -> bytes:
    """OBJ text: ``v`` lines in the shortest text that reads back as the same float64
    (Python's ``repr``), ``vn`` lines, then 1-based ``f`` lines, each group's run of faces
    after its ``g`` line. Vertex colours follow the coordinates as ``v x y z r g b`` (floats
    0-1, as MeshLab writes them); integer colours are scaled from their type's range, and
    alpha is not written (OBJ holds none: see :func:`~mesh_normal.files.write.unkept`).

    Parameters
    ----------
    points : (n, 3) float64
    triangles : (m, 3) intp
    vertex_colors : (n, 3) or (n, 4), optional
    normals : (n, 3), (m, 3) or (m, 3, 3) float64, optional
        Vertex, face or corner normals, as ``normals_kind`` says: one ``vn`` per vertex
        (``f a//a``), per face (``f a//k b//k c//k``), or per distinct corner normal.
    face_groups : (m,) intp, optional
        Each face's group, an index into ``group_names``: a run of faces in one group comes
        after ``o name`` (``o a`` then ``g b`` for ``"a/b"``), so the reader gives the same
        names back.
    """
    rows = (
        points
        if vertex_colors is None
        else np.concatenate([points, unit_colors(vertex_colors)[:, :3]], axis=1)
    )
    vn, corner_vn = _obj_normals(normals, normals_kind, triangles)
    # A chunk of lines at a time: the text of every line at once is several times the file.
    parts = [f"# written by {MAKER}\n".encode()]
    for keyword, values in (("v", rows), ("vn", vn)):
        for start in range(0, len(values), _CHUNK):
            numbers = values[start : start + _CHUNK].tolist()
            parts.append(
                "".join(f"{keyword} {' '.join(map(repr, row))}\n" for row in numbers).encode()
            )
    for start, stop, label in _group_runs(face_groups, group_names, len(triangles)):
        if label is not None:
            parts.append(_group_line(label).encode())
        for chunk in range(start, stop, _CHUNK):
            end = min(chunk + _CHUNK, stop)
            corners = (triangles[chunk:end] + 1).tolist()
            if corner_vn is None:
                parts.append("".join(f"f {a} {b} {c}\n" for a, b, c in corners).encode())
                continue
            ids = (corner_vn[chunk:end] + 1).tolist()
            parts.append(
                "".join(
                    f"f {a}//{p} {b}//{q} {c}//{r}\n"
                    for (a, b, c), (p, q, r) in zip(corners, ids, strict=True)
                ).encode()
            )
    return b"".join(parts)


def _obj_normals(
    normals: NDArray[np.float64] | None, kind: str | None, triangles: NDArray[np.intp]
) -> tuple[NDArray[np.float64], NDArray[np.intp] | None]:
    """The ``vn`` rows and each corner's index into them (``None`` without normals).

    Corner normals are written once per distinct vector: a smooth vertex's corners share one.
    """
    if normals is None:
        return np.zeros((0, 3)), None
    if kind == "vertex":
        return normals, triangles
    if kind == "face":
        return normals, np.repeat(np.arange(len(triangles), dtype=np.intp)[:, None], 3, axis=1)
    distinct, inverse = np.unique(normals.reshape(-1, 3), axis=0, return_inverse=True)
    return distinct, inverse.reshape(-1, 3).astype(np.intp)


def _group_runs(
    face_groups: NDArray[np.intp] | None, names: tuple[str, ...] | None, count: int
) -> list[tuple[int, int, str | None]]:
    """Runs of consecutive faces in one group: ``(start, stop, name)``; one run without
    groups. Faces keep their order: a group met again gets its ``g`` line again."""
    if face_groups is None or names is None or not count:
        return [(0, count, None)]
    starts = np.flatnonzero(np.r_[True, face_groups[1:] != face_groups[:-1]])
    stops = np.r_[starts[1:], count]
    return [
        (int(a), int(b), names[int(face_groups[a])]) for a, b in zip(starts, stops, strict=True)
    ]


def _group_line(label: str) -> str:
    """The statements that make the reader's ``label`` again: ``o`` starts afresh (it ends
    the group before it), so a plain name is an object, ``"o/g"`` an object and a group."""
    thing, slash, group = label.partition("/")
    return f"o {thing}\ng {group}\n" if slash else f"o {label}\n"


def unit_colors(colors: NDArray[np.generic]) -> NDArray[np.float64]:
    """Colours as float64 in 0-1: integers divided by their type's maximum (255 for uchar),
    floats as they are.

    Parameters
    ----------
    colors : (n, k) integer or float
    """
    values = colors.astype(np.float64)
    if colors.dtype.kind in "ui":
        top = np.iinfo(colors.dtype.str).max
        return values / float(top)
    return values
