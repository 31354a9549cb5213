"""The geometry core: NumPy and the standard library, no web imports.

The per-face mesh loops (and the union-find of :mod:`app.core.orientation`) are compiled with
numba and cached on disk; everything else is plain NumPy.
"""

from app.core.batch import BatchNormals, triangle_normals
from app.core.mesh import FaceNormals, check_mesh, face_areas, face_normals
from app.core.mesh_normals import CornerNormals, VertexNormals, corner_normals, vertex_normals
from app.core.orientation import (
    ComponentOrientation,
    ComponentTable,
    MeshTopology,
    Orientation,
    mesh_topology,
    orient,
    signed_volume,
)
from app.core.triangle import TriangleNormal, triangle_normal

__all__ = [
    "BatchNormals",
    "ComponentOrientation",
    "ComponentTable",
    "CornerNormals",
    "FaceNormals",
    "MeshTopology",
    "Orientation",
    "TriangleNormal",
    "VertexNormals",
    "check_mesh",
    "corner_normals",
    "face_areas",
    "face_normals",
    "mesh_topology",
    "orient",
    "signed_volume",
    "triangle_normal",
    "triangle_normals",
    "vertex_normals",
]
