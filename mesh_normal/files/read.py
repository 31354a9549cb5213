"""Which format a file is in, and the one entry point that reads any of them."""

from __future__ import annotations

import dataclasses
import io
import mmap
import os
import re
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Protocol
from urllib.parse import unquote

from mesh_normal.files.archive import is_zip
from mesh_normal.files.errors import MeshFileError, failure_reason, unsupported
from mesh_normal.files.expansion import expanding
from mesh_normal.files.formats import FORMATS, SUFFIXES, suffix_format
from mesh_normal.files.loaded import LoadedMesh
from mesh_normal.files.stl import HEADER, RECORD, is_binary, looks_ascii


class BinaryReadable(Protocol):
    """A file object opened in binary mode (``open(path, "rb")``, ``io.BytesIO``, an upload)."""

    def read(self) -> bytes: ...


#: What :func:`read_mesh` reads: a path, the file's bytes, or a binary file object.
MeshSource = str | os.PathLike[str] | bytes | bytearray | memoryview | BinaryReadable

_OFF = re.compile(rb"\s*(?:#[^\n]*\n\s*)*(?:ST)?C?N?4?n?OFF\b")
_OBJ = re.compile(rb"^[ \t]*(?:v|f)[ \t]", re.MULTILINE)


def read_mesh(source: MeshSource, filename: str | None = None) -> LoadedMesh:
    """Read a mesh file; the format comes from the bytes, else from the file name's extension.

    Parameters
    ----------
    source : str, os.PathLike, bytes or binary file object
        The file: a path, its bytes, or a file object opened in binary mode.
    filename : str, optional
        Only helps tell the format (and names it in notes); for a path or a file object
        with a ``name`` it defaults to that name.

    Returns
    -------
    LoadedMesh
        The vertices ``(n, 3)``, the triangles ``(m, 3)`` and what else the file holds.

    Raises
    ------
    MeshFileError
        With one sentence naming the problem: 400 for a broken file or bad content, 413 for
        one that expands past its budget (:mod:`mesh_normal.files.expansion`: a zip bomb, a
        3MF that places one object thousands of times), 415 for a format that is unknown or
        not supported.
    OSError
        A path that cannot be opened, as Python raises it (``FileNotFoundError``,
        ``PermissionError``, ``IsADirectoryError``), like ``open`` and ``numpy.load``: the file
        was never read, so there is no mesh to judge.
    TypeError
        A source of another type, or a file object opened in text mode.

    Examples
    --------
    >>> read_mesh("bunny.obj")                         # a path (str or os.PathLike)
    >>> read_mesh(data, "bunny.obj")                   # bytes, with the name if known
    >>> with open("bunny.obj", "rb") as file:          # a binary file object
    ...     mesh = read_mesh(file)
    """
    mapped = mapped_binary_stl(source)
    if mapped is not None:
        return read_mapped(mapped, filename or Path(source).name)  # type: ignore[arg-type]
    data, filename = source_bytes(source, filename)
    with expanding(len(data)):  # one budget for all it expands into
        return _read_bytes(data, filename, source)


def _read_bytes(data: bytes, filename: str | None, source: object) -> LoadedMesh:
    if not data:
        raise MeshFileError("The file is empty (0 bytes).")
    if data.startswith(b"\xef\xbb\xbf"):  # a UTF-8 byte order mark: text formats only
        data = data[3:]
    named = suffix_format(filename)
    if is_zip(data) and (sniff(data) or named) != "3mf":  # a 3MF file is a zip package itself
        from mesh_normal.files.archive import read_zip

        return read_zip(data, read_mesh)
    found = sniff(data) or named
    if found is None:
        raise unknown_format(filename)
    return _read_as(found, named, data, source)


def _read_as(found: str, named: str | None, data: bytes, source: object = None) -> LoadedMesh:
    """``data`` read as the format ``found``; a library's exception becomes a
    :class:`MeshFileError`, and a note says so where the name (``named``) gave another format.
    ``source``: the path a glTF was read from, to find the files beside it."""
    try:
        if found == "gltf" and isinstance(source, str | os.PathLike):
            from mesh_normal.files.gltf import read_gltf

            mesh = read_gltf(data, _beside(Path(source)))
        else:
            mesh = FORMATS[found].read(data)
    except (MeshFileError, MemoryError):  # memory running out is the server's, not the file's
        raise
    except Exception as error:  # a library's own exception: never a 500
        raise MeshFileError(
            f"The file could not be read as {FORMATS[found].title}: {failure_reason(error)}."
        ) from error
    if named is not None and named != found:
        named_as, holds = FORMATS[named].title, FORMATS[found].title
        note = f"The file is named as {named_as} but holds {holds}; it was read as {holds}."
        mesh = dataclasses.replace(mesh, notes=(note, *mesh.notes))
    return mesh


#: A path to a binary STL of this many bytes or more is mapped rather than read: its pages come
#: from the system's file cache as the reader touches them, instead of a copy in fresh memory
#: (for a 700 MB file, more than ten times faster, and 700 MB less memory).
MAPPED_BYTES = 1 << 26


