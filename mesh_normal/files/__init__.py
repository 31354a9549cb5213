"""Reading and writing whole-mesh files: STL, OBJ, PLY, OFF, GLB and glTF.

:func:`read_mesh` keeps what the file holds: OBJ, PLY and OFF vertices in file order (none
merged, none dropped, none reordered), faces in file order with polygons fan-triangulated, and
any normals the file stores. STL, which stores separate corners, is welded exactly. Every
problem, from a truncated file to a NaN coordinate, is a :class:`MeshFileError` with one
sentence and a 4xx status; nothing else escapes.
"""

from __future__ import annotations

from mesh_normal.files.errors import MeshFileError
from mesh_normal.files.loaded import LoadedMesh
from mesh_normal.files.read import SUFFIXES, read_mesh
from mesh_normal.files.write import write_mesh

__all__ = ["SUFFIXES", "LoadedMesh", "MeshFileError", "read_mesh", "write_mesh"]
