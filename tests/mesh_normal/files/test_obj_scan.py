"""The OBJ scan: what it reads in every statement, its numbers' bits, its sentences.

The compiled scan reads a file's bytes as Latin-1 text the way Python's str methods do: lines
end where str.splitlines() ends them, words split where str.split() splits them, a backslash
continues a line, numbers are float()'s and indices int()'s. :func:`reference` below says so in
a few lines of Python, one line at a time; the scan must agree with it on every file, in every
array's bytes and in every sentence, whatever the size of the chunks it scans.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mesh_normal._core import read_decimal
from mesh_normal.files import MeshFileError, obj


def _plain(value: object) -> object:
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    return value


def scanned(data: bytes) -> dict[str, Any] | str:
    """What the reader's scan finds, as :func:`reference` gives it, or the error's sentence."""
    try:
        found = obj._scan(data)
    except MeshFileError as error:
        return str(error)
    labels = None
    if found.face_labels is not None:
        labels = [found.labels[label] for label in found.face_labels.tolist()]
    return {
        "vertices": _plain(found.vertices),
        "vertex_lines": found.vertex_lines.tolist(),
        "colors": None if found.colors is None else _plain(found.colors),
        "normals": _plain(found.normals),
        "vertex_fields": found.vertex_fields.tolist(),
        "normal_fields": None if found.normal_fields is None else found.normal_fields.tolist(),
        "counts": found.counts.tolist(),
        "face_lines": found.face_lines.tolist(),
        "vertices_before": found.vertices_before.tolist(),
        "normals_before": found.normals_before.tolist(),
        "labels": labels,
        "notes": found.notes,
        "unkept": found.unkept,
    }


# --- the reference: a line at a time, in Python's own words ------------------------------------


def _lines(text: str) -> list[tuple[int, str]]:
    """The statements of a chunk of text and each one's first line: a line whose last visible
    character is a backslash goes on in the next (joined by a space), unless it is a comment."""
    found: list[tuple[int, str]] = []
    pending: list[str] = []
    first = 0
    for number, line in enumerate(text.splitlines(), 1):
        end = line.rstrip()
        if end.endswith("\\") and (pending or not end.lstrip().startswith("#")):
            first = first if pending else number
            pending.append(end[:-1])
            continue
        found.append((first if pending else number, " ".join([*pending, line])))
        pending = []
    if pending:
        found.append((first, " ".join(pending)))
    return found


def _coordinates(words: list[str], number: int, key: str) -> list[float]:
    if len(words) < 3:
        raise MeshFileError(f"Line {number:,}: '{key}' needs 3 numbers, but has {len(words)}.")
    try:
        return [float(word) for word in words]
    except ValueError:
        bad = next(word for word in words if not _is_float(word))
        raise MeshFileError(f"Line {number:,}: {bad[:40]!r} is not a number.") from None


def _is_float(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _corner(corner: str, number: int) -> tuple[int, int | None]:
    """A corner's vertex index and normal index (None when it has none)."""
    parts = corner.split("/")
    bad = MeshFileError(
        f"The face corner {corner[:40]!r} is not an index, nor index/texture, "
        f"index//normal or index/texture/normal (line {number:,})."
    )
    if len(parts) > 3 or not parts[0]:
        raise bad
    try:
        values = [int(part) if part else None for part in parts]
    except ValueError:
        raise bad from None
    for kind, position in (("vertex", 0), ("normal", 2)):
        value = values[position] if position < len(values) else None
        if value is not None and not -(2**63) <= value < 2**63:
            raise MeshFileError(
                f"Line {number:,}: {kind} index {parts[position][:40]} is out of range."
            )
    vertex, *rest = values
    assert vertex is not None
    return vertex, rest[1] if len(rest) == 2 else None


def _keyword(line: str, words: list[str]) -> str:
    """A line's keyword: its first two characters when they are one of these (``vn`` and
    ``vt`` whatever follows), else its first word; ``#`` for a blank line."""
    for start in ("v ", "vn", "vt", "f ", "o ", "g "):
        if line.startswith(start):
            return start.strip()
    return words[0] if words else "#"


