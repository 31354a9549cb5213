"""A ``.zip`` holding one mesh file and its neighbours (a ``.gltf`` and its ``.bin``, an OBJ
and its ``.mtl``, textures), read as that mesh.

The one member whose extension names a mesh format is read; a ``.gltf`` finds the files its
URIs name among the other members, read only when asked for, so images cost nothing.

Guarded against zip bombs: at most :data:`MAX_MEMBERS` members; a total uncompressed size of
at most :func:`unpack_limit` (:data:`MAX_RATIO` times the archive, at least :data:`MIN_LIMIT`,
at most :data:`MAX_TOTAL`), checked on the sizes the archive states and again on the bytes
really read; no member named outside the archive (``..``, absolute paths, drive letters).
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import posixpath
import struct
import zipfile
import zlib
from collections.abc import Callable, Iterator

from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.loaded import LoadedMesh

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


def read_zip(data: bytes, read_file: Callable[[bytes, str], LoadedMesh]) -> LoadedMesh:
    """Read the one mesh file in a ``.zip`` (see the module docstring); ``read_file(data,
    name)`` reads a member other than a ``.gltf`` (it is ``read_mesh``, passed in because
    ``read_mesh`` calls this)."""
    with opened_zip(data, "The .zip file could not be opened") as (archive, members, budget):
        member = _mesh_member(members)
        mesh = _read_member(archive, member, members, budget, read_file)
    note = f"Read {member.filename} from the .zip file."
    return dataclasses.replace(mesh, notes=(note, *mesh.notes))


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
    members = {}
    for info in infos:
        name = info.filename.replace("\\", "/")
        parts = name.split("/")
        if name.startswith("/") or ".." in parts or (parts and ":" in parts[0]):
            raise MeshFileError(f"The .zip file names a member outside itself: {name[:100]}.")
        if not info.is_dir():
            members[posixpath.normpath(name)] = info
    return members


def _mesh_member(members: dict[str, zipfile.ZipInfo]) -> zipfile.ZipInfo:
    from mesh_normal.files.formats import suffix_format

    found = [
        info
        for name, info in members.items()
        if suffix_format(name) is not None
        and not name.startswith("__MACOSX/")  # macOS's resource forks, not meshes
        and not posixpath.basename(name).startswith(".")
    ]
    if not found:
        raise MeshFileError(
            "The .zip file holds no mesh file (.gltf, .glb, .obj, .ply, .stl, .off or .3mf)."
        )
    if len(found) > 1:
        names = ", ".join(info.filename for info in found[:5])
        raise MeshFileError(
            f"The .zip file holds {len(found):,} mesh files ({names}); send one mesh a time."
        )
    return found[0]


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


def _read_member(
    archive: zipfile.ZipFile,
    member: zipfile.ZipInfo,
    members: dict[str, zipfile.ZipInfo],
    budget: Budget,
    read_file: Callable[[bytes, str], LoadedMesh],
) -> LoadedMesh:
    from mesh_normal.files.formats import suffix_format
    from mesh_normal.files.gltf import read_gltf

    data = budget.read(archive, member)
    if is_zip(data) and suffix_format(member.filename) != "3mf":  # one level: no fresh budget
        raise MeshFileError(
            f"The member {member.filename} of the .zip file is itself a .zip; send the mesh "
            "file's own archive."
        )
    if suffix_format(member.filename) != "gltf" or data.startswith(b"glTF"):
        return read_file(data, posixpath.basename(member.filename))
    folder = posixpath.dirname(posixpath.normpath(member.filename.replace("\\", "/")))

    def resolve(uri: str) -> bytes | None:
        info = members.get(posixpath.normpath(posixpath.join(folder, uri)))
        return None if info is None else budget.read(archive, info)

    try:
        return read_gltf(data, resolve)
    except MeshFileError:
        raise
    except Exception as error:  # trimesh's own exception, worded as read_mesh words it
        reason = str(error).strip().rstrip(".") or type(error).__name__
        raise MeshFileError(
            f"The file {member.filename} could not be read as glTF: {reason[:200]}."
        ) from error