def mapped_binary_stl(source: MeshSource) -> mmap.mmap | None:
    """The file of a path, mapped read-only, when it is a large binary STL (its length is what
    its header's triangle count calls for, and nothing else claims its first bytes); else
    ``None``, and :func:`read_mesh` reads the bytes as ever (raising the path's own errors)."""
    if not isinstance(source, str | os.PathLike):
        return None
    try:
        with open(source, "rb") as file:
            size = os.fstat(file.fileno()).st_size
            if size < MAPPED_BYTES:
                return None
            if not reads_as_binary_stl(file.read(4096), size):
                return None
            return mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ)
    except (OSError, ValueError):
        return None


def reads_as_binary_stl(head: bytes, size: int) -> bool:
    """Whether a file of ``size`` bytes that starts with ``head`` (its first 4096 bytes, or all
    of it) is read by :func:`read_mesh` as a binary STL: its length is what the header's
    triangle count calls for, and a zip, a byte order mark or another format's start does not
    claim it first. Such a file can be read from a map of it (:func:`read_mapped`)."""
    if is_zip(head) or head.startswith(b"\xef\xbb\xbf") or sniff(head[:4096]) not in ("stl", None):
        return False
    if len(head) < HEADER:
        return False
    count = int.from_bytes(head[80:HEADER], "little")
    return size == HEADER + RECORD.itemsize * count


def read_mapped(mapped: mmap.mmap, filename: str) -> LoadedMesh:
    """:func:`read_mesh` of a mapped binary STL (see :func:`mapped_binary_stl`): the same mesh
    and notes as from its bytes. The map closes when the last array over it goes (the reader
    keeps none: the weld and the facet normals are copies). A file cut short by another program
    while it is being read ends the process (SIGBUS), as with any mapped file."""
    return _read_as("stl", suffix_format(filename), mapped)  # type: ignore[arg-type]


def read_mesh_files(files: Iterable[tuple[str | None, bytes]]) -> LoadedMesh:
    """Read one mesh sent as several files, as ``(name, bytes)`` pairs, exactly as if they
    were the members of one ``.zip`` (see :mod:`mesh_normal.files.archive`).

    >>> read_mesh_files([("Box.gltf", gltf), ("Box0.bin", buffer)])  # a .gltf and its .bin
    >>> read_mesh_files([("model.obj", obj), ("model.mtl", mtl)])   # the .mtl is not needed

    The one file whose extension names a mesh format is read; a ``.gltf`` finds the files its
    relative URIs name among the others. Names must not reach outside their folder (``..``,
    absolute paths) nor come twice, and a ``.zip`` is sent alone; each problem is a
    :class:`MeshFileError` with one sentence. One pair alone is read as :func:`read_mesh`
    reads it.
    """
    from mesh_normal.files.archive import read_files

    parts = list(files)
    with expanding(sum(len(data) for _, data in parts)):
        return read_files(parts, read_mesh)


def _beside(path: Path) -> Callable[[str], bytes | None]:
    """Find the files a glTF's relative URIs name in the folder of the glTF read from ``path``."""

    def resolve(uri: str) -> bytes | None:
        if ":" in uri.split("/", 1)[0]:  # a scheme (http:, file:) or a drive: nothing to fetch
            return None
        beside = path.parent / unquote(uri)
        return beside.read_bytes() if beside.is_file() else None

    return resolve


def source_bytes(source: MeshSource, filename: str | None) -> tuple[bytes, str | None]:
    """The bytes to read and the file name to go by."""
    if isinstance(source, bytes | bytearray | memoryview):
        return bytes(source), filename
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        return path.read_bytes(), filename or path.name
    if isinstance(source, io.TextIOBase):
        raise TypeError(_TEXT_MODE)
    read = getattr(source, "read", None)
    if not callable(read):
        raise TypeError(
            "read_mesh reads a path (str or os.PathLike), bytes or a binary file object, "
            f"not {type(source).__name__}."
        )
    data = read()
    if isinstance(data, str):
        raise TypeError(_TEXT_MODE)
    if not isinstance(data, bytes | bytearray | memoryview):
        raise TypeError(f"The file object's read() gave {type(data).__name__}, not bytes.")
    name = getattr(source, "name", None)
    if filename is None and isinstance(name, str | os.PathLike):
        filename = Path(name).name  # an int name is a file descriptor: nothing to go by
    return bytes(data), filename


_TEXT_MODE = "read_mesh needs a file opened in binary mode: open(path, 'rb'), not 'r'."


def sniff(data: bytes) -> str | None:
    """The format the bytes themselves show, or ``None`` (OBJ only when it is plain)."""
    head = data[:4096]
    if is_zip(data):
        from mesh_normal.files.threemf import is_3mf

        return "3mf" if is_3mf(data) else None
    if head.startswith(b"glTF"):
        return "glb"
    if re.match(rb"ply\r?\n", head):
        return "ply"
    if is_binary(data) or looks_ascii(data):
        return "stl"
    if _OFF.match(head):
        return "off"
    if head.lstrip().startswith(b"{") and b'"asset"' in data:
        return "gltf"
    if b"\0" not in head and _OBJ.search(head):
        return "obj"
    return None


def unknown_format(filename: str | None) -> MeshFileError:
    formats = ", ".join(sorted(SUFFIXES))
    if filename and "." in filename:
        suffix = filename.rsplit(".", 1)[-1][:20]
        return unsupported(
            f"The format of this .{suffix} file is not supported; the formats are {formats}."
        )
    return unsupported(
        f"The file's format was not recognised from its content; the formats "
        f"are {formats} (a file name with its extension helps)."
    )
