"""What we find in a mesh file: one analysis, one JSON payload (the API, the page, the CLI).

:func:`analyse` runs the core on a :class:`~mesh_normal.files.LoadedMesh` once and keeps the arrays
(the page draws them); :func:`report_payload` turns that into the report, every value a plain
JSON number, string, bool or ``null`` (never NaN or Infinity).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal.diagnosis import problems
from mesh_normal.exports import compute_normals
from mesh_normal.faces import FaceNormals, face_normals
from mesh_normal.files import LoadedMesh
from mesh_normal.orientation import MeshTopology, Orientation, orient

#: How many face indices (or components) a list in the report holds at most; counts are full.
INDEX_LIST_LIMIT = 100
#: File normals within this angle of ours count as agreeing.
AGREEMENT_DEGREES = 1.0
#: The crease angle of the corner normals we compare an OBJ's per-corner normals with.
COMPARISON_CREASE = 30.0


@dataclass(frozen=True, slots=True)
class MeshAnalysis:
    """Everything the report says about one mesh, with the arrays behind it."""

    mesh: LoadedMesh
    name: str | None
    size: int
    faces: FaceNormals
    topology: MeshTopology
    orientation: Orientation
    unused_vertices: int


def analyse(mesh: LoadedMesh, name: str | None = None, size: int = 0) -> MeshAnalysis:
    """Run every check of the core on ``mesh`` (read from a file of ``size`` bytes)."""
    faces = mesh.faces
    used = np.zeros(len(mesh.vertices), dtype=bool)
    used[faces.ravel()] = True
    orientation = orient(mesh.vertices, faces)
    return MeshAnalysis(
        mesh=mesh,
        name=name,
        size=size,
        faces=face_normals(mesh.vertices, faces),
        topology=orientation.topology,
        orientation=orientation,
        unused_vertices=int(len(used) - np.count_nonzero(used)),
    )


def finite(value: float) -> float | None:
    """``value`` as a JSON number, or ``None`` when it is not finite."""
    return float(value) if math.isfinite(value) else None


def first_indices(mask: NDArray[np.bool_]) -> list[int]:
    """The first INDEX_LIST_LIMIT indices where ``mask`` is true, 0-based."""
    return np.flatnonzero(mask)[:INDEX_LIST_LIMIT].tolist()


def report_payload(analysis: MeshAnalysis) -> dict[str, Any]:
    """The report: counts, checks, the fix that orient() would make, and the diagnosis."""
    mesh, topology, orientation = analysis.mesh, analysis.topology, analysis.orientation
    degenerate = analysis.faces.degenerate
    vertices = mesh.vertices
    report: dict[str, Any] = {
        "file": {"name": analysis.name, "format": mesh.format, "bytes": analysis.size},
        "vertices": len(vertices),
        "faces": len(mesh.faces),
        "source_faces": mesh.source_faces,
        "unused_vertices": analysis.unused_vertices,
        "area": finite(float(np.sum(analysis.faces.areas))),
        "volume": None if orientation.volume is None else finite(orientation.volume),
        "watertight": topology.watertight,
        "winding_consistent": topology.winding_consistent,
        "orientation": orientation.orientation,
        "degenerate_faces": int(np.count_nonzero(degenerate)),
        "degenerate_face_indices": first_indices(degenerate),
        # Faces with a repeated index are the ones outside every component.
        "repeated_index_faces": int(np.count_nonzero(topology.face_component < 0)),
        "boundary_edges": topology.boundary_edges,
        "nonmanifold_edges": topology.nonmanifold_edges,
        "components": topology.components,
        "nonorientable_components": int(np.count_nonzero(~orientation.components.orientable)),
        "bounds": _bounds(vertices),
        "fix": _fix(orientation),
        "file_normals": file_normal_agreement(analysis),
        "notes": list(mesh.notes),
    }
    report["problems"] = problems(report)
    return report


def _bounds(vertices: NDArray[np.float64]) -> dict[str, list[float]] | None:
    if not len(vertices):
        return None
    return {"min": vertices.min(axis=0).tolist(), "max": vertices.max(axis=0).tolist()}


def flips_by_component(orientation: Orientation) -> str:
    """``"component:faces"`` for the first components with flipped faces, e.g. ``"0:1,3:12"``."""
    flipped = orientation.components.flipped
    parts = np.flatnonzero(flipped)[:INDEX_LIST_LIMIT]
    return ",".join(f"{part}:{flipped[part]}" for part in parts.tolist())


def _fix(orientation: Orientation) -> dict[str, Any]:
    return {
        "faces_flipped": int(np.count_nonzero(orientation.flipped)),
        "components_changed": int(np.count_nonzero(orientation.components.flipped)),
        "flipped_face_indices": first_indices(orientation.flipped),
        "components": [
            {
                "component": part.index,
                "faces": part.faces,
                "closed": part.closed,
                "orientable": part.orientable,
                "method": part.method,
                "faces_flipped": part.flipped,
                "volume": None if part.volume is None else finite(part.volume),
            }
            for part in orientation.components[:INDEX_LIST_LIMIT]
        ],
    }


def file_normal_agreement(analysis: MeshAnalysis) -> dict[str, Any] | None:
    """How well the normals stored in the file agree with ours, or ``None`` without any."""
    mesh = analysis.mesh
    if mesh.file_face_normals is not None:
        kind, theirs = "face", mesh.file_face_normals
        ours, missing = analysis.faces.normals, analysis.faces.degenerate
        reference = "our face normals"
    elif mesh.file_corner_normals is not None:
        corners, corner_missing = compute_normals(mesh, "corner", "angle", COMPARISON_CREASE)
        kind, theirs = "corner", mesh.file_corner_normals.reshape(-1, 3)
        ours, missing = corners.reshape(-1, 3), corner_missing.ravel()
        reference = f"our corner normals (crease angle {COMPARISON_CREASE:g}°)"
    elif mesh.file_vertex_normals is not None:
        kind, theirs = "vertex", mesh.file_vertex_normals
        ours, missing = compute_normals(mesh, "vertex", "angle")
        reference = "our angle-weighted vertex normals"
    else:
        return None
    # A stored normal is usable when it is finite and not zero. Each is first divided by its
    # largest |component| (so its length can neither overflow nor underflow); ours are unit
    # vectors, so the cosine is a dot product over that length. Only the cosines are formed
    # (one pass); the angles of the median and the worst row come from atan2.
    with np.errstate(invalid="ignore", divide="ignore"):
        magnitude = np.abs(theirs)  # the max of three columns: axis=1 reductions are slow
        largest = np.maximum(np.maximum(magnitude[:, 0], magnitude[:, 1]), magnitude[:, 2])
        usable = np.isfinite(largest) & (largest > 0)
        theirs = theirs / np.where(usable, largest, 1.0)[:, None]
        lengths = np.sqrt(np.einsum("ij,ij->i", theirs, theirs))
        both = usable & ~missing
        rows = np.flatnonzero(both)
        cosines = (np.einsum("ij,ij->i", theirs, ours) / lengths)[rows]  # no row copies
    agree = math.cos(math.radians(AGREEMENT_DEGREES))
    compared = int(np.count_nonzero(both))
    return {
        "kind": kind,
        "compared_with": reference,
        "stored": len(theirs),
        "compared": compared,
        "unusable": int(np.count_nonzero(~usable)),
        "agreeing": int(np.count_nonzero(cosines >= agree)),
        "opposite": int(np.count_nonzero(cosines < 0)),
        "agreement_degrees": AGREEMENT_DEGREES,
        "median_angle_degrees": _angle(theirs, ours, rows, cosines, "median"),
        "max_angle_degrees": _angle(theirs, ours, rows, cosines, "max"),
    }


def _angle(
    theirs: NDArray[np.float64],
    ours: NDArray[np.float64],
    rows: NDArray[np.intp],
    cosines: NDArray[np.float64],
    which: str,
) -> float | None:
    """The median or largest angle in degrees, taken accurately (atan2) at that one row."""
    if not len(cosines):
        return None
    if which == "max":
        row = int(rows[np.argmin(cosines)])
    else:
        middle = len(cosines) // 2
        row = int(rows[np.argpartition(cosines, middle)[middle]])
    a, b = theirs[row], ours[row]
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b)))
