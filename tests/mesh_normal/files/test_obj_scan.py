"""The compiled OBJ scan against the Python one: the same statements, bits and errors.

Every OBJ here is read twice, by the compiled scan (as every file is read) and by the Python
path alone (the scan made to decline every chunk), and the two must agree in every array's
bytes and in every note and error message: the scan reads a chunk only when it can certify it,
and declines it to the Python path otherwise. Its numbers must be the bits of ``float()``.
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

FAST, SLOW = True, False
PRESCAN = obj._prescan


def declined(_data: bytes, _start: int, _end: int) -> None:
    return None


def compiled(monkeypatch: pytest.MonkeyPatch, fast: bool) -> None:
    """Read with the compiled scan (``FAST``), or with the Python path alone (``SLOW``)."""
    monkeypatch.setattr(obj, "_prescan", PRESCAN if fast else declined)


def scanned(monkeypatch: pytest.MonkeyPatch, data: bytes, fast: bool) -> Any:
    """``obj._scan(data)``'s statements as plain values, or the error's message."""
    compiled(monkeypatch, fast)
    try:
        found = obj._scan(data)
    except (MeshFileError, OverflowError) as error:
        return f"{type(error).__name__}: {error}"
    return {field.name: _plain(getattr(found, field.name)) for field in dataclasses.fields(found)}


def _plain(value: object) -> object:
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    return value


def read(monkeypatch: pytest.MonkeyPatch, data: bytes, fast: bool) -> Any:
    """The whole reader's answer: every array of the mesh, its notes, or the error."""
    compiled(monkeypatch, fast)
    try:
        mesh = obj.read_obj(data)
    except (MeshFileError, OverflowError) as error:
        return f"{type(error).__name__}: {error}"
    return {
        field.name: _plain(getattr(mesh, field.name))
        for field in dataclasses.fields(mesh)
        if not callable(getattr(mesh, field.name))
    }


def same_both_ways(monkeypatch: pytest.MonkeyPatch, data: bytes) -> Any:
    fast, slow = scanned(monkeypatch, data, FAST), scanned(monkeypatch, data, SLOW)
    assert fast == slow
    assert read(monkeypatch, data, FAST) == read(monkeypatch, data, SLOW)
    return fast


def fast_reads(data: bytes) -> bool:
    """Whether the scan certifies ``data`` as one chunk (rather than declining it)."""
    groups = obj._Groups([obj._DEFAULT_GROUP], {obj._DEFAULT_GROUP: 0})
    read = PRESCAN(data, 0, len(data))
    if read is None:
        return False
    return obj._scan_fast(read, 0, 0, 0, groups, Counter(), Counter()) is not None


# --- numbers: the bits of float() -------------------------------------------------------------


def scan_float(token: str) -> float:
    value = read_decimal(token)
    assert value is not None, token
    return value


def same_bits(a: float, b: float) -> bool:
    return np.float64(a).tobytes() == np.float64(b).tobytes()


@st.composite
def decimal_tokens(draw: st.DrawFn) -> str:
    sign = draw(st.sampled_from(["", "-", "+"]))
    whole = draw(st.text("0123456789", max_size=22))
    fraction = draw(st.none() | st.text("0123456789", max_size=22))
    if not whole and not fraction:
        whole = "0"
    exponent = draw(
        st.none()
        | st.tuples(st.sampled_from("eE"), st.sampled_from(["", "+", "-"]), st.integers(0, 400))
    )
    token = sign + whole + ("" if fraction is None else "." + fraction)
    if exponent is not None:
        token += f"{exponent[0]}{exponent[1]}{exponent[2]}"
    return token


@settings(max_examples=3000, deadline=None)
@given(decimal_tokens())
def test_every_decimal_token_reads_as_python_float(token: str) -> None:
    assert same_bits(scan_float(token), float(token)), token


@settings(max_examples=2000, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False), st.integers(1, 17))
def test_doubles_written_with_any_number_of_digits_read_back_exactly(
    value: float, digits: int
) -> None:
    for token in (repr(value), f"{value:.{digits}g}", f"{value:.{digits}e}"):
        assert same_bits(scan_float(token), float(token)), token


