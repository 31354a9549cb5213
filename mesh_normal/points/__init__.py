"""Point clouds: normals estimated from each point's neighbours, then oriented.

>>> import mesh_normal as mn
>>> result = mn.point_normals(points, k=30)          # (n, 3) float: oriented outward / up
>>> result.normals.shape, result.counts()["ok"], result.components[0]
"""

from __future__ import annotations

from mesh_normal.points.estimate import PointNormals, PointStatus, point_normals
from mesh_normal.points.orient import ORIENT_MODES, ComponentOrientation, OrientMode

# read_points: from mesh_normal.points.read (another session)

__all__ = [
    "ORIENT_MODES",
    "ComponentOrientation",
    "OrientMode",
    "PointNormals",
    "PointStatus",
    "point_normals",
]
