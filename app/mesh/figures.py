"""The mesh page's figures for one analysed mesh: the 3D view and the area histogram."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from app.mesh.classes import face_classes
from app.mesh.histogram import area_histogram, histogram_figure
from app.mesh.view import build_view
from app.web.camera import up_axis

if TYPE_CHECKING:
    from mesh_normal.mesh.report.analysis import MeshAnalysis


def mesh_figures(analysis: MeshAnalysis) -> dict[str, Any]:
    """The page's figures for one analysed mesh: ``{"view", "histogram", "histogram_figure"}``."""
    mesh, topology = analysis.mesh, analysis.topology
    # The edges name each point by its first vertex (see mesh_normal.mesh.topology): so do the faces
    # here, or a face on a boundary whose corners are later copies would look fine.
    faces = analysis.points
    classes = face_classes(
        faces,
        len(mesh.vertices),
        analysis.faces.degenerate,
        analysis.orientation.flipped,
        topology.boundary_edge_list,
        topology.nonmanifold_edge_list,
    )
    view = build_view(
        mesh.vertices,
        faces,
        analysis.faces.normals,
        classes,
        topology.boundary_edge_list,
        topology.nonmanifold_edge_list,
        up=up_axis(mesh.format),
    )
    histogram = area_histogram(analysis.faces.areas, analysis.faces.degenerate)
    return {
        "view": view,
        "histogram": histogram,
        "histogram_figure": histogram_figure(histogram) if histogram["counts"] else None,
    }
