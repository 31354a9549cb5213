"""PLY, ASCII and binary (either endianness), read by our own parser.

trimesh's ``load_ply`` keeps vertex order, but it triangulates polygons grouped by size (all
triangles first, then quads, ...), not in file order, and drops face normals. Here every
element is read as the header declares it (fixed-size elements with one ``np.frombuffer``,
lists of one size too; mixed sizes record by record), vertices keep their order, faces are
fan-triangulated in file order, and ``nx ny nz`` on vertices or faces are kept. Triangle
strips (``element tristrips`` with a ``vertex_indices`` list, -1 restarting a strip, as classic
scanned models and trimesh2 write them) follow the faces as triangles with the OpenGL winding
(:func:`strip_triangles`); each record counts once in ``source_faces``, as a polygon does, and
a note says how many triangles the strips gave. Other elements are read past and named in a
note.

Vertex and face ``red green blue [alpha]`` are kept in the type the header declares (``uchar``
0-255 or ``float`` 0-1, say) and written back in it; each triangle of a polygon has its
polygon's colour.

Written as binary little-endian PLY with float64 coordinates (:func:`write_ply`), and with
vertex or face normals or colours beside them (:func:`ply_bytes`).
"""

from __future__ import annotations

import struct
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, TypeGuard

import numpy as np
from numpy.lib.recfunctions import structured_to_unstructured
from numpy.typing import NDArray

from mesh_normal._core import binary_items
from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.formats import MAKER
from mesh_normal.files.loaded import LoadedMesh, build
from mesh_normal.files.polygons import triangulate

_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
_ENDIAN = {"binary_little_endian": "<", "binary_big_endian": ">", "ascii": "="}
_NORMAL = ("nx", "ny", "nz")
_COLOR = ("red", "green", "blue", "alpha")
#: The PLY name of each type a colour is written in (others are written as float64).
_TYPE_NAMES = {"u1": "uchar", "u2": "ushort", "f4": "float", "f8": "double"}


@dataclass(slots=True)
class _Element:
    name: str
    count: int
    scalars: list[tuple[str, str]] = field(default_factory=list)  # (name, type) in order
    lists: dict[str, tuple[str, str]] = field(default_factory=dict)  # name: (count, item)
    order: list[str] = field(default_factory=list)  # every property name in order
    data: dict[str, object] = field(default_factory=dict)
    records: NDArray[np.void] | None = None  # a binary element of scalars, as read


def read_ply(data: bytes) -> LoadedMesh:
    """Read a PLY file (see the module docstring)."""
    elements, notes = read_elements(data)
    return _mesh(elements, notes)


#: One element of a PLY file as read: ``name``, ``count``, ``scalars`` (name and NumPy type
#: code of each scalar property, in order) and ``data`` (property name to its column).
PlyElement = _Element


def read_elements(data: bytes) -> tuple[list[PlyElement], list[str]]:
    """Every element of a PLY file, read as its header declares it, and the reading notes;
    no mesh is built (a point cloud's reader takes the vertex element alone)."""
    encoding, elements, body = _header(data)
    notes = []
    if encoding == "ascii":
        _check_words(elements, len(data) - body)
        notes = _read_ascii(elements, data[body:])
    else:
        _read_binary(elements, data, body, _ENDIAN[encoding])
    return elements, notes


def _check_words(elements: list[_Element], size: int) -> None:
    """Refuse, before allocating, counts that ``size`` bytes of text cannot hold: each number
    takes a character and a separator, so a header claiming a billion vertices over a few
    lines is found cheaply (the binary reader compares sizes the same way)."""
    room = (size + 1) // 2
    for element in elements:
        room -= element.count * len(element.order)
        if room < 0:
            raise MeshFileError(
                f"The PLY header says {element.count:,} {element.name} elements, but the "
                "file is too short to hold them: it looks truncated."
            )


