"""Which files a batch runs on: files, folders (recursive), glob patterns and fsspec URLs.

A folder or a pattern contributes the files whose suffix names a format the batch reads
(:data:`~mesh_normal.files.formats.ACCEPTED_SUFFIXES`, and with ``points`` also
:data:`~mesh_normal.points.io.read.POINT_SUFFIXES`); the others are counted as skipped, as are
hidden files and folders (a name that starts with a dot: ``.git``, a batch's own ``.parts``). A
file named on its own is always taken: if it is not a mesh, its row says so. The tasks come out
sorted by path, each file once.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from mesh_normal.datasets.tasks import FileTask


class InputError(ValueError):
    """An input that names nothing: a usage error, in one sentence."""


@dataclass(slots=True)
class Found:
    """The files found, sorted by path, and how many others were passed over."""

    tasks: list[FileTask] = field(default_factory=list)
    skipped: int = 0


def suffixes(points: bool) -> frozenset[str]:
    """The suffixes (lower case, with the dot) a folder's or a pattern's files need."""
    from mesh_normal.files.formats import ACCEPTED_SUFFIXES

    if not points:
        return frozenset(ACCEPTED_SUFFIXES)
    from mesh_normal.points.io.read import POINT_SUFFIXES

    return frozenset((*ACCEPTED_SUFFIXES, *POINT_SUFFIXES)) - {".zip"}


def is_url(text: str) -> bool:
    """Whether an input is an fsspec URL (``s3://``, ``memory://``, ``file://``)."""
    return "://" in text


def discover(inputs: Sequence[str], *, points: bool = False, exclude: str | None = None) -> Found:
    """The files of ``inputs``, sorted by path, each once; ``exclude`` is a folder (the
    batch's ``--out``) whose files are never inputs.

    Raises
    ------
    InputError
        When an input is neither a file, a folder nor a pattern that matches something.
    """
    wanted = suffixes(points)
    found = Found()
    tasks: dict[str, FileTask] = {}
    skip = None if exclude is None or is_url(exclude) else os.path.abspath(exclude)
    for text in inputs:
        listed = _url(text) if is_url(text) else _local(text)
        for task, named in listed:
            if skip is not None and _under(task.url, skip):
                continue
            if named or _wanted(task.path, wanted):
                tasks.setdefault(task.path, task)
            else:
                found.skipped += 1
    found.tasks = [tasks[path] for path in sorted(tasks)]
    return found


def _under(path: str, folder: str) -> bool:
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def _wanted(path: str, wanted: frozenset[str]) -> bool:
    name = path.rsplit("/", 1)[-1]
    if "." not in name:
        return False
    return "." + name.rsplit(".", 1)[-1].lower() in wanted


def _hidden(relative: str) -> bool:
    return any(part.startswith(".") for part in relative.split("/") if part not in (".", ".."))


def _local(text: str) -> Iterable[tuple[FileTask, bool]]:
    """(task, named on its own) for a local input."""
    if os.path.isfile(text):
        yield _local_task(text), True
    elif os.path.isdir(text):
        yield from _walk(text)
    elif glob.has_magic(text):
        matches = sorted(glob.glob(text, recursive=True))
        if not matches:
            raise InputError(f"{text} matches no file.")
        for match in matches:
            if os.path.isdir(match):
                yield from _walk(match)
            elif os.path.isfile(match):
                yield _local_task(match), False
    else:
        raise InputError(f"{text} is not a file, a folder or a pattern that matches one.")


def _local_task(path: str) -> FileTask:
    shown = path.replace(os.sep, "/")
    return FileTask(url=os.path.abspath(path), path=shown, size=os.path.getsize(path))


def _walk(folder: str) -> Iterable[tuple[FileTask, bool]]:
    base = folder.rstrip("/" + os.sep) or folder
    for root, folders, files in os.walk(folder):
        folders[:] = sorted(name for name in folders if not name.startswith("."))
        for name in sorted(files):
            if name.startswith("."):
                continue
            path = os.path.join(root, name)
            relative = os.path.relpath(path, folder).replace(os.sep, "/")
            shown = f"{base.replace(os.sep, '/')}/{relative}"
            yield FileTask(os.path.abspath(path), shown, os.path.getsize(path)), False


def _url(text: str) -> Iterable[tuple[FileTask, bool]]:
    """(task, named on its own) for an fsspec URL."""
    import fsspec

    try:
        fs, root = fsspec.core.url_to_fs(text)
    except (ImportError, ValueError) as error:  # no package for the protocol
        raise InputError(f"{text} cannot be opened: {error}") from None
    if glob.has_magic(root):
        matches = fs.glob(root, detail=True)
        if not matches:
            raise InputError(f"{text} matches no file.")
        for path, info in sorted(matches.items()):
            if info.get("type") == "directory":
                yield from _find(fs, path, fs.unstrip_protocol(path))
            elif not _hidden(path):
                url = fs.unstrip_protocol(path)
                yield FileTask(url, _shown(url, text), _size(info)), False
    elif fs.isdir(root):
        yield from _find(fs, root, text)
    elif fs.isfile(root):
        yield FileTask(text, text, _size(fs.info(root))), True
    else:
        raise InputError(f"{text} is not a file, a folder or a pattern that matches one.")


def _shown(url: str, text: str) -> str:
    """``url`` written like the input: ``memory://a`` stays so, not ``memory:///a``."""
    protocol, _, rest = url.partition("://")
    if rest.startswith("/") and not text.partition("://")[2].startswith("/"):
        return f"{protocol}://{rest.lstrip('/')}"
    return url


def _find(fs: object, root: str, shown_root: str) -> Iterable[tuple[FileTask, bool]]:
    listing = fs.find(root, detail=True)  # type: ignore[attr-defined]
    base = shown_root.rstrip("/")
    prefix = root.rstrip("/") + "/"
    for path, info in sorted(listing.items()):
        relative = path[len(prefix) :] if path.startswith(prefix) else path.lstrip("/")
        if info.get("type") == "directory" or _hidden(relative):
            continue
        url = fs.unstrip_protocol(path)  # type: ignore[attr-defined]
        yield FileTask(url, f"{base}/{relative}", _size(info)), False


def _size(info: dict[str, object]) -> int:
    size = info.get("size")
    return int(size) if isinstance(size, int | float) else 0