def reference(data: bytes) -> dict[str, Any] | str:
    """What the scan must find in ``data``."""
    vertices: list[list[float]] = []
    colors: list[list[float] | None] = []
    normals: list[list[float]] = []
    corners: list[tuple[int, int | None]] = []
    found: dict[str, list[Any]] = {
        key: [] for key in ("vertex_lines", "counts", "face_lines", "before", "labels")
    }
    other: Counter[str] = Counter()
    textures = 0
    thing = group = ""
    label: str | None = None
    offset = 0
    try:
        for start, end in obj._text_chunks(data):  # chunks are scanned one by one
            text = data[start:end].decode("latin-1")
            for number, line in _lines(text):
                number += offset
                words = line.split()
                key = _keyword(line, words)
                if key == "v":
                    vertices.append(_coordinates(words[1:4], number, "v"))
                    found["vertex_lines"].append(number)
                    rgb = line.partition("#")[0].split()[4:]
                    has = len(rgb) == 3 and all(map(_is_float, rgb))
                    colors.append([float(x) for x in rgb] if has else None)
                elif key == "vn":
                    normals.append(_coordinates(words[1:4], number, "vn"))
                elif key == "vt":
                    textures += 1
                elif key == "f":
                    words = line.partition("#")[0].split()[1:]
                    corners += [_corner(word, number) for word in words]
                    found["counts"].append(len(words))
                    found["face_lines"].append(number)
                    found["before"].append((len(vertices), len(normals)))
                    found["labels"].append(label)
                elif key in ("o", "g"):
                    name = " ".join(line.partition("#")[0].split()[1:])
                    thing, group = (name, "") if key == "o" else (thing, name)
                    label = "/".join(part for part in (thing, group) if part) or "default"
                elif not key.startswith("#"):
                    other[key] += 1
            offset += len(text.splitlines())
    except MeshFileError as error:
        return str(error)
    if label is not None:
        found["labels"] = [name or "default" for name in found["labels"]]
    unkept = {"vt": textures, **{key: other[key] for key in ("mtllib", "usemtl", "s")}}
    for key in obj._IGNORED:
        other.pop(key, None)
    return {
        "vertices": _plain(np.array(vertices, dtype=np.float64).reshape(-1, 3)),
        "vertex_lines": found["vertex_lines"],
        "colors": None
        if not colors or None in colors
        else _plain(np.array(colors, dtype=np.float64)),
        "normals": _plain(np.array(normals, dtype=np.float64).reshape(-1, 3)),
        "vertex_fields": [vertex for vertex, _ in corners],
        "normal_fields": None
        if not corners or any(normal is None for _, normal in corners)
        else [normal for _, normal in corners],
        "counts": found["counts"],
        "face_lines": found["face_lines"],
        "vertices_before": [v for v, _ in found["before"]],
        "normals_before": [n for _, n in found["before"]],
        "labels": None if label is None else found["labels"],
        "notes": obj._skipped(other),
        "unkept": [
            f"{words} ({count:,} {key})"
            for key, words in obj._UNKEPT.items()
            if (count := unkept[key])
        ],
    }


# --- every file: the scan and the reference agree ---------------------------------------------