def _header(data: bytes) -> tuple[str, list[_Element], int]:
    end = data.find(b"end_header")
    if end < 0:
        raise MeshFileError(
            "The PLY header has no 'end_header' line: the file is cut short or not PLY."
        )
    body = data.find(b"\n", end) + 1 or len(data)
    lines = data[:end].decode("latin-1").splitlines()[1:]
    encoding, elements = None, []
    for number, line in enumerate(lines, 2):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        try:
            if words[0] == "format":
                encoding = words[1]
                if encoding not in _ENDIAN:
                    raise MeshFileError(
                        f"Line {number}: the PLY format {encoding[:30]!r} is "
                        "not ascii, binary_little_endian or binary_big_endian."
                    )
            elif words[0] == "element":
                elements.append(_Element(words[1], int(words[2])))
            elif words[0] == "property" and words[1] == "list":
                elements[-1].lists[words[4]] = (_type(words[2]), _type(words[3]))
                elements[-1].order.append(words[4])
            elif words[0] == "property":
                elements[-1].scalars.append((words[2], _type(words[1])))
                elements[-1].order.append(words[2])
        except MeshFileError:
            raise
        except (IndexError, ValueError, KeyError):
            raise MeshFileError(
                f"Line {number} of the PLY header cannot be read: {line[:60]!r}."
            ) from None
    if encoding is None:
        raise MeshFileError("The PLY header has no 'format' line.")
    if any(element.count < 0 for element in elements):
        raise MeshFileError("The PLY header declares an element with a negative count.")
    return encoding, elements, body


def _type(name: str) -> str:
    if name not in _TYPES:
        raise KeyError(name)
    return _TYPES[name]


def _read_binary(elements: list[_Element], data: bytes, offset: int, endian: str) -> None:
    for element in elements:
        if not element.lists:
            dtype = np.dtype([(name, endian + kind) for name, kind in element.scalars])
            offset = _frombuffer(element, data, dtype, offset)
        else:
            offset = _binary_lists(element, data, offset, endian)


def _frombuffer(element: _Element, data: bytes, dtype: np.dtype, offset: int) -> int:
    size = dtype.itemsize * element.count
    if offset + size > len(data):
        held = (len(data) - offset) // max(dtype.itemsize, 1)
        raise MeshFileError(
            f"The PLY header says {element.count:,} {element.name} elements, "
            f"but the file holds only {max(held, 0):,}: it looks truncated."
        )
    records = np.frombuffer(data, dtype, element.count, offset)
    element.data = {name: records[name] for name in dtype.names or ()}
    element.records = records
    return offset + size


def _binary_lists(element: _Element, data: bytes, offset: int, endian: str) -> int:
    """Lists of one size read at once; mixed sizes record by record."""
    first = _list_sizes(element, data, offset, endian) if element.count else None
    if first is not None:
        dtype = np.dtype(
            [
                (name, endian + _kind(element, name))
                if name not in element.lists
                else (
                    name,
                    [
                        ("count", endian + element.lists[name][0]),
                        ("items", endian + element.lists[name][1], (first[name],)),
                    ],
                )
                for name in element.order
            ]
        )
        if offset + dtype.itemsize * element.count <= len(data):
            records = np.frombuffer(data, dtype, element.count, offset)
            if all(np.all(records[name]["count"] == first[name]) for name in element.lists):
                element.data = {
                    name: _items(records, name, data, offset) if name in element.lists
                    else records[name]
                    for name in element.order
                }  # fmt: skip
                return offset + dtype.itemsize * element.count
    return _binary_records(element, data, offset, endian)


def _items(records: NDArray[np.void], name: str, data: bytes, offset: int) -> NDArray[Any]:
    """The items of the list ``name`` of binary records whose lists have one length: integers
    as int64, read by the compiled loop (:func:`mesh_normal._core.binary_items`: NumPy's cast
    of the records' unaligned, strided view takes three times as long); floats (and 64-bit
    integers) as the records' own view."""
    items = records[name]["items"]
    kind = items.dtype
    if kind.kind not in "iu" or kind.itemsize > 4:
        return items
    out = np.empty(items.shape, np.int64)
    fields, inner = records.dtype.fields, records.dtype[name].fields
    assert fields is not None and inner is not None  # records of named fields
    at = offset + fields[name][1] + inner["items"][1]
    view = np.frombuffer(data, np.uint8)
    little = kind.byteorder == "<" or (kind.byteorder in "=|" and sys.byteorder == "little")
    binary_items(view, at, records.dtype.itemsize, kind.itemsize, kind.kind == "i", little, out)
    return out


def _kind(element: _Element, name: str) -> str:
    return dict(element.scalars)[name]


