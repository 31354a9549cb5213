"""One mesh, analysed once: the arrays behind the report, and the report built from them.

:func:`analyse_mesh` runs the core on a :class:`~mesh_normal.files.LoadedMesh` once and keeps the
arrays (the page draws them); :func:`build_report` sums them up as a
:class:`~mesh_normal.report.MeshReport`; :func:`analyse` does both from a file, and is the
library's ``mn.analyse``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mesh_normal.diagnosis import problems
from mesh_normal.faces import FaceGeometry, FaceNormals, face_geometry, face_normals
from mesh_normal.files import LoadedMesh, read_mesh
from mesh_normal.files.read import MeshSource, source_bytes
from mesh_normal.objects import object_reports
from mesh_normal.orientation import Orientation, orient
from mesh_normal.report import (
    INDEX_LIST_LIMIT,
    Bounds,
    ComponentFix,
    FileInfo,
    FileNormals,
    Fix,
    MeshReport,
    ObjectReport,
)
from mesh_normal.stored_normals import stored_normal_agreement
from mesh_normal.topology import MeshTopology, by_position


@dataclass(frozen=True, slots=True)
class MeshAnalysis:
    """Everything the report says about one mesh, with the arrays behind it."""

    mesh: LoadedMesh
    name: str | None
    size: int
    geometry: FaceGeometry
    faces: FaceNormals
    topology: MeshTopology
    orientation: Orientation
    unused_vertices: int


def analyse_mesh(mesh: LoadedMesh, name: str | None = None, size: int = 0) -> MeshAnalysis:
    """Run every check of the core on ``mesh`` (read from a file of ``size`` bytes).

    Returns the arrays (face normals, topology, orientation) that :func:`build_report` sums up
    and the page draws; for the report alone use :func:`analyse`.
    """
    # One pass: the reader checked the arrays, and the cross products are taken once here for
    # the face normals, the orientation's volumes and the file-normal comparison alike.
    geometry = face_geometry(mesh.checked())
    orientation = orient(geometry)
    used = np.zeros(len(mesh.vertices), dtype=bool)
    used[mesh.faces.ravel()] = True
    return MeshAnalysis(
        mesh=mesh,
        name=name,
        size=size,
        geometry=geometry,
        faces=face_normals(geometry),
        topology=orientation.topology,
        orientation=orientation,
        unused_vertices=int(len(used) - np.count_nonzero(used)),
    )


def analyse(source: LoadedMesh | MeshSource, filename: str | None = None) -> MeshReport:
    """The report on a mesh: ``mn.analyse(path)``.

    ``source`` is a mesh already read (:class:`~mesh_normal.files.LoadedMesh`), or a path, the
    file's bytes or a binary file object; ``filename`` names it in the report (by default the
    path's or the file object's name) and, for bytes without a recognisable header, gives the
    format by its extension.

    Returns
    -------
    MeshReport
        Counts, checks, the fix and the diagnosis, as ``POST /api/mesh`` answers them:
        ``report.model_dump_json()`` is that JSON, ``report.problems`` the diagnosis.

    Raises
    ------
    MeshFileError
        When the file is not a mesh that can be read.
    OSError
        When the path cannot be read.
    TypeError
        When a file object gives text, not bytes.
    """
    if isinstance(source, LoadedMesh):
        return build_report(analyse_mesh(source, filename, 0))
    if isinstance(source, str | os.PathLike):  # read as a path: a .gltf finds its .bin beside it
        path = Path(source)
        named = filename or path.name
        return build_report(analyse_mesh(read_mesh(path, named), named, path.stat().st_size))
    data, name = source_bytes(source, filename)
    return build_report(analyse_mesh(read_mesh(data, name), name, len(data)))


def build_report(analysis: MeshAnalysis) -> MeshReport:
    """The report: counts, checks, the fix that orient() would make, and the diagnosis."""
    mesh, topology, orientation = analysis.mesh, analysis.topology, analysis.orientation
    degenerate = analysis.faces.degenerate
    report = MeshReport(
        file=FileInfo(name=analysis.name, format=mesh.format, bytes=analysis.size),
        vertices=len(mesh.vertices),
        faces=len(mesh.faces),
        source_faces=mesh.source_faces,
        unused_vertices=analysis.unused_vertices,
        area=float(np.sum(analysis.faces.areas)),
        volume=orientation.volume,
        watertight=topology.watertight,
        winding_consistent=topology.winding_consistent,
        orientation=orientation.orientation,
        degenerate_faces=int(np.count_nonzero(degenerate)),
        degenerate_face_indices=first_indices(degenerate),
        # Faces with a repeated index are the ones outside every component.
        repeated_index_faces=int(np.count_nonzero(topology.face_component < 0)),
        boundary_edges=topology.boundary_edges,
        nonmanifold_edges=topology.nonmanifold_edges,
        components=topology.components,
        nonorientable_components=int(np.count_nonzero(~orientation.components.orientable)),
        bounds=_bounds(mesh.vertices),
        fix=_fix(orientation),
        file_normals=file_normal_agreement(analysis),
        object_count=0 if mesh.group_names is None else len(mesh.group_names),
        objects=_objects(analysis),
        notes=list(mesh.notes),
        problems=[],  # the diagnosis reads the rest of the report
    )
    return report.model_copy(update={"problems": problems(report)})


def _objects(analysis: MeshAnalysis) -> list[ObjectReport]:
    groups, names = analysis.mesh.face_groups, analysis.mesh.group_names
    if groups is None or names is None:
        return []
    # The faces by position again (one hash sort): the topology keeps only its sums.
    points = by_position(analysis.geometry.mesh)
    return object_reports(groups, names, analysis.faces, analysis.orientation, points)


def first_indices(mask: NDArray[np.bool_]) -> list[int]:
    """The first INDEX_LIST_LIMIT indices where ``mask`` is true, 0-based."""
    return [int(index) for index in np.flatnonzero(mask)[:INDEX_LIST_LIMIT]]


def _bounds(vertices: NDArray[np.float64]) -> Bounds | None:
    if not len(vertices):
        return None
    return Bounds(min=vertices.min(axis=0).tolist(), max=vertices.max(axis=0).tolist())


def flips_by_component(orientation: Orientation) -> str:
    """``"component:faces"`` for the first components with flipped faces, e.g. ``"0:1,3:12"``."""
    flipped = orientation.components.flipped
    parts = np.flatnonzero(flipped)[:INDEX_LIST_LIMIT]
    return ",".join(f"{part}:{flipped[part]}" for part in parts.tolist())


def _fix(orientation: Orientation) -> Fix:
    return Fix(
        faces_flipped=int(np.count_nonzero(orientation.flipped)),
        components_changed=int(np.count_nonzero(orientation.components.flipped)),
        flipped_face_indices=first_indices(orientation.flipped),
        components=[
            ComponentFix(
                component=part.index,
                faces=part.faces,
                closed=part.closed,
                orientable=part.orientable,
                method=part.method,
                faces_flipped=part.flipped,
                volume=part.volume,
            )
            for part in orientation.components[:INDEX_LIST_LIMIT]
        ],
    )


def file_normal_agreement(analysis: MeshAnalysis) -> FileNormals | None:
    """How well the normals stored in the file agree with ours, or ``None`` without any.

    Like with like: see :mod:`mesh_normal.stored_normals`.
    """
    return stored_normal_agreement(analysis.mesh, analysis.geometry, analysis.faces)
