"""A ``.zip`` holding one mesh file and its neighbours (a ``.gltf`` and its ``.bin``, an OBJ
and its ``.mtl``, textures), read as that mesh; or the same files sent one by one
(:func:`read_files`), read exactly as if they were the members of one ``.zip``.

The one member whose extension names a mesh format is read; a ``.gltf`` finds the files its
URIs name among the other members, read only when asked for, so images cost nothing. The
mesh's first note names the files read and those not needed.

Guarded against zip bombs: at most :data:`MAX_MEMBERS` members; a total uncompressed size of
at most :func:`unpack_limit` (:data:`MAX_RATIO` times the archive, at least :data:`MIN_LIMIT`,
at most :data:`MAX_TOTAL`), checked on the sizes the archive states and again on the bytes
really read; no member named outside the archive (``..``, absolute paths, drive letters), no
name twice, no ``.zip`` inside (one level only, so one budget).
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
from mesh_normal.files.formats import suffix_format

if TYPE_CHECKING:  # not NumPy at import: the app checks archives' names and sizes without it
    from mesh_normal.files.loaded import LoadedMesh

    #: ``read_mesh(data, name)``, passed in because ``read_mesh`` calls this module.
    ReadFile = Callable[[bytes, str | None], LoadedMesh]

#: Most members an archive may hold.
MAX_MEMBERS = 1000
#: Most bytes all members may hold together, uncompressed.
MAX_TOTAL = 1 << 30
#: Most uncompressed bytes per byte of archive (mesh files compress about 2 to 10 times).
MAX_RATIO = 50
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

#: What any archive may unpack to, whatever its ratio: a small file compresses well.
MIN_LIMIT = 1 << 20


def is_zip(data: bytes) -> bool:
    """Whether the bytes are a ``.zip`` archive (a local file header, or an empty archive)."""
    return data.startswith((b"PK\x03\x04", b"PK\x05\x06"))


def unpack_limit(size: int) -> int:
    """Most bytes an archive of ``size`` bytes may unpack to."""
    return min(MAX_TOTAL, max(MIN_LIMIT, MAX_RATIO * size))


def read_zip(data: bytes, read_file: ReadFile) -> LoadedMesh:
    """Read the one mesh file in a ``.zip`` (see the module docstring); ``read_file(data,
    name)`` reads a member other than a ``.gltf`` (it is ``read_mesh``, passed in because
    ``read_mesh`` calls this)."""
    with opened_zip(data, "The .zip file could not be opened") as (archive, members, budget):
        chosen = mesh_name(members, "The .zip file holds")
        first = budget.read(archive, members[chosen])
        if is_zip(first) and suffix_format(chosen) != "3mf":  # one level: no fresh budget
            raise MeshFileError(
                f"The member {chosen} of the .zip file is itself a .zip; send the mesh "
                "file's own archive."
            )

        def fetch(name: str) -> bytes | None:
            info = members.get(name)
            return None if info is None else budget.read(archive, info)

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


@contextlib.contextmanager
def opened_zip(
    data: bytes, cannot_open: str
) -> Iterator[tuple[zipfile.ZipFile, dict[str, zipfile.ZipInfo], Budget]]:
    """The archive in ``data``, its members once they pass the guards, and the budget of bytes
    it may unpack to; ``cannot_open`` starts the sentence for bytes that are no zip."""
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except UNPACK_ERRORS as error:
        raise MeshFileError(f"{cannot_open}: {error}.") from error
    with archive:
        yield archive, checked_members(archive, len(data)), Budget(unpack_limit(len(data)))


def checked_members(archive: zipfile.ZipFile, size: int) -> dict[str, zipfile.ZipInfo]:
    """The archive's files by normalised name, once its names and sizes pass the guards."""
    infos = archive.infolist()
    if len(infos) > MAX_MEMBERS:
        raise MeshFileError(f"The .zip file holds {len(infos):,} members; at most {MAX_MEMBERS:,}.")
    total = sum(info.file_size for info in infos)
    if total > unpack_limit(size):
        raise MeshFileError(
            f"The .zip file would unpack to {total:,} bytes, more than this reader accepts "
            f"({unpack_limit(size):,}: {MAX_RATIO} times the archive, at most {MAX_TOTAL:,})."
        )
    members: dict[str, zipfile.ZipInfo] = {}
    for info in infos:
        name = member_name(info.filename, "The .zip file names a member outside itself")
        if info.is_dir():
            continue
        if name in members:
            raise MeshFileError(f"The .zip file holds two members named {name[:100]}.")
        members[name] = info
    return members


@dataclasses.dataclass(slots=True)
class Budget:
    """Bytes left to unpack; the archive's stated sizes may lie, so what is read counts."""

    left: int

    def read(self, archive: zipfile.ZipFile, info: zipfile.ZipInfo) -> bytes:
        try:
            with archive.open(info) as file:
                data = file.read(self.left + 1)
        except UNPACK_ERRORS as error:
            reason = str(error).strip().rstrip(".") or type(error).__name__
            raise MeshFileError(
                f"The member {info.filename} of the archive could not be unpacked: {reason}."
            ) from error
        if len(data) > self.left:
            raise MeshFileError("The .zip file unpacks to more than its members state.")
        self.left -= len(data)
        return data
