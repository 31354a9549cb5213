"""What every command shares: exit codes, failures, progress on stderr, reading and writing."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TextIO, TypeVar

if TYPE_CHECKING:
    from mesh_normal.files import LoadedMesh

Parsed = TypeVar("Parsed")

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE, EXIT_INPUT, EXIT_OUTPUT = 0, 1, 2, 3, 4
#: The output that means standard output, as Unix tools take it.
STDOUT = "-"


class Failure(Exception):
    """A message for stderr and the exit code to leave with."""

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


class Progress:
    """Stage by stage on stderr with elapsed seconds, when stderr is a terminal (or forced)."""

    def __init__(self, stream: TextIO, enabled: bool) -> None:
        self.stream, self.enabled = stream, enabled
        self.start = time.perf_counter()

    def step(self, text: str) -> None:
        if self.enabled:
            elapsed = time.perf_counter() - self.start
            self.stream.write(f"\r\033[K[{elapsed:6.1f} s] {text}")
            self.stream.flush()

    def done(self) -> None:
        if self.enabled:
            self.step("done\n")


def load(path: str, progress: Progress) -> tuple[LoadedMesh, int]:
    from mesh_normal.files import read_mesh
    from mesh_normal.files.read import mapped_binary_stl, read_mapped

    mapped = mapped_binary_stl(path)  # a large binary STL: mapped, not copied into memory
    if mapped is not None:
        progress.step(f"reading {path}")
        size = len(mapped)
        _fault_ahead(size)
        return parsed(path, lambda: read_mapped(mapped, Path(path).name)), size
    data = read_input(path, progress)
    return parsed(path, lambda: read_mesh(data, Path(path).name)), len(data)


def _fault_ahead(size: int) -> None:
    """For a large binary STL of ``size`` bytes, in a process of the command's own: keep freed
    memory for the next step and fault the arrays' memory in on another thread while this one
    reads (``mesh_normal.allocator``). Smaller files and the text formats gain no time from it
    and take more memory."""
    from mesh_normal import allocator

    allocator.start_job(allocator.ARRAYS_PER_STL_BYTE * size)


def read_input(path: str, progress: Progress) -> bytes:
    """The bytes of the file ``path``; one that cannot be read is a failure that says why."""
    progress.step(f"reading {path}")
    try:
        return Path(path).read_bytes()
    except OSError as error:
        raise Failure(f"cannot read {path}: {error.strerror or error}", EXIT_INPUT) from None


def parsed(path: str, parse: Callable[[], Parsed]) -> Parsed:
    """``parse()``, its file's problem (a MeshFileError) a failure that names the file."""
    from mesh_normal.files import MeshFileError

    try:
        return parse()
    except MeshFileError as error:
        raise Failure(f"{path}: {error}", EXIT_INPUT) from None


def write(path: str, data: bytes) -> None:
    """Write ``data`` to standard output for ``-``; else through a temporary file beside
    ``path``, renamed over it: never a half-written file, and ``mesh-normal fix a.obj a.obj``
    cannot lose the input."""
    if path == STDOUT:
        try:
            sys.stdout.buffer.write(data)
            sys.stdout.buffer.flush()
        except BrokenPipeError:  # a reader that stopped early (``| head``)
            # Python would complain again when it flushes stdout at exit.
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            raise Failure(
                "standard output was closed before the data was written", EXIT_OUTPUT
            ) from None
        return
    from mesh_normal.files.write import replace_file

    try:
        replace_file(path, data)
    except OSError as error:
        raise Failure(f"cannot write {path}: {error.strerror or error}", EXIT_OUTPUT) from None


def where(path: str, written: str | None = None) -> str:
    """An output as a sentence names it, with the format ``written`` there where the name
    does not say it (standard output)."""
    if path != STDOUT:
        return path
    return "standard output" if written is None else f"standard output ({written})"


def tell(text: str, output: str | None) -> None:
    """What a command did: on stdout, or on stderr when stdout carries the data (``-o -``),
    so that a pipe gets the data alone."""
    print(text, file=sys.stderr if output == STDOUT else sys.stdout)


def count(number: int, noun: str, plural: str | None = None) -> str:
    """``1 face``, ``2 faces``, ``1,000 vertices``: a count with its noun, in the right number."""
    return f"{number:,} {noun if number == 1 else plural or noun + 's'}"


def output_form(output: str, given: str | None, suffixes: dict[str, str]) -> str:
    """What a command writes to ``output``: ``--format`` (``given``), else what the output's
    suffix names in ``suffixes``, else npy for standard output; a usage failure where the
    suffix names nothing written, or another form than ``--format``."""
    named = None if output == STDOUT else suffixes.get(Path(output).suffix.lower())
    if output != STDOUT and named is None and given is None:
        suffix = Path(output).suffix.lower() or "no suffix"
        raise Failure(
            f"the output must end in {', '.join(suffixes)}, not {suffix} (or give --format)",
            EXIT_USAGE,
        )
    if given is not None and named is not None and given != named:
        raise Failure(
            f"{output} names {named} but --format is {given}; give one, or make them agree",
            EXIT_USAGE,
        )
    return given or named or "npy"


def same_file(one: str, other: str) -> bool:
    """Whether two paths name one file: the same path once resolved, or a (hard) link."""
    if Path(one).resolve() == Path(other).resolve():
        return True
    try:
        return Path(one).samefile(other)
    except OSError:  # either does not exist (yet)
        return False