#: What separates words (str.split()), ends lines (str.splitlines(), a backslash continuing).
SPACES = [" ", " ", " ", "  ", "\t", "\x1f", "\xa0", " \t"]
ENDS = ["\n"] * 4 + ["\r\n", "\r", "\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85"]
ENDS += ["\\\n", "\\ \n", "\\\xa0\n", " \\\r\n"]
NUMBERS = st.one_of(
    st.floats().map(repr),
    st.integers(-9, 9).map(str),
    st.from_regex(r"\A[-+]?[0-9_]{0,3}(\.[0-9_]{0,3})?([eE][-+]?[0-9_]{1,3})?\Z"),
    st.sampled_from(["1e400", "-1e-400", "inf", "-Infinity", "nan", "-nan", "NaN", "infin"]),
    st.sampled_from(["x", "1e", ".", "-", "0x10", "1.2.3", "1#", "#", "1/2", "\\", "\xb2"]),
)
INDICES = st.one_of(
    st.integers(-6, 8).map(str),
    st.from_regex(r"\A[-+]?[0-9_]{1,3}\Z"),
    st.sampled_from(["99999999999999999999", "-9223372036854775808", "9223372036854775808"]),
    st.sampled_from(["x", "1.0", "", "#", "\xb2", "f"]),
)
CORNERS = st.builds(
    lambda form, v, t, n: form.format(v=v, t=t, n=n),
    st.sampled_from(
        [
            "{v}",
            "{v}",
            "{v}/{t}",
            "{v}//{n}",
            "{v}/{t}/{n}",
            "{v}/",
            "{v}//",
            "/{t}",
            "{v}/{t}/{n}/{n}",
        ]
    ),
    INDICES,
    INDICES,
    INDICES,
)
NAMES = st.text(st.sampled_from(list("ab _#\t\xa0\x1f\xc3\xbc\x85")), max_size=6)
STATEMENTS = st.one_of(
    st.tuples(st.sampled_from(["v", "v", "vn", "vnx", "v#"]), st.lists(NUMBERS, max_size=8)),
    st.tuples(st.sampled_from(["f", "f", "f#"]), st.lists(CORNERS, max_size=5)),
    st.tuples(st.sampled_from(["o", "g", "o#"]), st.lists(NAMES, max_size=3)),
    st.tuples(
        st.sampled_from(["vt", "l", "p", "s", "usemtl", "curv", "\xe9t\xe9"]),
        st.lists(INDICES, max_size=2),
    ),
    st.tuples(st.sampled_from(["", "#", "# C:\\\\models\\\\", "\\", "\xa0"]), st.just([])),
    st.tuples(st.sampled_from(["v 0 0 0", "v 1 0 0", "v 0 1 0", "vn 0 0 1"]), st.just([])),
)