def _list_sizes(element: _Element, data: bytes, offset: int, endian: str) -> dict[str, int] | None:
    """The list sizes of the first record, or ``None`` when the file ends inside it."""
    sizes = {}
    try:
        for name in element.order:
            if name in element.lists:
                count_type, item_type = element.lists[name]
                (count,) = struct.unpack_from(endian + _struct(count_type), data, offset)
                sizes[name] = int(count)
                offset += np.dtype(count_type).itemsize + count * np.dtype(item_type).itemsize
            else:
                offset += np.dtype(_kind(element, name)).itemsize
    except struct.error:
        return None
    return sizes


def _struct(kind: str) -> str:
    return {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "f4": "f", "f8": "d"}[
        kind
    ]


def _binary_records(element: _Element, data: bytes, offset: int, endian: str) -> int:
    columns: dict[str, list[object]] = {name: [] for name in element.order}
    readers = []
    for name in element.order:
        if name in element.lists:
            count_type, item_type = element.lists[name]
            readers.append(
                (
                    name,
                    struct.Struct(endian + _struct(count_type)),
                    endian + _struct(item_type),
                    np.dtype(item_type).itemsize,
                )
            )
        else:
            readers.append((name, struct.Struct(endian + _struct(_kind(element, name))), "", 0))
    try:
        for _ in range(element.count):
            for name, scalar, item, size in readers:
                (value,) = scalar.unpack_from(data, offset)
                offset += scalar.size
                if item:
                    columns[name].append(
                        struct.unpack_from(f"{endian}{value}{item[1:]}", data, offset)
                    )
                    offset += value * size
                else:
                    columns[name].append(value)
    except struct.error:
        raise MeshFileError(
            f"The PLY file ends inside its {element.name} elements: it looks truncated."
        ) from None
    element.data = {
        name: column if name in element.lists else np.array(column)
        for name, column in columns.items()
    }
    return offset


def _read_ascii(elements: list[_Element], body: bytes) -> list[str]:
    """Read the elements number by number; where that fails or leaves numbers over, line by
    line (:func:`_read_lines`), which reads files whose lines hold more than the header says.
    Returns the notes.

    The common file (every number where the header says, lists of one size) is read a chunk
    of words at a time (:func:`_read_chunks`); any other, as all its words at once."""
    if _read_chunks(elements, body):
        return []
    tokens = body.split()
    try:
        position = _read_tokens(elements, tokens)
    except MeshFileError:
        by_line = _read_lines(elements, body)
        if by_line is None:
            raise
        return _adopt(elements, *by_line)
    if position == len(tokens):
        return []
    by_line = _read_lines(elements, body)
    if by_line is not None and by_line[1]:
        return _adopt(elements, *by_line)
    return [f"Ignored {len(tokens) - position:,} numbers after the PLY file's last element."]


#: Bytes of the body split into words at once, for :func:`_read_chunks`.
_CHUNK = 1 << 20


def _word_chunks(body: bytes) -> Iterator[list[bytes]]:
    """The body's words, in chunks of about ``_CHUNK`` bytes cut at line ends."""
    position = 0
    while position < len(body):
        end = body.find(b"\n", position + _CHUNK)
        end = len(body) if end < 0 else end + 1
        yield body[position:end].split()
        position = end


def _read_chunks(elements: list[_Element], body: bytes) -> bool:
    """Read the elements as :func:`_read_tokens` does, a chunk of words at a time; ``False``
    (nothing kept) for any file where that would not give the same: a word that is not a
    number, lists of several sizes or one elements with other properties, numbers short or
    over. The list of every word (about 45 bytes each) is never made."""
    chunks = _word_chunks(body)
    words: list[bytes] = []
    found: list[dict[str, object]] = []
    for element in elements:
        if not element.lists:
            width = len(element.scalars)
            values, words = _take(chunks, words, width * element.count)
            if values is None:
                return False
            table = values.reshape(element.count, width)
            found.append(
                {name: table[:, i].astype(kind) for i, (name, kind) in enumerate(element.scalars)}
            )
        elif element.order == [*element.lists] and len(element.lists) == 1 and element.count:
            if not words:
                words = next(chunks, [])
            size = words[0] if words else b""
            if not size.isdigit() or len(size) >= 10:  # else int() may refuse it
                return False
            width = int(size) + 1
            values, words = _take(chunks, words, width * element.count, size, width)
            if values is None:
                return False
            found.append({element.order[0]: values.reshape(-1, width)[:, 1:]})
        else:
            return False
    if words or next(chunks, None) is not None:
        return False  # numbers over: _read_ascii says what it makes of them
    for element, data in zip(elements, found, strict=True):
        element.data = data
    return True


