"""Surface normals of triangles, meshes and their files: ``import mesh_normal as mn``.

>>> import mesh_normal as mn
>>> mesh = mn.read_mesh("bunny.obj")           # a path, bytes or a binary file object
>>> mn.face_normals(mesh.vertices, mesh.faces).normals.shape
(69451, 3)
>>> fixed = mn.orient(mesh.vertices, mesh.faces)
>>> mn.write_mesh(mesh.vertices, fixed.faces, path="bunny-fixed.ply")   # or "ply": the bytes
>>> mn.face_normals(mesh)                      # a mesh alone: read_mesh's, trimesh's, Open3D's...
>>> mn.show(mesh)                              # a Plotly figure (pip install mesh-normal[show])

Every name below is loaded on first use, so that ``import mesh_normal`` (and the command line's
``--help``) does not pay for NumPy and the readers until a name is needed. The command line is
``mesh-normal`` (or ``python -m mesh_normal``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mesh_normal._lazy import lazy_names

#: The one version: the wheel's metadata (hatch reads it here), ``mesh-normal --version``
#: and the web app's OpenAPI document.
__version__ = "0.2.0"

if TYPE_CHECKING:
    from mesh_normal.datasets.driver import batch
    from mesh_normal.files import LoadedMesh, MeshFileError, read_mesh, write_mesh
    from mesh_normal.mesh.checks import CheckedMesh, checked_mesh
    from mesh_normal.mesh.corners import CornerNormals, corner_normals
    from mesh_normal.mesh.faces import (
        FaceGeometry,
        FaceNormals,
        face_areas,
        face_geometry,
        face_normals,
    )
    from mesh_normal.mesh.orientation import Orientation, orient, signed_volume
    from mesh_normal.mesh.report.analysis import analyse
    from mesh_normal.mesh.report.models import MeshReport
    from mesh_normal.mesh.topology import MeshTopology, mesh_topology
    from mesh_normal.mesh.vertices import VertexNormals, vertex_normals
    from mesh_normal.notebook.show import show
    from mesh_normal.points import (
        ComponentOrientation,
        PointCloud,
        PointNormals,
        PointStatus,
        point_normals,
        read_points,
        write_points,
    )
    from mesh_normal.triangle.batch import BatchNormals, triangle_normals
    from mesh_normal.triangle.normal import TriangleNormal, triangle_normal

#: Public name to the module that defines it (``module:name`` where the name differs there). No
#: module may be named like a public name: the submodule, once imported, would shadow it as an
#: attribute of the package.
_HOMES = {
    "BatchNormals": "triangle.batch",
    "triangle_normals": "triangle.batch",
    "batch": "datasets.driver",  # mn.batch(paths, out=DIR): a Parquet table of reports
    "CheckedMesh": "mesh.checks",
    "checked_mesh": "mesh.checks",
    "CornerNormals": "mesh.corners",
    "corner_normals": "mesh.corners",
    "FaceGeometry": "mesh.faces",
    "FaceNormals": "mesh.faces",
    "face_areas": "mesh.faces",
    "face_geometry": "mesh.faces",
    "face_normals": "mesh.faces",
    "LoadedMesh": "files",
    "MeshFileError": "files",
    "read_mesh": "files",
    "write_mesh": "files",
    "Orientation": "mesh.orientation",
    "orient": "mesh.orientation",
    "signed_volume": "mesh.orientation",
    "ComponentOrientation": "points",
    "PointNormals": "points",
    "PointStatus": "points",
    "point_normals": "points",
    "PointCloud": "points",
    "read_points": "points",
    "write_points": "points",
    "MeshReport": "mesh.report.models",
    "analyse": "mesh.report.analysis",  # mn.analyse(path) is the report
    "MeshTopology": "mesh.topology",
    "mesh_topology": "mesh.topology",
    "show": "notebook.show",  # mn.show(mesh): a Plotly figure (the `show` extra)
    "TriangleNormal": "triangle.normal",
    "triangle_normal": "triangle.normal",
    "VertexNormals": "mesh.vertices",
    "vertex_normals": "mesh.vertices",
}

__all__ = [
    "BatchNormals",
    "CheckedMesh",
    "ComponentOrientation",
    "CornerNormals",
    "FaceGeometry",
    "FaceNormals",
    "LoadedMesh",
    "MeshFileError",
    "MeshReport",
    "MeshTopology",
    "Orientation",
    "PointCloud",
    "PointNormals",
    "PointStatus",
    "TriangleNormal",
    "VertexNormals",
    "__version__",
    "analyse",
    "batch",
    "checked_mesh",
    "corner_normals",
    "face_areas",
    "face_geometry",
    "face_normals",
    "mesh_topology",
    "orient",
    "point_normals",
    "read_mesh",
    "read_points",
    "show",
    "signed_volume",
    "triangle_normal",
    "triangle_normals",
    "vertex_normals",
    "write_mesh",
    "write_points",
]


__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
