"""Text tables of points: XYZ, XYZN, XYZRGB, PTS, TXT, CSV and ASC files.

One point a line; numbers apart by whitespace or commas; blank lines and lines starting with
``#`` or ``//`` are comments. Every line holds the same count of numbers: a line that does not,
or a word that is not a number, is refused with its line number (nothing is skipped).

Which column is what:

- A header row of names (``x,y,z,nx,ny,nz``, ``X Y Z R G B``, also as the last comment line
  before the numbers, as CloudCompare writes ``//X,Y,Z,R,G,B``) is used when it names ``x``,
  ``y`` and ``z``: ``nx ny nz`` (or ``normal_x``...) are normals, ``r g b`` (or ``red``...)
  colours; other named columns are not used, and a note names them.
- A first line holding one whole number is the point count (PTS, as Leica and Open3D write
  it); the rows must match it.
- Otherwise by the count of numbers in a line:

  ===== ==============================================================================
  3     ``x y z``
  4     ``x y z intensity`` (PTS); the intensity is not used
  6     ``x y z nx ny nz``; ``x y z r g b`` when the file is ``.xyzrgb`` or the last three
        columns are whole numbers in 0-255, not all 0 or 1 (``.xyzn``: normals always)
  7     ``x y z intensity r g b`` (PTS); the intensity is not used
  9     ``x y z nx ny nz r g b``, or ``x y z r g b nx ny nz`` when columns 4-6 are the
        ones that look like colours (whole numbers in 0-255)
  other ``x y z`` and the columns after them not used (a note says so)
  ===== ==============================================================================

Colours are 0-255 when written as whole numbers (any above 1), else 0-1 (Open3D's XYZRGB).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from itertools import chain

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError
from mesh_normal.points.io.cloud import PointCloud, colors_uint8, make_cloud

#: How a binary Expe point set (MeshLab's samples) begins: its records are not text.
_EXPE_BINARY = b"[Expe/PointSet/Binary/"

#: Bytes of text read at once (cut at a line end): the words of one chunk are Python objects.
_CHUNK = 1 << 20

_NAMES = {
    "x": "x",
    "y": "y",
    "z": "z",
    **{
        name: f"n{axis}"
        for axis in "xyz"
        for name in (f"n{axis}", f"normal_{axis}", f"normal{axis}")
    },
    **{
        name: key
        for key, names in (("r", ("r", "red")), ("g", ("g", "green")), ("b", ("b", "blue")))
        for name in names
    },
}


@dataclass(slots=True)
class _Table:
    """What the lines read so far hold."""

    width: int = 0
    names: list[str] | None = None  # from a header row
    count: int | None = None  # from a PTS count line
    blocks: list[NDArray[np.float64]] = field(default_factory=list)
    lines: list[NDArray[np.int64]] = field(default_factory=list)  # 1-based line of each row
    last_comment: bytes | None = None  # the last comment before the first row
    expected: str = "the lines before it have"  # where the width comes from, for errors


def read_xyz(data: bytes, suffix: str | None) -> PointCloud:
    """Read a text table of points (see the module docstring)."""
    if data.lstrip()[:22].lower() == _EXPE_BINARY.lower():
        raise MeshFileError(
            "This is a binary Expe point set (a .pts file that starts with "
            "[Expe/PointSet/Binary/...], as MeshLab's samples are), which is not read: save it "
            "from MeshLab as PLY or XYZ.",
            415,
        )
    table = _Table()
    rows, lines = _read_table(table, data, 1)
    if table.count is not None and table.count != len(rows):
        raise MeshFileError(
            f"The file's first line says {table.count:,} points, but it holds {len(rows):,}."
        )
    if not len(rows):
        raise MeshFileError("The file holds no points.")
    columns, notes = _columns(table, rows, suffix)
    normals = rows[:, columns["normals"]] if "normals" in columns else None
    colors = rows[:, columns["colors"]] if "colors" in columns else None
    return make_cloud(
        "pts" if table.count is not None else "xyz",
        rows[:, columns["points"]],
        normals=normals,
        colors=None if colors is None else colors_uint8(colors),
        notes=notes,
        describe=lambda row: f"the point on line {lines[row]:,}",
    )


def read_rows(
    text: bytes, first_line: int, width: int, expected: str
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The numbers of ``text``, ``width`` a line (blank and comment lines skipped), and the
    1-based line number of each row; ``expected`` says where ``width`` comes from, for the
    sentence refusing a line of another width."""
    return _read_table(_Table(width=width, expected=expected), text, first_line)