def _take(
    chunks: Iterator[list[bytes]],
    words: list[bytes],
    count: int,
    size: bytes | None = None,
    width: int = 1,
) -> tuple[NDArray[np.float64] | None, list[bytes]]:
    """The next ``count`` words as floats, and the words of the chunk left over; ``None`` when
    the words run out, one is not a number, or (``size``) a record of ``width`` words does not
    start with ``size``."""
    values = np.empty(count)
    filled = 0
    while filled < count:
        if not words:
            words = next(chunks, [])
            if not words:
                return None, []
        taken = words[: count - filled]
        if size is not None:
            first = -filled % width
            if taken[first::width].count(size) != len(range(first, len(taken), width)):
                return None, []
        try:
            values[filled : filled + len(taken)] = np.array(taken, dtype=np.float64)
        except ValueError:
            return None, []
        filled += len(taken)
        words = words[len(taken) :]
    return values, words


def _read_tokens(elements: list[_Element], tokens: list[bytes]) -> int:
    position = 0
    for element in elements:
        if not element.lists:
            width = len(element.scalars)
            end = position + width * element.count
            if end > len(tokens):
                raise _short(element, (len(tokens) - position) // max(width, 1))
            values = _floats(tokens[position:end]).reshape(element.count, width)
            # As declared: a float32 property holds the float32 nearest to its text.
            element.data = {
                name: values[:, i].astype(kind) for i, (name, kind) in enumerate(element.scalars)
            }
            position = end
        else:
            position = _ascii_lists(element, tokens, position)
    return position


#: What an element whose lines disagree with the header keeps: its position in space.
_GEOMETRY = frozenset({"x", "y", "z", "vertex_indices", "vertex_index"})


def _read_lines(
    elements: list[_Element], body: bytes
) -> tuple[list[dict[str, object]], list[str]] | None:
    """Each record from its own line, as PLY writers write them; ``None`` when the lines do
    not fit the header.

    A line may hold more numbers than the header declares (trimesh's ``fuze_ascii.ply``,
    written by MeshLab, ends each face with ten numbers where its header names four): then which
    number is which is unsure, so that element keeps only its coordinates or corner indices
    (every writer puts them first), and a note says what was not kept.
    """
    rows = [words for words in map(bytes.split, body.split(b"\n")) if words]
    row, found, notes = 0, [], []
    for element in elements:
        records = rows[row : row + element.count]
        row += element.count
        columns = _line_columns(element, records)
        if len(records) < element.count or columns is None:
            return None
        data, longer = columns
        if longer:
            dropped = [name for name in element.order if name not in _GEOMETRY]
            data = {name: column for name, column in data.items() if name in _GEOMETRY}
            kept = ", ".join(data) or "nothing"
            notes.append(
                f"{longer:,} of the {element.count:,} {element.name} lines of the PLY file "
                f"hold more numbers than its header declares; only their {kept} were read"
                + (f", not {', '.join(dropped)}." if dropped else ".")
            )
        found.append(data)
    return found, notes


def _line_columns(
    element: _Element, records: list[list[bytes]]
) -> tuple[dict[str, object], int] | None:
    """The element's columns read from one line per record, and how many lines hold more
    numbers than it declares; ``None`` when a line holds fewer."""
    columns: dict[str, list[object]] = {name: [] for name in element.order}
    longer = 0
    for words in records:
        at = 0
        for name in element.order:
            if name in element.lists:
                if at >= len(words) or not words[at].isdigit() or len(words[at]) >= 10:
                    return None
                size = int(words[at])
                columns[name].append(words[at + 1 : at + 1 + size])
                at += 1 + size
            else:
                columns[name].append(words[at] if at < len(words) else b"")
                at += 1
        if at > len(words):
            return None
        longer += at < len(words)
    kinds = dict(element.scalars)
    try:
        data: dict[str, object] = {
            name: column if name in element.lists else _floats(column).astype(kinds[name])  # type: ignore[arg-type]
            for name, column in columns.items()
        }
    except MeshFileError:
        return None
    return data, longer


def _adopt(elements: list[_Element], data: list[dict[str, object]], notes: list[str]) -> list[str]:
    for element, columns in zip(elements, data, strict=True):
        element.data = columns
    return notes


def _short(element: _Element, held: int) -> MeshFileError:
    return MeshFileError(
        f"The PLY header says {element.count:,} {element.name} elements, but "
        f"the file holds only {max(held, 0):,}: it looks truncated."
    )


def _floats(tokens: list[bytes]) -> NDArray[np.float64]:
    try:
        return np.array(tokens, dtype=np.float64)
    except ValueError:
        bad = next(token for token in tokens if not _is_number(token))
        raise MeshFileError(
            f"The PLY file has {bad[:40].decode('latin-1')!r} where a number should be."
        ) from None


def _is_number(token: bytes) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _ascii_lists(element: _Element, tokens: list[bytes], position: int) -> int:
    if element.order == [*element.lists] and len(element.lists) == 1 and element.count:
        size = tokens[position] if position < len(tokens) else b""
        width = int(size) + 1 if size.isdigit() and len(size) < 10 else 0  # else int() refuses
        end = position + width * element.count
        if width and end <= len(tokens) and tokens[position:end:width].count(size) == element.count:
            rows = _floats(tokens[position:end]).reshape(element.count, width)[:, 1:]
            element.data = {element.order[0]: rows}
            return end
    columns: dict[str, list[object]] = {name: [] for name in element.order}
    try:
        for _ in range(element.count):
            for name in element.order:
                if name in element.lists:
                    count = int(tokens[position])
                    columns[name].append(tokens[position + 1 : position + 1 + count])
                    if position + 1 + count > len(tokens):
                        raise IndexError
                    position += 1 + count
                else:
                    columns[name].append(tokens[position])
                    position += 1
    except IndexError:
        raise _short(element, len(columns[element.order[0]]) - 1) from None
    except ValueError:
        raise MeshFileError(
            f"The PLY file has {tokens[position][:40].decode('latin-1')!r} "
            "where a list length should be."
        ) from None
    element.data = {
        name: column if name in element.lists else _floats(column)  # type: ignore[arg-type]
        for name, column in columns.items()
    }
    return position


def _mesh(elements: list[_Element], notes: list[str]) -> LoadedMesh:
    named = {element.name: element for element in elements}
    vertex = named.get("vertex")
    if vertex is None or not {"x", "y", "z"} <= vertex.data.keys():
        raise MeshFileError("The PLY file has no vertex element with x, y and z.")
    vertices = _xyz(vertex)
    face = named.get("face")
    key = _indices_key(face)
    column = None if face is None or key is None else face.data[key]
    source: NDArray[np.intp] | None = None  # None: face i is the file's face i
    faces: NDArray[np.integer]
    if _triangle_rows(column):
        # Triangles read as integers (the compiled loop's): their own faces, as below, without
        # the counts and their check.
        faces, polygons = column, len(column)
    else:
        if face is None or key is None:
            counts, flat = np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        else:
            counts, flat = _polygons(column)
        polygons = len(counts)
        if len(counts) and np.all(counts == 3):
            # Only triangles: they are their own fans (what triangulate gives, without
            # building the fans' corner positions and gathering the corners through them).
            faces = flat.reshape(-1, 3)
        else:
            positions, source, fan_notes = triangulate(counts, flat, vertices)
            notes += fan_notes
            faces = flat[positions]
    from_polygons = len(faces)  # the triangles of the faces, before any of the strips'
    strips = _read_strips(named.get("tristrips"))
    if strips is not None:
        notes.append(strips.note)
    read = ("vertex", "face") if strips is None else ("vertex", "face", "tristrips")
    others = [
        f"{element.name} ({element.count:,})" for element in elements if element.name not in read
    ]
    if others:
        notes.append(f"Ignored elements this reader does not use: {', '.join(others)}.")
    face_normals = _face_normals(face, source)
    face_colors = None if face is None else _colors(face)
    if face_colors is not None and source is not None:
        face_colors = face_colors[source]
    if strips is not None and len(strips.triangles):
        faces = np.concatenate([faces, strips.triangles])
        face_normals = None  # strips carry none: normals for only some triangles say nothing
        if face_colors is not None:
            notes.append("Face colours were not kept: the triangle strips carry none.")
            face_colors = None
    return build(
        "ply",
        vertices,
        faces,
        source_faces=polygons + (0 if strips is None else strips.count),
        vertex_normals=_normals(vertex),
        face_normals=face_normals,
        vertex_colors=_colors(vertex),
        face_colors=face_colors,
        notes=notes,
        face=lambda i: (
            f"face {i if source is None else source[i]:,} (counting from 0)"
            if i < from_polygons or strips is None
            else f"triangle strip {strips.source[i - from_polygons]:,} (counting from 0)"
        ),
    )


def _xyz(vertex: _Element) -> NDArray[np.float64]:
    """The ``x y z`` columns as one (n, 3) array: from binary records whose three share one
    float type as one copy of the records' rows (a third of the time of three columns)."""
    declared = dict(vertex.scalars)
    kinds = {declared.get(axis) for axis in "xyz"}
    if vertex.records is not None and len(kinds) == 1 and kinds <= {"f4", "f8"}:
        rows = structured_to_unstructured(vertex.records[["x", "y", "z"]])
        return np.array(rows, dtype=np.float64)
    return np.stack([np.asarray(vertex.data[axis], dtype=np.float64) for axis in "xyz"], axis=1)


def _indices_key(element: _Element | None) -> str | None:
    """The list property naming an element's corners, if it has one."""
    names = ("vertex_indices", "vertex_index")
    return next((name for name in names if element is not None and name in element.lists), None)


@dataclass(frozen=True, slots=True)
class _Strips:
    """Triangles of a ``tristrips`` element.

    Attributes
    ----------
    triangles : (t, 3) int64
    source : (t,) intp
        The strip (record of the element) each triangle came from.
    count : int
        Strips as the file writes them (records; a record may hold several strips split by -1).
    note : str
    """

    triangles: NDArray[np.int64]
    source: NDArray[np.intp]
    count: int
    note: str


def _read_strips(element: _Element | None) -> _Strips | None:
    """The triangles of the ``tristrips`` element, or ``None`` when there is none."""
    key = _indices_key(element)
    if element is None or key is None:
        return None
    counts, flat = _polygons(element.data[key])
    item = np.dtype(element.lists[key][1])
    if item.kind == "u":  # -1 stored unsigned is all ones (OpenGL's primitive restart index)
        flat = np.where(flat == np.iinfo(item).max, -1, flat)
    triangles, source, dropped = strip_triangles(counts, flat)
    records = _count(len(counts), "triangle strip")
    restarts = int(np.sum(flat == -1))
    split = f" (with {_count(restarts, 'restart')})" if restarts else ""
    made = f"Read {records}{split} as {_count(len(triangles), 'triangle')}"
    if dropped:
        made += f", dropping {_count(dropped, 'degenerate triangle')} that repeat a corner"
    return _Strips(triangles, source, len(counts), made + ".")


def _count(count: int, noun: str) -> str:
    return f"{count:,} {noun}" + ("" if count == 1 else "s")


def strip_triangles(
    counts: NDArray[np.intp], flat: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.intp], int]:
    """Triangles of triangle strips, in strip order, with the OpenGL and glTF winding.

    Triangle ``i`` of a strip ``v`` is ``(v[i], v[i+1], v[i+2])`` for even ``i`` and
    ``(v[i+1], v[i], v[i+2])`` for odd ``i``; an index of -1 ends a strip and starts the next
    (counting ``i`` from 0 again). Triangles that repeat an index are dropped: strips use them
    to join or turn, and they have no area by construction.

    Parameters
    ----------
    counts : (p,) intp
        Indices in each strip record.
    flat : (s,) int64
        The records' indices, one after another.

    Returns
    -------
    triangles : (t, 3) int64
    source : (t,) intp
        The record each triangle came from.
    dropped : int
        Triangles dropped for repeating an index.
    """
    ends = np.cumsum(counts)
    # A -1 after every record: records end their strips just as a -1 inside one does.
    indices = np.insert(flat, ends, -1)
    record = np.repeat(np.arange(len(counts)), counts + 1)
    breaks = np.flatnonzero(indices == -1)
    first = np.arange(max(len(indices) - 2, 0))
    corners = np.stack([indices[first], indices[first + 1], indices[first + 2]], axis=1)
    whole = np.all(corners != -1, axis=1)
    # Place of each triangle in its strip: its first corner's distance from the last restart.
    last_break = np.searchsorted(breaks, first, side="right") - 1
    place = first - np.where(last_break >= 0, breaks[np.maximum(last_break, 0)], -1) - 1
    odd = place % 2 == 1
    corners[odd, :2] = corners[odd, 1::-1]
    degenerate = (
        (corners[:, 0] == corners[:, 1])
        | (corners[:, 1] == corners[:, 2])
        | (corners[:, 0] == corners[:, 2])
    )
    keep = whole & ~degenerate
    return corners[keep], record[first[keep]], int(np.sum(whole & degenerate))