@pytest.mark.parametrize(
    "token",
    [
        "0.1",
        "-0",
        "-0.0e-5",
        "9007199254740992",  # 2**53: the largest exact mantissa
        "9007199254740993",  # one more: rounded
        "1e22",
        "1e23",
        "123456789012345678e-22",
        "2.2250738585072011e-308",
        "4.9406564584124654e-324",
        "2.4703282292062328e-324",
        "1.7976931348623159e308",
        "1e400",
        "1e-400",
        ".5",
        "5.",
        "0.000000000000000000000000000000000001",
        "100000000000000000000000000000000000000000000001",
        "1.7976931348623157e308",  # the largest double
        "1.797693134862316e308",  # rounds to infinity
        "-1e400",
        "-1e-400",  # -0.0
        "0e99999999999999999999",
        "1e99999999999999999999",
        "1e-99999999999999999999",
        "0." + "0" * 400 + "1e400",
        "1" + "0" * 400 + "e-400",
        "0.1000000000000000055511151231257827021181583404541015625",
        "1.e5",
        "+.5e-3",
    ],
)
def test_the_edges_of_the_exact_fast_path(token: str) -> None:
    assert same_bits(scan_float(token), float(token))


@pytest.mark.parametrize(
    "token",
    [
        "",
        "-",
        ".",
        "e5",
        ".e5",
        "1e",
        "1e+",
        "1.2.3",
        "1-2",
        "+-1",
        "nan",
        "inf",
        "1_0",
        "0x10",
        "1#",
        "1e5.5",
        "1 2",
    ],
)
def test_what_is_no_decimal_is_declined(token: str) -> None:
    assert read_decimal(token) is None


# --- whole files: the scan and the Python path agree -------------------------------------------

TETRA = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"