def _read_table(
    table: _Table, data: bytes, first_line: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    for start, chunk in _chunks(data, first_line):
        _read_chunk(table, start, chunk)
    rows = np.concatenate(table.blocks) if table.blocks else np.zeros((0, max(table.width, 3)))
    lines = np.concatenate(table.lines) if table.lines else np.zeros(0, dtype=np.int64)
    return rows, lines


def _chunks(data: bytes, line: int) -> Iterator[tuple[int, bytes]]:
    """The text in chunks of about ``_CHUNK`` bytes cut at line ends, with the 1-based number
    of each chunk's first line."""
    position = 0
    while position < len(data):
        end = data.find(b"\n", position + _CHUNK)
        end = len(data) if end < 0 else end + 1
        chunk = data[position:end]
        yield line, chunk
        line += chunk.count(b"\n")
        position = end


def _read_chunk(table: _Table, first_line: int, chunk: bytes) -> None:
    lines = chunk.replace(b",", b" ").splitlines()
    numbers: list[int] = []
    words: list[list[bytes]] = []
    for index, line in enumerate(lines):
        split = line.split()
        if not split:
            continue
        if split[0].startswith((b"#", b"//")):
            if not table.width and not words:
                table.last_comment = line
            continue
        if not table.width and not words and _starts_table(table, split, first_line + index):
            continue
        numbers.append(first_line + index)
        words.append(split)
    if not words:
        return
    table.width = table.width or len(words[0])
    widths = np.fromiter(map(len, words), dtype=np.intp, count=len(words))
    if np.any(widths != table.width):
        row = int(np.argmax(widths != table.width))
        raise MeshFileError(
            f"Line {numbers[row]:,} has {_numbers(int(widths[row]))}, but {table.expected} "
            f"{table.width:,}; every point takes one line of the same columns."
        )
    if table.width < 3:
        raise MeshFileError(
            f"Line {numbers[0]:,} has only {_numbers(table.width)}; a point needs x, y and z."
        )
    try:
        values = np.array(list(chain.from_iterable(words)), dtype=np.float64)
    except ValueError:
        raise _not_a_number(words, numbers) from None
    table.blocks.append(values.reshape(-1, table.width))
    table.lines.append(np.array(numbers, dtype=np.int64))


def _starts_table(table: _Table, words: list[bytes], number: int) -> bool:
    """Whether the first line that is not a comment is a header row (names) or a PTS count
    line, taking it into ``table`` if so."""
    if len(words) == 1 and words[0].isdigit():
        table.count = int(words[0])
        return True
    if all(_is_number(word) for word in words):
        return False
    names = [word.decode("latin-1").lower() for word in words]
    if not {"x", "y", "z"} <= set(names):
        bad = next(word for word in words if not _is_number(word))
        raise MeshFileError(
            f"Line {number:,} has {bad[:40].decode('latin-1')!r} where a number should be "
            "(a header row of names must name x, y and z)."
        )
    table.names = names
    return True


def _is_number(word: bytes) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _not_a_number(words: list[list[bytes]], numbers: list[int]) -> MeshFileError:
    for line, row in zip(numbers, words, strict=True):
        for word in row:
            if not _is_number(word):
                return MeshFileError(
                    f"Line {line:,} has {word[:40].decode('latin-1')!r} where a number should be."
                )
    return MeshFileError("The file has a word where a number should be.")  # not reached


def _numbers(count: int) -> str:
    return f"{count:,} number" + ("" if count == 1 else "s")


def _columns(
    table: _Table, rows: NDArray[np.float64], suffix: str | None
) -> tuple[dict[str, list[int]], list[str]]:
    """Which columns hold the points, normals and colours, and notes on those not used."""
    names = table.names or _comment_names(table.last_comment, table.width)
    if names is not None:
        return _named_columns(names, table.width)
    width = table.width
    if width == 6:
        rgb = suffix == ".xyzrgb" or (suffix != ".xyzn" and _colour_like(rows[:, 3:6]))
        return ({"points": [0, 1, 2], "colors" if rgb else "normals": [3, 4, 5]}, [])
    if width == 9:
        first = _colour_like(rows[:, 3:6]) and not _colour_like(rows[:, 6:9])
        normals, colours = ([6, 7, 8], [3, 4, 5]) if first else ([3, 4, 5], [6, 7, 8])
        return {"points": [0, 1, 2], "normals": normals, "colors": colours}, []
    intensity = ["The file's fourth column (intensity, as PTS files hold) is not used."]
    if width == 4:
        return {"points": [0, 1, 2]}, intensity
    if width == 7:
        return {"points": [0, 1, 2], "colors": [4, 5, 6]}, intensity
    notes = []
    if width > 3:
        notes.append(
            f"The file's columns 4 to {width} are not used: a header row naming the columns "
            "(such as x,y,z,nx,ny,nz) tells which are normals or colours."
        )
    return {"points": [0, 1, 2]}, notes


def _comment_names(comment: bytes | None, width: int) -> list[str] | None:
    """The names in the last comment before the rows (``//X,Y,Z,R,G,B``), when it names x, y
    and z and as many columns as the rows hold."""
    if comment is None:
        return None
    text = comment.strip().lstrip(b"#/").replace(b",", b" ").decode("latin-1").lower()
    names = text.split()
    return names if len(names) == width and {"x", "y", "z"} <= set(names) else None


def _named_columns(names: list[str], width: int) -> tuple[dict[str, list[int]], list[str]]:
    if len(names) != width:
        raise MeshFileError(
            f"The header row names {len(names)} columns, but the rows hold {width} numbers."
        )
    where = {
        _NAMES[name]: index for index, name in reversed(list(enumerate(names))) if name in _NAMES
    }
    columns = {"points": [where["x"], where["y"], where["z"]]}
    if {"nx", "ny", "nz"} <= where.keys():
        columns["normals"] = [where["nx"], where["ny"], where["nz"]]
    if {"r", "g", "b"} <= where.keys():
        columns["colors"] = [where["r"], where["g"], where["b"]]
    used = set(chain.from_iterable(columns.values()))
    unused = [name for index, name in enumerate(names) if index not in used]
    notes = [f"The file's {', '.join(unused)} columns are not used."] if unused else []
    return columns, notes


def _colour_like(values: NDArray[np.float64]) -> bool:
    """Whole numbers in 0-255, some above 1: colours, where unit normals never are."""
    finite = values[np.isfinite(values)]
    return bool(
        finite.size == values.size
        and np.all(finite == np.round(finite))
        and finite.min() >= 0
        and finite.max() <= 255
        and finite.max() > 1
    )