def _polygons(column: object) -> tuple[NDArray[np.intp], NDArray[np.int64]]:
    """Corner counts and the flat corner indices of a list column (array or list of rows)."""
    if isinstance(column, np.ndarray) and column.ndim == 2:
        if column.dtype.kind == "f":  # ASCII: "2.9", or digits past any vertex count
            _whole_indices(column)
        # One pass from the records' strided view to a contiguous copy, then flattened free.
        flat = column.astype(np.int64, copy=False).ravel()
        return np.full(len(column), column.shape[1], dtype=np.intp), flat
    rows = list(column)  # type: ignore[call-overload]
    counts = np.fromiter(map(len, rows), dtype=np.intp, count=len(rows))
    listed = [value for row in rows for value in row]
    try:
        values = np.array(listed, dtype=np.float64) if listed else np.zeros(0)
    except ValueError:
        raise MeshFileError("The PLY file has a face index that is not a number.") from None
    _whole_indices(values)
    return counts, values.astype(np.int64)


def _whole_indices(values: NDArray[np.float64]) -> None:
    """Refuse face indices read as floats that are not whole numbers, or too large to cast
    (infinity, for a number of thousands of digits, would become a negative index)."""
    if np.any(np.abs(values) >= 2.0**53):
        raise MeshFileError("The PLY file has a face index too large to name a vertex.")
    if not np.all(values == np.round(values)):
        raise MeshFileError("The PLY file has a face index that is not a whole number.")