@pytest.mark.parametrize(
    ("text", "certified"),
    [
        (TETRA + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n", True),
        (TETRA + "vn 0 0 1\nvt 0 0\nf 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\n", True),
        (TETRA + "f 1/1 3/1 2/1\nf -4 -3 -2 -1\n", True),
        (TETRA + "vn 0 0 1\nf 1//1 2//1 3//\n", True),  # a corner without its normal
        (TETRA + "f 1/ 2// 3\n", True),
        (TETRA + "f +1 2 3 # a comment\nf 1 2 4#no space\n", True),
        (TETRA + "f 1 2 3 4 # a quad\nf 2 3\nf \n", True),
        ("# a header\r\n" + TETRA.replace("\n", "\r\n") + "f 1 2 3\r\n\r\n", True),
        ("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n", True),  # colours
        ("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0.5\nf 1 2 3\n", True),  # mixed widths, w
        ("v 0.1234567890123456789 1e300 -2.5e-310\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", True),
        (
            "mtllib a.mtl\no thing\n" + TETRA + "g lid\nusemtl red\ns off\nf 1 2 3\nl 1 2\np 3\n",
            True,
        ),
        (TETRA + "o a\nf 1 2 3\ng b c\nf 1 2 4\no a\ng\nf 1 3 4\ncurv 1 2\nfoo bar\n", True),
        (TETRA + "vt 0 0\nvtx 1\nvn 0 0 1\nf 1 2 3\n", True),
        (TETRA + "f 1 2 \\\n 3\n", False),  # a continued line
        (TETRA + "f 1 2 3 \\\nf 1 2 3 \\", False),  # into another "f": an error, no crash
        ("v\t0 0 0\n" + TETRA + "f 1 2 3\n", False),  # a tab after the keyword
        ("  v 0 0 0\n" + TETRA + "f 1 2 3\n", False),  # indented
        (TETRA + "\tf 1 2 3\n", False),
        (TETRA + "f\t1 2 3\n", False),
        ("v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", False),
        ("v 0 0 1_0\nv 1 0 0\nv inf 1 0\nf 1 2 3\n", False),
        ("v 0 0 0 # here\n" + TETRA + "f 1 2 3\n", False),
        ("v 0 0\n" + TETRA + "f 1 2 3\n", False),  # too few numbers: the error
        ("v 0 0 x\n" + TETRA + "f 1 2 3\n", False),
        ("vnx 0 0 1\n" + TETRA + "f 1 2 3\n", False),
        (TETRA + "f 1 2 0\n", True),  # index 0: the same error from both
        (TETRA + "f 1 2 9\n", True),
        (TETRA + "f 1 2 -9\n", True),
        (TETRA + "f 1 2 3.0\n", False),
        (TETRA + "f 1 2 /3\n", False),
        (TETRA + "f 1 2 3/4/5/6\n", False),
        (TETRA + "f 1 2 1234567890123456789012\n", False),
        (TETRA + "f 1 2 3\x85f 1 2 4\n", False),  # NEL: a line break to Python
        (TETRA + "f 1 2 3\rf 1 2 4\n", False),  # a lone CR
        (TETRA + "# \x0c form feed\nf 1 2 3\n", False),
        (TETRA + "f 1 2 3\xa04\n", False),  # a no-break space: a separator to str.split
        (TETRA + "o W\xc3\xbcrfel\nf 1 2 3\n", True),
        ("", True),
        ("\n\n", True),
        ("# nothing\n", True),
    ],
)
def test_the_scan_and_the_python_path_agree(
    monkeypatch: pytest.MonkeyPatch, text: str, certified: bool
) -> None:
    data = text.encode("latin-1")
    same_both_ways(monkeypatch, data)
    assert fast_reads(data) == certified


def test_a_file_of_many_chunks_some_declined(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(obj, "_TEXT_CHUNK", 64)
    rng = np.random.default_rng(3)
    lines = [f"v {x!r} {y:.6g} {z:.3e}" for x, y, z in rng.normal(size=(60, 3)).tolist()]
    lines.insert(20, "v 1 2 \\\n 3")  # this chunk goes to Python
    lines.insert(40, "o part")
    lines += [f"f {a} {b}/{a} {c}" for a, b, c in rng.integers(1, 61, (80, 3)).tolist()]
    lines.insert(100, "g side")
    lines.insert(120, "f -1 -2 -3 -4")
    found = same_both_ways(monkeypatch, "\n".join(lines).encode())
    assert found["labels"] == ["default", "part", "part/side"]


_LINES = st.sampled_from(
    [
        "v 1 2 3",
        "v -1.5 2e3 .25",
        "v 0.1234567890123456789 -7 1e-300",
        "v 1 2 3 0.5 0.25 1",
        "v 1 2 3 4",
        "vn 0 0 1",
        "vn 0.6 0.8 0",
        "vt 0.5 0.5",
        "f 1 2 3",
        "f -1 -2 -3",
        "f 1/1 2/1 3/1",
        "f 1//1 2//1 3//1",
        "f 1/1/1 2/1/1 3/1/1 4/1/1",
        "f 1// 2 3/",
        "f 1 2",
        "f 0 1 2",
        "# comment",
        "",
        "o obj",
        "g grp",
        "g",
        "s 1",
        "usemtl m",
        "l 1 2",
        "v 1 2",
        "v 1 2 nan",
        " v 1 2 3",
        "f 1 2 3 \\",
        "f 1 2 x",
        "vnx 1",
    ]
)


@settings(
    max_examples=400, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.lists(_LINES, max_size=30), st.sampled_from(["\n", "\r\n"]), st.booleans())
def test_random_files_read_the_same_both_ways(
    monkeypatch: pytest.MonkeyPatch, lines: list[str], end: str, final: bool
) -> None:
    text = end.join(lines) + (end if final else "")
    same_both_ways(monkeypatch, text.encode())


@pytest.mark.parametrize("count", [3, 100_000])
def test_small_and_large_files_take_the_compiled_scan(
    monkeypatch: pytest.MonkeyPatch, count: int
) -> None:
    calls: list[int] = []
    scan = obj.scan_obj

    def counted(chunk: Any) -> Any:
        calls.append(len(chunk))
        return scan(chunk)

    monkeypatch.setattr(obj, "scan_obj", counted)
    text = "".join(f"v {i} {i + 0.5} 0.125\n" for i in range(count)) + "f 1 2 3\n"
    found = obj._scan(text.encode())
    assert sum(calls) == len(text) and len(found.vertices) == count
    assert found.vertices[2].tolist() == [2.0, 2.5, 0.125]
    assert found.vertex_fields.tolist() == [1, 2, 3] and found.counts.tolist() == [3]


@pytest.mark.parametrize("threads", [2, 3])
def test_chunks_scanned_on_several_threads_read_as_on_one(
    monkeypatch: pytest.MonkeyPatch, threads: int
) -> None:
    # Small chunks, some declined by the scan (a continued line, a tab-indented v) between
    # ones it reads: the same statements, in file order, however many threads scan them.
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


def test_the_scan_takes_only_bytes_as_they_are() -> None:
    # A wrong type or a strided view is refused, not copied into another type.
    with pytest.raises(TypeError):
        obj.scan_obj(np.zeros(4, np.int8))  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        obj.scan_obj(np.frombuffer(b"v 1 2 3\n" * 2, np.uint8)[::2])
    read = obj.scan_obj(np.frombuffer(b"v 1 2 3\nf 1 1 1\n", np.uint8))
    assert read is not None and read[1].tolist() == [[1.0, 2.0, 3.0]]
