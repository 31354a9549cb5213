"""Point clouds: normals estimated from each point's neighbours, then oriented; the files
they come in (PLY, XYZ/PTS/TXT/CSV, PCD, LAS/LAZ, and any mesh file's vertices).

>>> import mesh_normal as mn
>>> cloud = mn.read_points("scan.pcd")                # points, stored normals, viewpoint
>>> result = mn.point_normals(cloud.points, k=30)     # (n, 3) float: oriented outward / up
>>> result.normals.shape, result.counts()["ok"], result.components[0]

Names are loaded on first use, like :mod:`mesh_normal`'s: reading a file needs no k-d tree.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mesh_normal._lazy import lazy_names

if TYPE_CHECKING:
    from mesh_normal.points.analysis import PointAnalysis, analyse_points
    from mesh_normal.points.estimate import PointNormals, PointStatus, point_normals
    from mesh_normal.points.io.read import POINT_SUFFIXES, PointCloud, read_points
    from mesh_normal.points.io.write import POINT_WRITE_FORMATS, write_points
    from mesh_normal.points.orient import ORIENT_MODES, ComponentOrientation, OrientMode
    from mesh_normal.points.report import PointReport

#: Public name to the module under ``mesh_normal.points`` that defines it.
_HOMES = {
    "ORIENT_MODES": "orient",
    "ComponentOrientation": "orient",
    "OrientMode": "orient",
    "PointNormals": "estimate",
    "PointStatus": "estimate",
    "point_normals": "estimate",
    "POINT_SUFFIXES": "io.read",
    "PointCloud": "io.read",
    "read_points": "io.read",
    "POINT_WRITE_FORMATS": "io.write",
    "PointAnalysis": "analysis",
    "PointReport": "report",
    "analyse_points": "analysis",
    "write_points": "io.write",
}

__all__ = [
    "ORIENT_MODES",
    "POINT_SUFFIXES",
    "POINT_WRITE_FORMATS",
    "ComponentOrientation",
    "OrientMode",
    "PointAnalysis",
    "PointCloud",
    "PointNormals",
    "PointReport",
    "PointStatus",
    "analyse_points",
    "point_normals",
    "read_points",
    "write_points",
]


__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
