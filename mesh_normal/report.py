"""What we find in a mesh file: one analysis, one typed report (the API, the page, the CLI).

:func:`analyse` runs the core on a :class:`~mesh_normal.files.LoadedMesh` once and keeps the arrays
(the page draws them); :func:`build_report` turns that into a :class:`MeshReport`, whose JSON
(``report.model_dump_json()``) is what ``POST /api/mesh`` answers. :func:`mesh_report` does both
from a file, and is the library's ``mn.analyse``.

Every number of the report is finite or ``None``: a measure that overflows the double range (an
area or a volume) becomes ``None`` when the model is built, and the models write any non-finite
float as ``null``, so their JSON never holds ``NaN`` or ``Infinity``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Annotated, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from mesh_normal.diagnosis import Problem, problems
from mesh_normal.faces import FaceNormals, face_normals
from mesh_normal.files import LoadedMesh, read_mesh
from mesh_normal.orientation import MeshTopology, Method, Orientation, Verdict, orient
from mesh_normal.vertices import corner_normals, vertex_normals

__all__ = [
    "AGREEMENT_DEGREES",
    "COMPARISON_CREASE",
    "INDEX_LIST_LIMIT",
    "Bounds",
    "ComponentFix",
    "FileInfo",
    "FileNormals",
    "Fix",
    "MeshAnalysis",
    "MeshReport",
    "Problem",
    "analyse",
    "build_report",
    "mesh_report",
]

#: How many face indices (or components) a list in the report holds at most; counts are full.
INDEX_LIST_LIMIT = 100
#: File normals within this angle of ours count as agreeing.
AGREEMENT_DEGREES = 1.0
#: The crease angle of the corner normals we compare an OBJ's per-corner normals with.
COMPARISON_CREASE = 30.0

MeshFormat = Literal["stl", "obj", "ply", "off", "glb", "gltf"]
StoredKind = Literal["face", "corner", "vertex"]
#: A path, the file's bytes, or a binary file object open for reading.
MeshSource = str | os.PathLike[str] | bytes | IO[bytes]


def finite(value: object) -> object:
    """``value`` unchanged, or ``None`` when it is a float that is not finite."""
    if isinstance(value, float | np.floating) and not math.isfinite(value):
        return None
    return value


#: A measure that may overflow the double range: ``None`` (JSON ``null``) when it does.
Measure = Annotated[float | None, BeforeValidator(finite)]
#: A float that is always finite (a coordinate of a checked mesh, a fixed angle).
Finite = Annotated[float, Field(allow_inf_nan=False)]


class _Model(BaseModel):
    # Frozen: the diagnosis and the page read one report and never change it. Any float that
    # is not finite is written as null, so no model's JSON can hold NaN or Infinity.
    model_config = ConfigDict(frozen=True, extra="forbid", ser_json_inf_nan="null")


class FileInfo(_Model):
    """The uploaded file."""

    name: str | None = Field(description="The file's name as uploaded, or null without one.")
    format: MeshFormat = Field(description="The format read from the bytes (else the name).")
    bytes: int = Field(
        ge=0, description="The file's size in bytes (0 for a mesh handed over already read)."
    )


class Bounds(_Model):
    """The axis-aligned box around every vertex, used or not."""

    min: list[Finite] = Field(min_length=3, max_length=3, description="Smallest x, y and z.")
    max: list[Finite] = Field(min_length=3, max_length=3, description="Largest x, y and z.")


class ComponentFix(_Model):
    """One connected part (faces joined by edges) and what orient() does to it."""

    component: int = Field(ge=0, description="The part's number, 0-based.")
    faces: int = Field(ge=0, description="How many faces the part has.")
    closed: bool = Field(description="Whether every edge of the part joins exactly two faces.")
    orientable: bool = Field(description="Whether the part can be wound consistently at all.")
    method: Method = Field(
        description="How its outside was chosen: by the sign of its volume (closed parts), by "
        "a heuristic (open parts), or not at all (one-sided or flat parts, closed parts that "
        "enclose no volume)."
    )
    faces_flipped: int = Field(ge=0, description="How many of its faces orient() reverses.")
    volume: Measure = Field(
        description="The part's signed volume after the fix; null when it is open, one-sided "
        "or beyond the double range."
    )


class Fix(_Model):
    """What orient() (the fixed mesh download) changes: consistent, outward winding."""

    faces_flipped: int = Field(ge=0, description="How many faces the fix reverses.")
    components_changed: int = Field(ge=0, description="How many parts have a reversed face.")
    flipped_face_indices: list[int] = Field(
        description=f"The first {INDEX_LIST_LIMIT} reversed faces, 0-based, in file order."
    )
    components: list[ComponentFix] = Field(
        description=f"The first {INDEX_LIST_LIMIT} parts, in the order of their first face."
    )


class FileNormals(_Model):
    """How the normals stored in the file agree with the ones computed from the winding."""

    kind: StoredKind = Field(description="Which normals the file stores: face, corner or vertex.")
    compared_with: str = Field(description="Which of our normals they are compared with.")
    stored: int = Field(ge=0, description="How many normals the file stores.")
    compared: int = Field(
        ge=0, description="How many were compared: usable in the file and defined by us."
    )
    unusable: int = Field(ge=0, description="How many stored normals are zero or not finite.")
    agreeing: int = Field(ge=0, description="How many are within agreement_degrees of ours.")
    opposite: int = Field(ge=0, description="How many differ from ours by more than 90 degrees.")
    agreement_degrees: Finite = Field(description="The angle within which normals agree.")
    median_angle_degrees: Measure = Field(
        description="The median angle between theirs and ours; null when none was compared."
    )
    max_angle_degrees: Measure = Field(
        description="The largest angle between theirs and ours; null when none was compared."
    )


class MeshReport(_Model):
    """The report on one mesh file: counts, checks, the fix and the diagnosis in plain words."""

    file: FileInfo = Field(description="The file: name, format and size.")
    vertices: int = Field(ge=0, description="Vertices, in file order (none merged or dropped).")
    faces: int = Field(ge=0, description="Triangles, after polygons are fan-triangulated.")
    source_faces: int = Field(ge=0, description="Faces (polygons) as the file stores them.")
    unused_vertices: int = Field(ge=0, description="Vertices that no face uses.")
    area: Measure = Field(description="Total surface area; null beyond the double range.")
    volume: Measure = Field(
        description="Signed volume (positive when the normals point outward); null unless "
        "the mesh is closed and consistently wound, or beyond the double range."
    )
    watertight: bool = Field(description="Whether every edge joins exactly two faces.")
    winding_consistent: bool = Field(
        description="Whether the two faces of every shared edge run it in opposite directions."
    )
    orientation: Verdict = Field(
        description="The winding as the file has it: outward (the fix flips no face), inward "
        "(it flips every face), mixed (it flips some: inconsistent winding, or parts that "
        "disagree) or undetermined (no part has a decidable outside: no faces, or only flat "
        "or one-sided parts)."
    )
    degenerate_faces: int = Field(ge=0, description="Faces without area (and so no normal).")
    degenerate_face_indices: list[int] = Field(
        description=f"The first {INDEX_LIST_LIMIT} faces without area, 0-based, in file order."
    )
    repeated_index_faces: int = Field(
        ge=0, description="Faces that name a vertex twice (a kind of degenerate face)."
    )
    boundary_edges: int = Field(ge=0, description="Edges that belong to one face only.")
    nonmanifold_edges: int = Field(ge=0, description="Edges shared by three or more faces.")
    components: int = Field(ge=0, description="Connected parts (faces joined by edges).")
    nonorientable_components: int = Field(
        ge=0,
        description="Parts that cannot be wound consistently (one-sided, like a Moebius strip).",
    )
    bounds: Bounds | None = Field(description="The box around the vertices; null without any.")
    fix: Fix = Field(description="What the fixed mesh changes.")
    file_normals: FileNormals | None = Field(
        description="How the normals stored in the file agree with ours; null without any."
    )
    notes: list[str] = Field(description="What the reader noticed about the file, in words.")
    problems: list[Problem] = Field(description="Each problem found, the most serious first.")


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
    """Run every check of the core on ``mesh`` (read from a file of ``size`` bytes).

    Returns the arrays (face normals, topology, orientation) that :func:`build_report` sums up
    and the page draws; for the report alone use :func:`mesh_report`.
    """
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


def mesh_report(source: LoadedMesh | MeshSource, filename: str | None = None) -> MeshReport:
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
        return build_report(analyse(source, filename, 0))
    data, name = _file_bytes(source, filename)
    return build_report(analyse(read_mesh(data, name), name, len(data)))


def _file_bytes(source: MeshSource, filename: str | None) -> tuple[bytes, str | None]:
    """The bytes of a path, bytes or binary file, and the name to give them."""
    if isinstance(source, bytes | bytearray | memoryview):
        return bytes(source), filename
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        return path.read_bytes(), filename or path.name
    data = source.read()
    if not isinstance(data, bytes):  # a file opened in text mode
        raise TypeError(f"read the mesh file in binary mode ('rb'), not {type(data).__name__}")
    attribute = getattr(source, "name", None)
    name = Path(attribute).name if isinstance(attribute, str) else None
    return data, filename or name


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
        notes=list(mesh.notes),
        problems=[],  # the diagnosis reads the rest of the report
    )
    return report.model_copy(update={"problems": problems(report)})


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


def _stored_normals(
    analysis: MeshAnalysis,
) -> tuple[StoredKind, str, NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]] | None:
    """The file's normals beside ours: kind, our kind in words, theirs, ours, ours missing."""
    mesh = analysis.mesh
    if mesh.file_face_normals is not None:
        faces = analysis.faces
        return "face", "our face normals", mesh.file_face_normals, faces.normals, faces.degenerate
    if mesh.file_corner_normals is not None:
        corners = corner_normals(mesh.vertices, mesh.faces, COMPARISON_CREASE, "angle")
        return (
            "corner",
            f"our corner normals (crease angle {COMPARISON_CREASE:g}°)",
            mesh.file_corner_normals.reshape(-1, 3),
            corners.normals.reshape(-1, 3),
            corners.missing.ravel(),
        )
    if mesh.file_vertex_normals is not None:
        smooth = vertex_normals(mesh.vertices, mesh.faces, "angle")
        return (
            "vertex",
            "our angle-weighted vertex normals",
            mesh.file_vertex_normals,
            smooth.normals,
            smooth.missing,
        )
    return None


def file_normal_agreement(analysis: MeshAnalysis) -> FileNormals | None:
    """How well the normals stored in the file agree with ours, or ``None`` without any."""
    stored = _stored_normals(analysis)
    if stored is None:
        return None
    kind, reference, theirs, ours, missing = stored
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
    return FileNormals(
        kind=kind,
        compared_with=reference,
        stored=len(theirs),
        compared=int(np.count_nonzero(both)),
        unusable=int(np.count_nonzero(~usable)),
        agreeing=int(np.count_nonzero(cosines >= agree)),
        opposite=int(np.count_nonzero(cosines < 0)),
        agreement_degrees=AGREEMENT_DEGREES,
        median_angle_degrees=_angle(theirs, ours, rows, cosines, "median"),
        max_angle_degrees=_angle(theirs, ours, rows, cosines, "max"),
    )


def _angle(
    theirs: NDArray[np.float64],
    ours: NDArray[np.float64],
    rows: NDArray[np.intp],
    cosines: NDArray[np.float64],
    which: Literal["median", "max"],
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
