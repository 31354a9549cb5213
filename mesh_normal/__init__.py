"""Surface normals of triangles, meshes and their files: ``import mesh_normal as mn``.

>>> import mesh_normal as mn
>>> mesh = mn.read_mesh("bunny.obj")           # a path, bytes or a binary file object
>>> mn.face_normals(mesh.vertices, mesh.faces).normals.shape
(69451, 3)
>>> fixed = mn.orient(mesh.vertices, mesh.faces)
>>> mn.write_mesh(mesh.vertices, fixed.faces, path="bunny-fixed.ply")   # or "ply": the bytes

Every name below is loaded on first use, so that ``import mesh_normal`` (and the command line's
``--help``) does not pay for numba until a kernel is needed. The command line is
``mesh-normal`` (or ``python -m mesh_normal``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

#: The one version: the wheel's metadata (hatch reads it here), ``mesh-normal --version``
#: and the web app's OpenAPI document.
__version__ = "0.2.0"

if TYPE_CHECKING:
    from mesh_normal.analysis import MeshAnalysis
    from mesh_normal.analysis import mesh_report as analyse
    from mesh_normal.batch import BatchNormals, triangle_normals
    from mesh_normal.faces import FaceNormals, face_areas, face_normals
    from mesh_normal.files import LoadedMesh, MeshFileError, read_mesh, write_mesh
    from mesh_normal.orientation import Orientation, mesh_topology, orient, signed_volume
    from mesh_normal.report import MeshReport
    from mesh_normal.triangle import TriangleNormal, triangle_normal
    from mesh_normal.vertices import (
        CornerNormals,
        VertexNormals,
        corner_normals,
        vertex_normals,
    )

#: Public name to the module that defines it (``module:name`` where the name differs there).
_HOMES = {
    "BatchNormals": "batch",
    "triangle_normals": "batch",
    "FaceNormals": "faces",
    "face_areas": "faces",
    "face_normals": "faces",
    "LoadedMesh": "files",
    "MeshFileError": "files",
    "read_mesh": "files",
    "write_mesh": "files",
    "Orientation": "orientation",
    "mesh_topology": "orientation",
    "orient": "orientation",
    "signed_volume": "orientation",
    "MeshAnalysis": "analysis",
    "MeshReport": "report",
    "analyse": "analysis:mesh_report",  # mn.analyse(path) is the report
    "TriangleNormal": "triangle",
    "triangle_normal": "triangle",
    "CornerNormals": "vertices",
    "VertexNormals": "vertices",
    "corner_normals": "vertices",
    "vertex_normals": "vertices",
}

__all__ = [
    "BatchNormals",
    "CornerNormals",
    "FaceNormals",
    "LoadedMesh",
    "MeshAnalysis",
    "MeshFileError",
    "MeshReport",
    "Orientation",
    "TriangleNormal",
    "VertexNormals",
    "__version__",
    "analyse",
    "corner_normals",
    "face_areas",
    "face_normals",
    "mesh_topology",
    "orient",
    "read_mesh",
    "signed_volume",
    "triangle_normal",
    "triangle_normals",
    "vertex_normals",
    "write_mesh",
]


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'mesh_normal' has no attribute {name!r}")
    module, _, attribute = home.partition(":")
    value = getattr(importlib.import_module(f"mesh_normal.{module}"), attribute or name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