def _normals(element: _Element | None) -> NDArray[np.float64] | None:
    if element is None or not set(_NORMAL) <= element.data.keys():
        return None
    return np.stack([np.asarray(element.data[axis], dtype=np.float64) for axis in _NORMAL], axis=1)


def _colors(element: _Element) -> NDArray[np.generic] | None:
    """An element's ``red green blue [alpha]`` in the type the header declares them (one type
    for all, NumPy's common type where the file mixes them)."""
    if not set(_COLOR[:3]) <= element.data.keys():
        return None
    names = _COLOR if "alpha" in element.data else _COLOR[:3]
    declared = dict(element.scalars)
    if not all(name in declared for name in names):  # a list named "red": not a colour
        return None
    kind = np.result_type(*(np.dtype(declared[name]) for name in names))
    return np.stack([np.asarray(element.data[name]).astype(kind) for name in names], axis=1)


def _face_normals(
    face: _Element | None, source: NDArray[np.intp] | None
) -> NDArray[np.float64] | None:
    normals = _normals(face)
    return normals if normals is None or source is None else normals[source]


def _triangle_rows(column: object) -> TypeGuard[NDArray[np.int64]]:
    """Whether a list column holds triangles read as one int64 array of rows (binary lists of
    one length, by the compiled loop): every face has 3 corners, unlooked at."""
    return (
        isinstance(column, np.ndarray)
        and column.dtype == np.int64
        and column.ndim == 2
        and column.shape[1] == 3
    )


