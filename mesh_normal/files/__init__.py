"""Reading and writing whole-mesh files: STL, OBJ, PLY, OFF, GLB and glTF.

:func:`read_mesh` keeps what the file holds: OBJ, PLY and OFF vertices in file order (none
merged, none dropped, none reordered), faces in file order with polygons fan-triangulated, and
any normals the file stores. STL, which stores separate corners, is welded exactly. Every
problem, from a truncated file to a NaN coordinate, is a :class:`MeshFileError` with one
sentence and a 4xx status; nothing else escapes, except the ``OSError`` of a path that cannot
be opened. :func:`write_mesh` writes PLY, STL and OBJ. The formats are one table,
:data:`mesh_normal.files.formats.FORMATS`.

Names are loaded on first use, like :mod:`mesh_normal`'s, so that the format table (which the
command line's ``--help`` reads) comes without numpy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mesh_normal._lazy import lazy_names

if TYPE_CHECKING:
    from mesh_normal.files.errors import MeshFileError
    from mesh_normal.files.formats import FORMATS, SUFFIXES, WRITABLE, MeshFormat
    from mesh_normal.files.loaded import LoadedMesh
    from mesh_normal.files.read import read_mesh, read_mesh_files
    from mesh_normal.files.write import write_mesh

#: Public name to the module under ``mesh_normal.files`` that defines it.
_HOMES = {
    "FORMATS": "formats",
    "SUFFIXES": "formats",
    "WRITABLE": "formats",
    "MeshFormat": "formats",
    "LoadedMesh": "loaded",
    "MeshFileError": "errors",
    "read_mesh": "read",
    "read_mesh_files": "read",
    "write_mesh": "write",
}

__all__ = [
    "FORMATS",
    "SUFFIXES",
    "WRITABLE",
    "LoadedMesh",
    "MeshFileError",
    "MeshFormat",
    "read_mesh",
    "read_mesh_files",
    "write_mesh",
]


__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
