"""A ``.zip`` holding one mesh file and its neighbours (a ``.gltf`` and its ``.bin``, an OBJ
and its ``.mtl``, textures), read as that mesh; or the same files sent one by one
(:func:`read_files`), read exactly as if they were the members of one ``.zip``.

The one member whose extension names a mesh format is read; a ``.gltf`` finds the files its
URIs name among the other members, read only when asked for, so images cost nothing. The
mesh's first note names the files read and those not needed.

Guarded against zip bombs: at most :data:`MAX_MEMBERS` members, counted in the archive's
directory before :mod:`zipfile` parses it (:func:`open_zip`); what the members unpack to is
charged to the input's one expansion budget (:mod:`mesh_normal.files.expansion`) as it is
unpacked, so a member that lies about its size is stopped as it unpacks; no member named
outside the archive (``..``, absolute paths, drive letters), no name twice, no ``.zip`` inside
(a 3MF inside charges the same budget).
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import posixpath
import struct
import zipfile
import zlib
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import TYPE_CHECKING

from mesh_normal.files.errors import MeshFileError, failure_reason
from mesh_normal.files.expansion import charge
from mesh_normal.files.formats import suffix_format

if TYPE_CHECKING:  # not NumPy at import: the app checks archives' names and sizes without it
    from mesh_normal.files.loaded import LoadedMesh

    #: ``read_mesh(data, name)``, passed in because ``read_mesh`` calls this module.
    ReadFile = Callable[[bytes, str | None], LoadedMesh]

#: Most members an archive may hold.
MAX_MEMBERS = 1000
#: Memory a member takes per byte unpacked, by the format it is read as: its bytes while they
#: are read, and the reader's peak (``make bench-memory``: binary STL 5.1, OBJ 4.9, PLY 4.9,
#: OFF 6.0, GLB 5.9). Other members (a glTF's buffers, a 3MF's parts) are held as bytes: 1,
#: and their readers charge what they make of them.
MEMORY_PER_BYTE: dict[str, float] = {"stl": 6, "obj": 6, "ply": 6, "off": 7, "glb": 7, "gltf": 7}
#: Bytes unpacked (and charged) at a time.
CHUNK = 1 << 20
#: What the standard library raises for a damaged archive or member (bad CRC, a broken deflate
#: stream, data cut short), an encrypted one, or a version or method it does not have.
UNPACK_ERRORS = (
    zipfile.BadZipFile,
    zlib.error,
    EOFError,
    RuntimeError,
    NotImplementedError,
    ValueError,  # "negative seek value" for offsets that lie; names that are not UTF-8
    struct.error,
)


def is_zip(data: bytes) -> bool:
    """Whether the bytes are a ``.zip`` archive (a local file header, or an empty archive)."""
    return data.startswith((b"PK\x03\x04", b"PK\x05\x06"))


def read_zip(data: bytes, read_file: ReadFile) -> LoadedMesh:
    """Read the one mesh file in a ``.zip`` (see the module docstring); ``read_file(data,
    name)`` reads a member other than a ``.gltf`` (it is ``read_mesh``, passed in because
    ``read_mesh`` calls this)."""
    with opened_zip(data, ".zip file") as (archive, members):
        chosen = mesh_name(members, "The .zip file holds")
        per_byte = MEMORY_PER_BYTE.get(suffix_format(chosen) or "", 1)
        first = unpack(archive, members[chosen], ".zip file", per_byte)
        if is_zip(first) and suffix_format(chosen) != "3mf":  # one level
            raise MeshFileError(
                f"The member {chosen} of the .zip file is itself a .zip; send the mesh "
                "file's own archive."
            )

        def fetch(name: str) -> bytes | None:
            info = members.get(name)
            return None if info is None else unpack(archive, info, ".zip file")

        mesh, used = read_chosen(chosen, first, fetch, read_file)
    return with_note(mesh, chosen, used, members, "from the .zip file")


def read_files(files: Sequence[tuple[str | None, bytes]], read_file: ReadFile) -> LoadedMesh:
    """Read several files as if they were the members of one ``.zip``: the same choice of the
    one mesh file, the same look-up of the files a ``.gltf`` names, the same guards on names
    (none outside the folder, none twice) and count. A ``.zip`` among them is refused, as a
    ``.zip`` inside a ``.zip`` is; one file alone is read as ``read_file`` reads it."""
    if len(files) == 1:
        name, data = files[0]
        return read_file(data, name)
    if not files:
        raise MeshFileError("No file was sent: send the mesh file (and the files it names).")
    parts = _checked_parts(files)
    where = f"The {len(parts):,} files sent"
    chosen = mesh_name(parts, f"{where} hold")
    if is_zip(parts[chosen]) and suffix_format(chosen) != "3mf":
        raise _zip_among_files(chosen)

    def fetch(name: str) -> bytes:
        if name not in parts:
            raise MeshFileError(
                f"The glTF file {chosen} refers to the separate file {name[:100]}, which is "
                "not among the files sent; send it too, or a .glb."
            )
        return parts[name]

    mesh, used = read_chosen(chosen, parts[chosen], fetch, read_file)
    return with_note(mesh, chosen, used, parts, f"from the {len(parts):,} files sent")


def _checked_parts(files: Sequence[tuple[str | None, bytes]]) -> dict[str, bytes]:
    if len(files) > MAX_MEMBERS:
        raise MeshFileError(f"{len(files):,} files were sent; at most {MAX_MEMBERS:,} at once.")
    parts: dict[str, bytes] = {}
    for number, (given, data) in enumerate(files, start=1):
        if not given:
            raise MeshFileError(
                f"File {number} of the {len(files):,} sent has no name; several files need "
                "their names, which tell the mesh file from the files it refers to."
            )
        name = member_name(given, "One of the files sent is named outside its folder")
        if name in parts:
            raise MeshFileError(f"Two of the files sent are named {name[:100]}; send each once.")
        if name.lower().endswith(".zip"):
            raise _zip_among_files(name)
        parts[name] = data
    return parts


def _zip_among_files(name: str) -> MeshFileError:
    return MeshFileError(
        f"The file {name[:100]} is a .zip among several files; send the .zip alone, or the "
        "files it holds without it."
    )


def member_name(name: str, outside: str) -> str:
    """A member's name, normalised (``\\`` to ``/``, ``a/./b`` to ``a/b``); ``outside`` starts
    the sentence for a name that reaches outside its folder (``..``, absolute, a drive). Names
    with control characters (a line break, say) are refused: sentences quote names."""
    if any(ord(character) < 32 or ord(character) == 127 for character in name):
        raise MeshFileError(f"A file name holds control characters: {name[:100]!a}.")
    name = name.replace("\\", "/")
    parts = name.split("/")
    if name.startswith("/") or ".." in parts or (parts and ":" in parts[0]):
        raise MeshFileError(f"{outside}: {name[:100]}.")
    return posixpath.normpath(name)


def mesh_name(names: Iterable[str], holds: str) -> str:
    """The one name whose extension names a mesh format (macOS's ``__MACOSX/`` forks and
    hidden files aside); ``holds`` starts the sentence when there is none or more than one."""
    found = [
        name
        for name in names
        if suffix_format(name) is not None
        and not name.startswith("__MACOSX/")  # macOS's resource forks, not meshes
        and not posixpath.basename(name).startswith(".")
    ]
    if not found:
        raise MeshFileError(f"{holds} no mesh file (.gltf, .glb, .obj, .ply, .stl, .off or .3mf).")
    if len(found) > 1:
        listed = ", ".join(name[:100] for name in found[:5])
        raise MeshFileError(f"{holds} {len(found):,} mesh files ({listed}); send one mesh a time.")
    return found[0]


def read_chosen(
    chosen: str, data: bytes, fetch: Callable[[str], bytes | None], read_file: ReadFile
) -> tuple[LoadedMesh, list[str]]:
    """The mesh in the member ``chosen`` (its bytes ``data``), and the members its URIs named
    (a ``.gltf``'s buffers), which ``fetch`` gives by normalised name (``None``: absent)."""
    from mesh_normal.files.gltf import read_gltf

    if suffix_format(chosen) != "gltf" or data.startswith(b"glTF"):
        return read_file(data, posixpath.basename(chosen)), []
    folder = posixpath.dirname(chosen)
    used: list[str] = []

    def resolve(uri: str) -> bytes | None:
        name = posixpath.normpath(posixpath.join(folder, uri))
        found = fetch(name)
        if found is not None and name not in used:
            used.append(name)
        return found

    try:
        return read_gltf(data, resolve), used
    except (MeshFileError, MemoryError):  # memory running out is the server's, not the file's
        raise
    except Exception as error:  # trimesh's own exception, worded as read_mesh words it
        raise MeshFileError(
            f"The file {chosen} could not be read as glTF: {failure_reason(error)}."
        ) from error


def with_note(
    mesh: LoadedMesh, chosen: str, used: list[str], names: Iterable[str], source: str
) -> LoadedMesh:
    """The mesh with a first note saying which files were read and which were not needed."""
    note = f"Read {chosen}" + (f" with {_listed(used)}" if used else "") + f" {source}"
    unneeded = [name for name in names if name != chosen and name not in used]
    if unneeded:
        note += f"; not needed for the geometry: {_listed(unneeded)}"
    return dataclasses.replace(mesh, notes=(note + ".", *mesh.notes), files=(chosen, *used))


def _listed(names: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``; beyond five names, ``a, ..., e and 3 more``."""
    shown = [name[:100] for name in names[:5]]
    if len(names) > 5:
        return ", ".join(shown) + f" and {len(names) - 5:,} more"
    return " and ".join(filter(None, (", ".join(shown[:-1]), shown[-1])))


#: The end of central directory record, the zip64 one and its locator (APPNOTE 4.3.14-16).
_END = struct.Struct("<4s4H2LH")
_LOCATOR = struct.Struct("<4sLQL")
_END64 = struct.Struct("<4sQ2H2L4Q")
#: A central directory record: its fixed part, and where its three lengths are.
_ENTRY_SIZE = 46
_LENGTHS = struct.Struct("<3H")


def listed_members(data: bytes) -> tuple[int, int] | None:
    """The members the archive in ``data`` states in its end record, and how many records its
    directory holds, counted no further than ``MAX_MEMBERS + 1``; ``None`` for bytes with no
    end record. Bounded: the end record is found as :mod:`zipfile` finds it (in the last 22
    bytes and up to 64 KB of comment); its count may lie, and :mod:`zipfile` reads the
    directory by its size, so the directory's records are walked as :mod:`zipfile` will."""
    end = _end_record(data)
    if end is None:
        return None
    stated, size, start = end
    position, count = start, 0
    while 0 <= position < start + size and count <= MAX_MEMBERS:
        if position + _ENTRY_SIZE > len(data) or not data.startswith(b"PK\x01\x02", position):
            break  # zipfile refuses the directory here
        count += 1
        position += _ENTRY_SIZE + sum(_LENGTHS.unpack_from(data, position + 28))
    return stated, count


def _end_record(data: bytes) -> tuple[int, int, int] | None:
    """The members the end record states, the directory's size and where it starts."""
    at = len(data) - _END.size
    if not (at >= 0 and data.startswith(b"PK\x05\x06", at) and data.endswith(b"\0\0")):
        at = data.rfind(b"PK\x05\x06", max(len(data) - (1 << 16) - _END.size, 0))
        if at < 0 or at + _END.size > len(data):
            return None
    stated, size = _END.unpack_from(data, at)[4:6]
    start = at - size
    if at >= _LOCATOR.size + _END64.size:
        signature, disk, _, disks = _LOCATOR.unpack_from(data, at - _LOCATOR.size)
        end64 = _END64.unpack_from(data, at - _LOCATOR.size - _END64.size)
        if signature == b"PK\x06\x07" and disk == 0 and disks <= 1 and end64[0] == b"PK\x06\x06":
            stated, size = end64[7:9]
            start = at - _LOCATOR.size - _END64.size - size
    return stated, size, start


def open_zip(data: bytes, title: str = ".zip file") -> zipfile.ZipFile:
    """The archive in ``data``, once its directory lists at most :data:`MAX_MEMBERS` members
    (:func:`listed_members`, before :mod:`zipfile` parses it: a directory of a million
    entries takes seconds and a gigabyte to parse). ``title`` names it in the sentences."""
    stated, count = listed_members(data) or (0, 0)
    if stated > MAX_MEMBERS or count > MAX_MEMBERS:
        listed = f"{stated:,}" if stated > MAX_MEMBERS else f"more than {MAX_MEMBERS:,}"
        raise MeshFileError(f"The {title} lists {listed} members; at most {MAX_MEMBERS:,}.", 413)
    try:
        return zipfile.ZipFile(io.BytesIO(data))
    except UNPACK_ERRORS as error:
        raise MeshFileError(f"The {title} could not be opened: {unpack_reason(error)}.") from error


def unpack_reason(error: Exception) -> str:
    """What :mod:`zipfile` or :mod:`zlib` found wrong, in our words (theirs name internals)."""
    text = str(error).lower()
    if isinstance(error, RuntimeError) and ("encrypted" in text or "password" in text):
        return "it is encrypted"
    if isinstance(error, NotImplementedError) or "not supported" in text:
        return "it uses a compression method or zip feature that is not supported"
    if "crc" in text:
        return "its data does not match its checksum"
    if isinstance(error, zlib.error | EOFError):
        return "its compressed data is damaged or cut short"
    if "not a zip file" in text:
        return "it is not a zip archive, or its end is missing"
    return "its directory or headers are damaged"


@contextlib.contextmanager
def opened_zip(
    data: bytes, title: str
) -> Iterator[tuple[zipfile.ZipFile, dict[str, zipfile.ZipInfo]]]:
    """The archive in ``data`` (:func:`open_zip`) and its members once they pass the guards;
    ``title`` names it in the sentences (``.zip file``, ``3MF file``)."""
    with open_zip(data, title) as archive:
        yield archive, checked_members(archive, title)


def checked_members(archive: zipfile.ZipFile, title: str) -> dict[str, zipfile.ZipInfo]:
    """The archive's files by normalised name, once their names pass the guards."""
    members: dict[str, zipfile.ZipInfo] = {}
    for info in archive.infolist():
        name = member_name(info.filename, f"The {title} names a member outside itself")
        if info.is_dir():
            continue
        if name in members:
            raise MeshFileError(f"The {title} holds two members named {name[:100]}.")
        members[name] = info
    return members


def unpack(
    archive: zipfile.ZipFile, info: zipfile.ZipInfo, title: str, per_byte: float = 1
) -> bytes:
    """The member ``info`` unpacked, charged to the input's expansion budget at ``per_byte``
    bytes of memory a byte, a chunk at a time: the sizes an archive states may lie."""
    what = f"unpacking {info.filename[:100]} from the {title}"
    chunks: list[bytes] = []
    try:
        with archive.open(info) as file:
            while chunk := file.read(CHUNK):
                charge(int(len(chunk) * per_byte), what)
                chunks.append(chunk)
    except MeshFileError:  # the budget's: a ValueError too
        raise
    except UNPACK_ERRORS as error:
        raise MeshFileError(
            f"The member {info.filename[:100]} of the {title} could not be unpacked: "
            f"{unpack_reason(error)}."
        ) from error
    return b"".join(chunks)