def write_ply(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_colors: NDArray[np.generic] | None = None,
    face_colors: NDArray[np.generic] | None = None,
    normals: NDArray[np.float64] | None = None,
    normals_kind: str | None = None,
) -> bytes:
    """Binary little-endian PLY with float64 coordinates: it reads back bit for bit, and so do
    vertex and face colours (written in their own type, see :func:`ply_bytes`) and normals.

    Parameters
    ----------
    points : (n, 3) float64
    triangles : (m, 3) intp
    vertex_colors : (n, 3) or (n, 4), optional
    face_colors : (m, 3) or (m, 4), optional
    normals : (n, 3) or (m, 3) float64, optional
        ``nx ny nz`` of the vertices or of the faces, as ``normals_kind`` says.
    """
    return ply_bytes(
        points,
        triangles,
        vertex_normals=normals if normals_kind == "vertex" else None,
        face_normals=normals if normals_kind == "face" else None,
        vertex_colors=vertex_colors,
        face_colors=face_colors,
    )


def ply_bytes(
    points: NDArray[np.float64],
    triangles: NDArray[np.intp],
    vertex_normals: NDArray[np.float64] | None = None,
    face_normals: NDArray[np.float64] | None = None,
    vertex_colors: NDArray[np.generic] | None = None,
    face_colors: NDArray[np.generic] | None = None,
) -> bytes:
    """Binary little-endian PLY: float64 ``x y z`` and int32 triangles, ``nx ny nz``
    (float64) of the vertices or of the faces where those normals are given, and
    ``red green blue [alpha]`` of the vertices or of the faces where colours are given.

    Parameters
    ----------
    points : (n, 3) float64
    triangles : (m, 3) intp
    vertex_normals : (n, 3) float64, optional
    face_normals : (m, 3) float64, optional
    vertex_colors : (n, 3) or (n, 4) uint8, uint16, float32 or float64, optional
        Written in their own type (``uchar``, ``ushort``, ``float``, ``double``), so colours
        read from a PLY file go back as they were; other types as ``double``.
    face_colors : (m, 3) or (m, 4), optional
        The same, one per triangle, after the face normals.
    """
    normal_fields = [("nx", "<f8"), ("ny", "<f8"), ("nz", "<f8")]
    normal_lines = "".join(f"property double {name}\n" for name, _ in normal_fields)
    color_fields, color_lines = _color_fields(vertex_colors)
    face_color_fields, face_color_lines = _color_fields(face_colors)
    vertices = np.empty(
        len(points),
        dtype=[("xyz", "<f8", (3,))]
        + (normal_fields if vertex_normals is not None else [])
        + color_fields,
    )
    faces = np.empty(
        len(triangles),
        dtype=[("count", "u1"), ("indices", "<i4", (3,))]
        + (normal_fields if face_normals is not None else [])
        + face_color_fields,
    )
    vertices["xyz"] = points
    faces["count"] = 3
    faces["indices"] = triangles
    for records, normals in ((vertices, vertex_normals), (faces, face_normals)):
        if normals is not None:
            for axis, (name, _) in enumerate(normal_fields):
                records[name] = normals[:, axis]
    for records, fields, colors in (
        (vertices, color_fields, vertex_colors),
        (faces, face_color_fields, face_colors),
    ):
        for axis, (name, _) in enumerate(fields):
            records[name] = colors[:, axis]  # type: ignore[index]
    header = (
        f"ply\nformat binary_little_endian 1.0\ncomment written by {MAKER}\n"
        f"element vertex {len(points)}\nproperty double x\nproperty double y\n"
        f"property double z\n{normal_lines if vertex_normals is not None else ''}{color_lines}"
        f"element face {len(triangles)}\nproperty list uchar int vertex_indices\n"
        f"{normal_lines if face_normals is not None else ''}{face_color_lines}end_header\n"
    )
    # The records go into the file as they are: no copy of each, nor of their sum.
    return b"".join([header.encode(), vertices.view(np.uint8).data, faces.view(np.uint8).data])


def _color_fields(colors: NDArray[np.generic] | None) -> tuple[list[tuple[str, str]], str]:
    """The record fields and header lines of colours (none without colours)."""
    if colors is None:
        return [], ""
    kind = colors.dtype.str[1:] if colors.dtype.str[1:] in _TYPE_NAMES else "f8"
    names = _COLOR[: colors.shape[1]]
    lines = "".join(f"property {_TYPE_NAMES[kind]} {name}\n" for name in names)
    return [(name, "<" + kind) for name in names], lines
