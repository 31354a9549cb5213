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
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal._core import ObjChunk, scan_obj
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


#: Bytes of the file scanned at once (cut at a line end): chunks are scanned on several threads.
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
    """Every statement of the file, a chunk at a time (see :func:`_scans`)."""
    groups = _Groups([_DEFAULT_GROUP], {_DEFAULT_GROUP: 0})
    other: Counter[str] = Counter()
    ignored: Counter[str] = Counter()
    chunks: list[ObjChunk] = []
    labels: list[NDArray[np.intp] | None] = []
    # A chunk counts its lines, v and vn from its own start: these count from the file's.
    vertex_lines: list[NDArray[np.int64]] = []
    face_lines: list[NDArray[np.int64]] = []
    vertices_before: list[NDArray[np.int64]] = []
    normals_before: list[NDArray[np.int64]] = []
    lines = vertices = normals = 0
    with _scans(data, list(_text_chunks(data))) as scans:
        for chunk in scans:
            if chunk.failure is not None:
                raise _failure(*chunk.failure, lines)
            labels.append(_face_labels(chunk.groups, len(chunk.counts), groups))
            for key, count in chunk.skipped:
                name = key.decode("latin-1")
                if name not in _IGNORED:
                    other[name] += count
                elif name in _UNKEPT:
                    ignored[name] += count
            ignored["vt"] += chunk.textures
            chunks.append(chunk)
            vertex_lines.append(chunk.vertex_lines + lines)
            face_lines.append(chunk.face_lines + lines)
            vertices_before.append(chunk.vertices_before + vertices)
            normals_before.append(chunk.normals_before + normals)
            lines += chunk.lines
            vertices += len(chunk.vertices)
            normals += len(chunk.normals)
    faced = [chunk for chunk in chunks if len(chunk.counts)]
    colored = [chunk.colors for chunk in chunks if len(chunk.vertices)]
    normal_fields = [chunk.normal_ids for chunk in faced]
    return _Statements(
        vertices=_joined([chunk.vertices for chunk in chunks], (0, 3), np.float64),
        vertex_lines=_joined(vertex_lines, (0,), np.intp),
        colors=None
        if not colored or any(part is None for part in colored)
        else np.concatenate(colored),  # type: ignore[arg-type]
        normals=_joined([chunk.normals for chunk in chunks], (0, 3), np.float64),
        vertex_fields=_joined([chunk.vertex_ids for chunk in faced], (0,), np.int64),
        normal_fields=None
        if not faced or any(part is None for part in normal_fields)
        else np.concatenate(normal_fields),  # type: ignore[arg-type]
        counts=_joined([chunk.counts for chunk in faced], (0,), np.intp),
        face_lines=_joined(face_lines, (0,), np.intp),
        vertices_before=_joined(vertices_before, (0,), np.intp),
        normals_before=_joined(normals_before, (0,), np.intp),
        face_labels=None
        if not groups.seen
        else _joined(
            [
                np.zeros(len(chunk.counts), np.intp) if part is None else part
                for chunk, part in zip(chunks, labels, strict=True)
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


def _failure(code: int, line: int, text: bytes, number: int, offset: int) -> MeshFileError:
    """The sentence for what stopped the scan (see :class:`mesh_normal._core.ObjChunk`) on
    line ``line`` of the chunk after ``offset`` lines."""
    line += offset
    word = text.decode("latin-1")
    if code == _TOO_FEW:
        return MeshFileError(f"Line {line:,}: '{word}' needs 3 numbers, but has {number}.")
    if code == _NOT_A_NUMBER:
        return MeshFileError(f"Line {line:,}: {word[:40]!r} is not a number.")
    if code == _BAD_CORNER:
        return MeshFileError(
            f"The face corner {word[:40]!r} is not an index, nor index/texture, "
            f"index//normal or index/texture/normal (line {line:,})."
        )
    kind = "vertex" if number == 0 else "normal"
    return MeshFileError(f"Line {line:,}: {kind} index {word[:40]} is out of range.")


#: The codes of :attr:`mesh_normal._core.ObjChunk.failure`.
_TOO_FEW, _NOT_A_NUMBER, _BAD_CORNER, _TOO_LARGE = 1, 2, 3, 4


def _joined(parts: list[NDArray[Any]], empty: tuple[int, ...], dtype: type) -> NDArray[Any]:
    """The chunks' arrays as one (a chunk's own when there is one)."""
    if not parts:
        return np.zeros(empty, dtype)
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


#: The most threads that scan an OBJ file's chunks at once (:func:`_scans`).
SCAN_THREADS = 4


@contextmanager
def _scans(data: bytes, spans: list[tuple[int, int]]) -> Iterator[Iterator[ObjChunk]]:
    """What the compiled scan (:func:`mesh_normal._core.scan_obj`) reads in each chunk
    ``data[start:end]``, in order.

    The chunks are scanned ahead on up to ``SCAN_THREADS`` threads (the scan releases the
    GIL), while the caller takes each result in turn: a chunk depends on the ones before only
    for its line and vertex numbers, which the caller adds. At most twice as many chunks as
    threads are scanned ahead of the caller, so the scans' results cost no more memory than
    the chunks they replace."""
    threads = max(1, min(SCAN_THREADS, len(spans), len(os.sched_getaffinity(0))))

    def scan(span: tuple[int, int]) -> ObjChunk:
        start, end = span
        return scan_obj(np.frombuffer(data, np.uint8, end - start, start))

    if threads == 1:
        yield map(scan, spans)
        return
    from concurrent.futures import ThreadPoolExecutor  # here: 6 ms of imports, for large files

    with ThreadPoolExecutor(threads, thread_name_prefix="mesh-normal-obj") as pool:
        yield _ahead(pool, scan, spans, 2 * threads)


def _ahead(
    pool: ThreadPoolExecutor,
    scan: Callable[[tuple[int, int]], ObjChunk],
    spans: list[tuple[int, int]],
    depth: int,
) -> Iterator[ObjChunk]:
    """The results of ``scan`` over ``spans`` in order, with ``depth`` of them running ahead."""
    waiting: deque[Future[ObjChunk]] = deque()
    for span in spans:
        waiting.append(pool.submit(scan, span))
        if len(waiting) >= depth:
            yield waiting.popleft().result()
    while waiting:
        yield waiting.popleft().result()


def _face_labels(
    statements: list[tuple[bool, int, bytes]], faces: int, groups: _Groups
) -> NDArray[np.intp] | None:
    """Each face's group (see the module docstring) in a chunk of ``faces`` faces, from its
    ``o`` and ``g`` statements (``(is o, faces before it, name)``), ``groups`` the state before
    it (updated); ``None`` before any statement."""
    if not statements:
        return None if not groups.seen else np.full(faces, groups.latest, dtype=np.intp)
    before = groups.latest
    current = np.empty(len(statements), dtype=np.intp)
    starts = np.empty(len(statements), dtype=np.intp)
    for position, (is_object, start, name) in enumerate(statements):
        if is_object:
            groups.thing, groups.group = name.decode("latin-1"), ""
        else:
            groups.group = name.decode("latin-1")
        label = "/".join(part for part in (groups.thing, groups.group) if part) or _DEFAULT_GROUP
        current[position] = groups.index.setdefault(label, len(groups.labels))
        starts[position] = start
        if len(groups.labels) < len(groups.index):
            groups.labels.append(label)
    groups.latest, groups.seen = int(current[-1]), True
    # The last statement before each face.
    latest = np.searchsorted(starts, np.arange(faces), side="right") - 1
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


#: Lines written at once: the text of a chunk of lines, not of the file, is held as strings.
_CHUNK = 1 << 16


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
