"""The geometry core: pure NumPy and the standard library, no web imports."""

from app.core.batch import BatchNormals, triangle_normals
from app.core.triangle import TriangleNormal, triangle_normal

__all__ = ["BatchNormals", "TriangleNormal", "triangle_normal", "triangle_normals"]
