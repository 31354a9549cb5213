"""One mesh, analysed once: the arrays behind the report, and the report built from them.

:func:`analyse_mesh` runs the core on a :class:`~mesh_normal.files.LoadedMesh` once and keeps the
arrays (the page draws them); :func:`build_report` sums them up as a

:class:`~mesh_normal.mesh.report.models.MeshReport`; :func:`analyse` does both from a file, and is
the library's ``mn.analyse``.
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files import LoadedMesh, read_mesh
from mesh_normal.files.read import MeshSource, source_bytes
from mesh_normal.mesh.bounds import column_bounds
from mesh_normal.mesh.checks import MESH_FORMS, HeldMesh, checked_mesh
from mesh_normal.mesh.faces import FaceGeometry, FaceNormals, face_geometry, geometry_areas
from mesh_normal.mesh.orientation import HeadStart, Orientation, oriented
from mesh_normal.mesh.report.diagnosis import problems
from mesh_normal.mesh.report.models import (
    Bounds,
    ComponentFix,
    FileInfo,
    FileNormals,
    Fix,
    MeshReport,
    ObjectReport,
    Weld,
)
from mesh_normal.mesh.report.objects import object_reports
from mesh_normal.mesh.report.stored_normals import stored_normal_agreement
from mesh_normal.mesh.topology import (
    MeshTopology,
    by_position,
    same_points,
    structure,
    weld_distance,
)
from mesh_normal.record import INDEX_LIST_LIMIT
from mesh_normal.tolerances import WELD_LIMIT
from mesh_normal.types import FloatArray, IndexArray


@dataclass(frozen=True, slots=True)
class MeshAnalysis:
    """Everything the report says about one mesh, with the arrays behind it."""

    mesh: LoadedMesh
    name: str | None
    size: int
    geometry: FaceGeometry
    topology: MeshTopology
    orientation: Orientation
    unused_vertices: int
    weld: Weld | None
    points: IndexArray  # (m, 3): the faces as the topology saw them, each vertex by its point
    file_normals: FileNormals | None  # the normals the file stores, compared with ours
    _areas: list[FloatArray] = field(default_factory=list, repr=False)

    @property
    def areas(self) -> FloatArray:
        """(m,) float64 face areas, taken on first use."""
        if not self._areas:
            self._areas.append(geometry_areas(self.geometry))
        return self._areas[0]

    @property
    def faces(self) -> FaceNormals:
        """The unit normals (taken on first use: a report needs them only to compare a file's
        own face normals, and does not hold 24 bytes a face otherwise), areas and flags."""
        return FaceNormals(self.geometry.normals, self.areas, self.geometry.degenerate)


def checked_weld(weld: object) -> float | None:
    """``weld`` as a float, or ``None`` (off); refuses anything but a number 0 to WELD_LIMIT.

    Raises
    ------
    ValueError
        When ``weld`` is not a finite number from 0 to WELD_LIMIT (a fraction of the
        bounding-box diagonal).
    """
    if weld is None:
        return None
    number = float(weld) if isinstance(weld, numbers.Real) and not isinstance(weld, bool) else None
    if number is None or not (math.isfinite(number) and 0 <= number <= WELD_LIMIT):
        raise ValueError(
            f"weld must be a number from 0 to {WELD_LIMIT:g} (a fraction of the bounding-box "
            f"diagonal), not {weld!r}."
        )
    return number


def weld_summary(vertices: FloatArray, weld: float | None) -> Weld | None:
    """What a weld tolerance (checked) meant for these vertices, or ``None`` when it is off."""
    return None if weld is None else _welded(vertices, weld)[0]


def _welded(vertices: FloatArray, weld: float) -> tuple[Weld, IndexArray | None]:
    """The weld's summary and the map of :func:`~mesh_normal.mesh.topology.same_points`."""
    exact, welded = same_points(vertices), same_points(vertices, weld)
    summary = Weld(
        tolerance=weld,
        distance=weld_distance(vertices, weld),
        joined_vertices=_point_count(exact, len(vertices)) - _point_count(welded, len(vertices)),
    )
    return summary, welded


def _point_count(point: IndexArray | None, count: int) -> int:
    """How many points a map of :func:`~mesh_normal.mesh.topology.same_points` leaves."""
    return count if point is None else int(np.count_nonzero(point == np.arange(count)))


def analyse_mesh(
    mesh: LoadedMesh, name: str | None = None, size: int = 0, *, weld: float | None = None
) -> MeshAnalysis:
    """Run every check of the core on ``mesh`` (read from a file of ``size`` bytes).

    ``weld`` (see :func:`analyse`) also joins vertices closer than that fraction of the
    bounding-box diagonal. Returns the arrays (face normals, topology, orientation) that
    :func:`build_report` sums up and the page draws; for the report alone use :func:`analyse`.
    """
    weld = checked_weld(weld)
    # One pass: the reader checked the arrays, and the cross products are taken once here for
    # the face normals, the orientation's volumes and the file-normal comparison alike.
    checked = mesh.checked()
    if weld is None:
        summary, points = None, by_position(checked)
    else:
        summary, point = _welded(mesh.vertices, weld)
        points = checked.faces if point is None else point[checked.faces]
    # The edges first: their sort is the largest working set, and the products are not
    # held yet while it runs (peak memory a face, not the sum of the two).
    ahead = HeadStart(checked, points)  # an open mesh's twins and rays, while this runs
    try:
        found = structure(points, len(checked.vertices), ahead.start)
        geometry = face_geometry(checked)
        orientation = oriented(geometry, points, found, ahead)  # the vertices matched once
    finally:
        ahead.finish()
    # The file's own normals against ours of their kind (mesh_normal.mesh.report.stored_normals).
    file_normals = stored_normal_agreement(mesh, geometry)
    used = np.zeros(len(mesh.vertices), dtype=bool)
    used[mesh.faces.ravel()] = True
    return MeshAnalysis(
        mesh=mesh,
        name=name,
        size=size,
        geometry=geometry,
        topology=orientation.topology,
        orientation=orientation,
        unused_vertices=int(len(used) - np.count_nonzero(used)),
        weld=summary,
        points=points,
        file_normals=file_normals,
    )