@st.composite
def obj_files(draw: st.DrawFn) -> bytes:
    text = draw(st.sampled_from(["", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n"]))
    for key, words in draw(st.lists(STATEMENTS, max_size=20)):
        line = draw(st.sampled_from(["", "", "", " ", "\t", "\xa0"])) + key
        for word in words:
            line += draw(st.sampled_from(SPACES)) + word
        text += line + draw(st.sampled_from([""] * 6 + [" # a", "#", "\t", "\xa0"]))
        text += draw(st.sampled_from(ENDS))
    return text.encode("latin-1")


@settings(
    max_examples=500, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(obj_files(), st.sampled_from([1 << 20, 1, 16, 64]))
def test_every_file_reads_as_the_reference_says(
    monkeypatch: pytest.MonkeyPatch, data: bytes, chunk: int
) -> None:
    monkeypatch.setattr(obj, "_TEXT_CHUNK", chunk)
    assert scanned(data) == reference(data)


# --- each rule, by hand ----------------------------------------------------------------------

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
TRIANGLES = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


def read(text: str) -> dict[str, Any] | str:
    found = scanned(text.encode("latin-1"))
    assert found == reference(text.encode("latin-1"))
    if isinstance(found, dict):
        for key in ("vertices", "normals", "colors"):
            if found[key] is not None:
                dtype, shape, raw = found[key]
                found[key] = np.frombuffer(raw, dtype).reshape(shape).tolist()
    return found


@pytest.mark.parametrize(
    "text",
    [
        TRIANGLE + "f 1 2 3\n",
        TRIANGLE.replace("\n", "\r\n") + "f 1 2 3\r\n",
        "v\t0 0 0\n  v 1 0 0\n\xa0v 0 1 0\n f\t1 2 3\n",  # indented, tab- and NBSP-separated
        "v 0 0 0\nv 1 \\\n 0 0\nv 0 1 0\nf 1 2 3\n",  # continued: line 2 and 3 are one
        "v 0_0 0e0 -0\nv +1 0.0 0_0.0_0\nv 0 1 .0\nf 1 2 3\n",  # underscores between digits
        "v 0 0 0 # a comment after three numbers\nv 1 0 0 extra words\nv 0 1 0\nf 1 2 3 # c\n",
        TRIANGLE + "f 1/9 2/x 3\n",
    ],
)
def test_the_same_triangle_however_written(text: str) -> None:
    found = read(text)
    if "2/x" in text:
        assert found == (
            "The face corner '2/x' is not an index, nor index/texture, index//normal or "
            "index/texture/normal (line 4)."
        )
        return
    assert isinstance(found, dict)
    assert found["vertices"] == TRIANGLES and found["vertex_fields"] == [1, 2, 3]
    assert found["counts"] == [3] and found["face_lines"][0] == 4 + text.count("\\")


def test_lines_end_where_python_ends_them() -> None:
    # \r, \v, \f, \x1c-\x1e and NEL (0x85) end a line too, so every line after counts them.
    text = "v 0 0 0\rv 1 0 0\x0bv 0 1 0\x0c\x1c\x1d\x1e\x85f 1 2 3\n"
    found = read(text)
    assert isinstance(found, dict)
    assert found["vertex_lines"] == [1, 2, 3] and found["face_lines"] == [8]


def test_a_comment_ending_in_a_backslash_does_not_continue() -> None:
    found = read("# saved in C:\\models\\\n" + TRIANGLE + "f 1 2 3 \\\n# here a comment goes on\n")
    assert isinstance(found, dict)
    assert found["vertex_lines"] == [2, 3, 4] and found["counts"] == [3]


@pytest.mark.parametrize(
    ("word", "value"),
    [
        ("inf", np.inf),
        ("-Infinity", -np.inf),
        ("1e400", np.inf),
        ("-1e-400", -0.0),
        ("1_000.5", 1000.5),
        ("1e1_0", 1e10),
        ("+.5", 0.5),
        ("5.", 5.0),
    ],
)
def test_numbers_are_float_s(word: str, value: float) -> None:
    found = read(f"v {word} 0 0\n")
    assert isinstance(found, dict)
    assert np.float64(found["vertices"][0][0]).tobytes() == np.float64(value).tobytes()


def test_nan_keeps_its_sign_bit() -> None:
    found = scanned(b"v nan -nan NaN\n")
    assert isinstance(found, dict)
    assert found["vertices"][2] == bytes.fromhex("000000000000f87f000000000000f8ff000000000000f87f")


@pytest.mark.parametrize("word", ["1__0", "_1", "1_", "1_.5", "1e", "0x10", "nanx", "\xb2", "1,5"])
def test_what_float_refuses_is_no_number(word: str) -> None:
    assert read(f"v 0 0 0\nv 1 {word} 0\n") == f"Line 2: {word!r} is not a number."
    assert read_decimal(word) is None


@pytest.mark.parametrize(
    ("text", "sentence"),
    [
        ("v 0 0\n", "Line 1: 'v' needs 3 numbers, but has 2."),
        ("\nvn 0 0 # 1\n", "Line 2: '#' is not a number."),
        ("vnx 0 0\n", "Line 1: 'vn' needs 3 numbers, but has 2."),  # "vnx" is its keyword
        (
            "f 1 2 3\nf 1 2 3.0\n",
            "The face corner '3.0' is not an index, nor index/texture, "
            "index//normal or index/texture/normal (line 2).",
        ),
        (
            "f 1 2 3/4/5/6\n",
            "The face corner '3/4/5/6' is not an index, nor index/texture, "
            "index//normal or index/texture/normal (line 1).",
        ),
        (
            "f 1 2 -99999999999999999999\n",
            "Line 1: vertex index -99999999999999999999 is out of range.",
        ),
        (
            "f 1//2 2//9223372036854775808\n",
            "Line 1: normal index 9223372036854775808 is out of range.",
        ),
        ("v 1 2\nf 1 2 x\n", "Line 1: 'v' needs 3 numbers, but has 2."),  # the first bad line
        (
            "f 1 2 x\nv 1 2\n",
            "The face corner 'x' is not an index, nor index/texture, "
            "index//normal or index/texture/normal (line 1).",
        ),
        ("v 1 \\\n2 3\nv 1 2 x\n", "Line 3: 'x' is not a number."),
        # A keyword among a line's words is a word of that line, whatever the other lines hold.
        ("v 1 2 3 x v 5 6 7\nv\n", "Line 2: 'v' needs 3 numbers, but has 0."),
        (
            "f 1 2 3 f 5 6\nf\n",
            "The face corner 'f' is not an index, nor index/texture, "
            "index//normal or index/texture/normal (line 1).",
        ),
    ],
)
def test_a_bad_line_is_named(text: str, sentence: str) -> None:
    assert read(text) == sentence


def test_a_keyword_among_the_words_of_lines_of_other_widths() -> None:
    found = read("v 2.5 2.5 1e3 nan 2.5 1e3 1e3 v\nv 2.5 nan nan nan 1e3 2.5\n")
    assert isinstance(found, dict) and found["vertex_lines"] == [1, 2]


def test_a_texture_index_of_any_size_is_read_as_unused() -> None:
    found = read(TRIANGLE + "f 1/99999999999999999999 2/1_0 3/-0\n")
    assert isinstance(found, dict) and found["vertex_fields"] == [1, 2, 3]


def test_colours_only_when_every_v_has_exactly_three_numbers_more() -> None:
    coloured = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0 # red\nv 0 1 0 0 0 1\n"
    found = read(coloured)
    assert isinstance(found, dict) and found["colors"] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    for other in ("v 0 1 0 0 0\n", "v 0 1 0 0 0 1 1\n", "v 0 1 0 0 0 x\n", "v 0 1 0 0 0#1\n"):
        found = read(coloured + other)
        assert isinstance(found, dict) and found["colors"] is None, other


def test_normals_only_when_every_corner_has_one() -> None:
    base = TRIANGLE + "vn 0 0 1\n"
    found = read(base + "f 1//1 2/5/1 -1//-1\n")
    assert isinstance(found, dict) and found["normal_fields"] == [1, 1, -1]
    found = read(base + "f 1//1 2//1 3//\n")
    assert isinstance(found, dict) and found["normal_fields"] is None


def test_groups_statements_and_notes() -> None:
    text = (
        "mtllib a.mtl\n" + TRIANGLE + "f 1 2 3\no lid # top\nusemtl red\ns off\nf 1 2 3\n"
        "g a\xa0b\tc\nf 1 2 3\no\nvt 0 0\nvtx\nf 1 2 3\nl 1 2\np 1\ncurv 1\nfoo\nfoo\n"
    )
    found = read(text)
    assert isinstance(found, dict)
    assert found["labels"] == ["default", "lid", "lid/a b c", "default"]
    assert found["notes"] == [
        "Skipped 1 line ('l') and 1 point ('p') elements: only faces are read.",
        "Ignored statements this reader does not use: 'foo' (2).",
    ]
    assert found["unkept"] == [
        "texture coordinates (2 vt)",
        "material libraries (1 mtllib)",
        "materials (1 usemtl)",
        "smoothing groups (1 s)",
    ]


@pytest.mark.parametrize("threads", [2, 3])
def test_chunks_scanned_on_several_threads_read_as_on_one(
    monkeypatch: pytest.MonkeyPatch, threads: int
) -> None:
    rng = np.random.default_rng(threads)
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in rng.normal(size=(3000, 3)).tolist()]
    lines[700] = "v 1 2 \\\n3"
    lines[1900] = "\tv 0.5 0.25 0.125"
    lines.insert(2500, "g second")
    lines += [f"f {a} {b} {c}" for a, b, c in rng.integers(1, 3000, (2000, 3)).tolist()]
    data = ("\n".join(lines) + "\n").encode()
    monkeypatch.setattr(obj, "_TEXT_CHUNK", 4096)
    monkeypatch.setattr(obj, "SCAN_THREADS", 1)
    alone = obj._scan(data)
    monkeypatch.setattr(obj, "SCAN_THREADS", threads)
    monkeypatch.setattr(obj.os, "sched_getaffinity", lambda _: set(range(threads)))
    together = obj._scan(data)
    for field in dataclasses.fields(alone):
        assert _plain(getattr(together, field.name)) == _plain(getattr(alone, field.name))
    assert len(alone.vertices) == 3000 and len(alone.counts) == 2000
    assert scanned(data) == reference(data)


def test_the_scan_takes_only_bytes_as_they_are() -> None:
    # A wrong type or a strided view is refused, not copied into another type.
    with pytest.raises(TypeError):
        obj.scan_obj(np.zeros(4, np.int8))  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        obj.scan_obj(np.frombuffer(b"v 1 2 3\n" * 2, np.uint8)[::2])
    chunk = obj.scan_obj(np.frombuffer(b"v 1 2 3\nf 1 1 1\n", np.uint8))
    assert chunk.vertices.tolist() == [[1.0, 2.0, 3.0]] and chunk.lines == 2
