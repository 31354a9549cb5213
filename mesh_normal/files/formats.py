"""The one table of mesh file formats: name, suffixes, media type, reader and writer.

Everything else that lists formats (:data:`SUFFIXES`, :data:`WRITABLE`, the command line's
choices, the error sentences) is derived from :data:`FORMATS`. The table names its reader and
writer instead of importing them, so that reading it (for ``mesh-normal --help``, say) loads
neither numpy nor any reader: each format's module under ``mesh_normal.files`` is imported on
its first :meth:`MeshFormat.read` or :meth:`MeshFormat.write`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from mesh_normal.files.loaded import LoadedMesh

    Reader = Callable[[bytes], LoadedMesh]
    #: ``(points, triangles, *, vertex_colors=..., face_colors=..., normals=...,
    #: normals_kind=..., face_groups=..., group_names=...) -> bytes``, the first two already
    #: checked by ``check_mesh``; only formats that hold a kind of colour, normal or group
    #: take it.
    Writer = Callable[..., bytes]

#: What the writers put in the comment of a file's header.
MAKER = "Mesh Normal Calculator"


@dataclass(frozen=True, slots=True)
class MeshFormat:
    """One mesh file format.

    ``module`` is the module under ``mesh_normal.files`` that holds ``read_<name>`` and, when
    ``writable``, ``write_<name>``.
    """

    name: str
    title: str
    suffixes: tuple[str, ...]
    media_type: str
    module: str
    writable: bool = False

    def read(self, data: bytes) -> LoadedMesh:
        """The mesh in ``data``; raises :class:`~mesh_normal.files.MeshFileError` (or whatever
        the reader's library raises, which :func:`~mesh_normal.files.read_mesh` rewords)."""
        reader = cast("Reader", self._function("read"))
        return reader(data)

    def write(
        self,
        points: NDArray[np.float64],
        triangles: NDArray[np.intp],
        vertex_colors: NDArray[np.generic] | None = None,
        face_colors: NDArray[np.generic] | None = None,
        *,
        normals: NDArray[np.float64] | None = None,
        normals_kind: str | None = None,
        face_groups: NDArray[np.intp] | None = None,
        group_names: tuple[str, ...] | None = None,
    ) -> bytes:
        """The bytes of the file; ``points`` and ``triangles`` must be checked already.
        Colours, normals and groups are written where the format holds them
        (:data:`HOLDS_COLORS`, :data:`HOLDS_FACE_COLORS`, :data:`HOLDS_NORMALS`,
        :data:`HOLDS_GROUPS`) and left out elsewhere."""
        if not self.writable:
            raise ValueError(f"{self.title} files cannot be written.")
        writer = cast("Writer", self._function("write"))
        extra: dict[str, object] = {}
        if vertex_colors is not None and self.name in HOLDS_COLORS:
            extra["vertex_colors"] = vertex_colors
        if face_colors is not None and self.name in HOLDS_FACE_COLORS:
            extra["face_colors"] = face_colors
        if normals is not None and normals_kind in HOLDS_NORMALS.get(self.name, ()):
            extra["normals"], extra["normals_kind"] = normals, normals_kind
        if face_groups is not None and group_names is not None and self.name in HOLDS_GROUPS:
            extra["face_groups"], extra["group_names"] = face_groups, group_names
        return writer(points, triangles, **extra)

    def _function(self, verb: str) -> object:
        module = importlib.import_module(f"mesh_normal.files.{self.module}")
        return getattr(module, f"{verb}_{self.name}")


#: Format name to format, in order of preference for writing (PLY keeps float64 exactly).
FORMATS: dict[str, MeshFormat] = {
    entry.name: entry
    for entry in (
        # PLY and OFF have no registered media type.
        MeshFormat("ply", "PLY", (".ply",), "application/octet-stream", "ply", writable=True),
        MeshFormat("stl", "STL", (".stl",), "model/stl", "stl", writable=True),
        MeshFormat("obj", "OBJ", (".obj",), "model/obj", "obj", writable=True),
        MeshFormat("off", "OFF", (".off",), "application/octet-stream", "off", writable=True),
        MeshFormat("glb", "GLB", (".glb",), "model/gltf-binary", "gltf", writable=True),
        MeshFormat("gltf", "glTF", (".gltf",), "model/gltf+json", "gltf"),
        MeshFormat("3mf", "3MF", (".3mf",), "model/3mf", "threemf"),
    )
}

#: Writable formats whose writer takes vertex colours, and what of them each keeps.
HOLDS_COLORS: dict[str, str] = {"ply": "rgba", "obj": "rgb", "glb": "rgba", "off": "rgba"}
#: Writable formats whose writer takes face colours (one per triangle), and what it keeps.
HOLDS_FACE_COLORS: dict[str, str] = {"ply": "rgba", "off": "rgba"}
#: Writable formats whose writer takes normals, and the kinds it holds: PLY ``nx ny nz`` of
#: vertices or faces, OBJ ``vn`` of any kind, OFF ``NOFF`` vertex normals, GLB ``NORMAL``
#: (vertices split where a face's or corner's normal differs), STL facet normals.
HOLDS_NORMALS: dict[str, tuple[str, ...]] = {
    "ply": ("vertex", "face"),
    "obj": ("face", "vertex", "corner"),
    "glb": ("face", "vertex", "corner"),
    "stl": ("face",),
    "off": ("vertex",),
}
#: Writable formats that hold the division into groups (OBJ ``g``).
HOLDS_GROUPS: frozenset[str] = frozenset({"obj"})

#: File extension (lower case, with the dot) to format name.
SUFFIXES: dict[str, str] = {
    suffix: entry.name for entry in FORMATS.values() for suffix in entry.suffixes
}

#: Archives :func:`~mesh_normal.files.read_mesh` opens to read the one mesh file inside, with
#: its neighbours (a ``.gltf`` and its ``.bin``): see :mod:`mesh_normal.files.archive`. Not
#: formats of their own: the mesh keeps the format of the file inside.
ARCHIVE_SUFFIXES: tuple[str, ...] = (".zip",)

#: Files that come with a mesh file and may be sent with it (see
#: :func:`~mesh_normal.files.read_mesh_files`): a ``.gltf``'s buffers, an OBJ's materials.
COMPANION_SUFFIXES: tuple[str, ...] = (".bin", ".mtl")

#: Every suffix :func:`~mesh_normal.files.read_mesh` takes, sorted: the formats' and archives'.
ACCEPTED_SUFFIXES: tuple[str, ...] = tuple(sorted((*SUFFIXES, *ARCHIVE_SUFFIXES)))

#: The formats :func:`~mesh_normal.files.write_mesh` can write, in order of preference.
WRITABLE: tuple[str, ...] = tuple(name for name, entry in FORMATS.items() if entry.writable)


def suffix_format(filename: str | None) -> str | None:
    """The format a file name's extension names, or ``None``."""
    if not filename or "." not in filename:
        return None
    return SUFFIXES.get("." + filename.rsplit(".", 1)[-1].lower())