def analyse(
    source: LoadedMesh | MeshSource | HeldMesh,
    filename: str | None = None,
    *,
    weld: float | None = None,
) -> MeshReport:
    """The report on a mesh: ``mn.analyse(path)``.

    ``source`` is a mesh already read (:class:`~mesh_normal.files.LoadedMesh`), a path, the
    file's bytes or a binary file object, or a mesh in memory as
    :func:`~mesh_normal.mesh.checks.checked_mesh` takes it (a ``(vertices, faces)`` tuple, a
    ``trimesh.Trimesh``, an Open3D ``TriangleMesh``, a PyVista ``PolyData`` of triangles; its
    report's format is ``"memory"``). ``filename`` names it in the report (by default the
    path's or the file object's name) and, for bytes without a recognisable header, gives the
    format by its extension.

    ``weld``, off by default, is a tolerance for files whose pieces miss each other by
    rounding: vertices closer than this fraction of the bounding-box diagonal (0 to
    ``WELD_LIMIT``, 0.01; 1e-6 covers float32 rounding) count as one point for the edges,
    parts, winding and fix, as ``orient(..., weld=)`` does; the vertices themselves are kept.
    The report's ``weld`` says what it meant for the mesh and how many vertices it joined.

    Returns
    -------
    MeshReport
        Counts, checks, the fix and the diagnosis, as ``POST /api/mesh`` answers them:
        ``report.to_json()`` is that JSON, ``report.problems`` the diagnosis.

    Raises
    ------
    MeshFileError
        When the file is not a mesh that can be read.
    OSError
        When the path cannot be read.
    TypeError
        When a file object gives text, not bytes, or ``source`` is none of the above.
    ValueError
        When ``weld`` is not a number from 0 to 0.01, or a mesh's arrays are not a mesh.
    """
    weld = checked_weld(weld)  # before reading: a bad option fails at once
    if isinstance(source, LoadedMesh):
        return build_report(analyse_mesh(source, filename, 0, weld=weld))
    if isinstance(source, str | os.PathLike):  # read as a path: a .gltf finds its .bin beside it
        path = Path(source)
        named = filename or path.name
        mesh = read_mesh(path, named)
        return build_report(analyse_mesh(mesh, named, path.stat().st_size, weld=weld))
    if isinstance(source, bytes | bytearray | memoryview) or hasattr(source, "read"):
        data, name = source_bytes(source, filename)  # type: ignore[arg-type]
        return build_report(analyse_mesh(read_mesh(data, name), name, len(data), weld=weld))
    try:
        checked = checked_mesh(source)
    except TypeError:
        raise TypeError(
            "analyse takes a path, the file's bytes, a binary file object or a mesh "
            f"({MESH_FORMS}), not {type(source).__name__}."
        ) from None
    held = LoadedMesh(checked.vertices, checked.faces, "memory", len(checked.faces))
    return build_report(analyse_mesh(held, filename, 0, weld=weld))


def build_report(analysis: MeshAnalysis) -> MeshReport:
    """The report: counts, checks, the fix that orient() would make, and the diagnosis."""
    mesh, topology, orientation = analysis.mesh, analysis.topology, analysis.orientation
    degenerate = analysis.geometry.degenerate
    report = MeshReport(
        file=FileInfo(name=analysis.name, format=mesh.format, bytes=analysis.size),
        vertices=len(mesh.vertices),
        faces=len(mesh.faces),
        source_faces=mesh.source_faces,
        unused_vertices=analysis.unused_vertices,
        area=float(np.sum(analysis.areas)),
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
        file_normals=analysis.file_normals,
        object_count=0 if mesh.group_names is None else len(mesh.group_names),
        objects=_objects(analysis),
        weld=analysis.weld,
        notes=list(mesh.notes),
        problems=[],  # the diagnosis reads the rest of the report
    )
    return replace(report, problems=problems(report))


def _objects(analysis: MeshAnalysis) -> list[ObjectReport]:
    groups, names = analysis.mesh.face_groups, analysis.mesh.group_names
    if groups is None or names is None:
        return []
    # The faces by position again (one hash sort): the topology keeps only its sums.
    points = analysis.points
    areas, degenerate = analysis.areas, analysis.geometry.degenerate
    return object_reports(groups, names, areas, degenerate, analysis.orientation, points)


def first_indices(mask: NDArray[np.bool_]) -> list[int]:
    """The first INDEX_LIST_LIMIT indices where ``mask`` is true, 0-based."""
    return [int(index) for index in np.flatnonzero(mask)[:INDEX_LIST_LIMIT]]


def _bounds(vertices: NDArray[np.float64]) -> Bounds | None:
    if not len(vertices):
        return None
    low, high = column_bounds(vertices)
    return Bounds(min=low.tolist(), max=high.tolist())


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
                depth=part.depth,
                inside=part.inside,
                touches=part.touches,
            )
            for part in orientation.components[:INDEX_LIST_LIMIT]
        ],
    )
