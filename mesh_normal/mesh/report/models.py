"""The report on a mesh as frozen dataclasses: what ``POST /api/mesh`` answers, ``mn.analyse``
returns.

:class:`MeshReport` holds counts, checks, the fix that :func:`~mesh_normal.orient` makes and the
diagnosis (:class:`Problem` items, written by :mod:`mesh_normal.mesh.report.diagnosis`);
:mod:`mesh_normal.mesh.report.analysis` builds it from the arrays. ``report.to_json()`` is the
JSON of ``POST /api/mesh``, ``report.to_dict()`` the same as dicts and lists.

Every number of the report is finite or ``None``: a measure that overflows the double range (an
area or a volume) becomes ``None`` when the report is built, so its JSON never holds ``NaN`` or
``Infinity``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

# The reports import no NumPy and no kernels (the app declares its routes with them at start).
from mesh_normal.choices import MeshFormat as MeshFormat  # the files' formats, named here too
from mesh_normal.choices import Method, ReportFormat, Verdict, Weighting
from mesh_normal.record import INDEX_LIST_LIMIT, Finite, Measure, Record, described
from mesh_normal.tolerances import WELD_LIMIT

#: File normals within this angle of ours count as agreeing.
AGREEMENT_DEGREES = 1.0
#: The first crease angle of the corner normals we compare an OBJ's per-corner normals with
#: (others are tried too: see :mod:`mesh_normal.mesh.report.stored_normals`).
COMPARISON_CREASE = 30.0

StoredKind = Literal["face", "corner", "vertex"]


Severity = Literal["error", "warning", "info"]
ProblemCode = Literal[
    "winding",
    "inward",
    "mixed",
    "nonmanifold",
    "nonorientable",
    "degenerate",
    "open",
    "file_normals",
    "unused_vertices",
    "components",
    "cavities",
    "touching",
    "overflow",
    "underflow",
]


@dataclass(frozen=True, slots=True)
class Problem(Record):
    """One problem of a mesh in plain words: what it is, why it matters, what to do."""

    code: ProblemCode = described(description="A stable name for the problem, for scripts.")
    severity: Severity = described(
        description="error: normals or volume are wrong as the file stands; warning: some "
        "results are missing or need care; info: worth knowing."
    )
    title: str = described(description="The problem in one line.")
    detail: str = described(description="What it means and why it matters.")
    action: str = described(description="What to do about it.")
    python: str | None = described(
        description="The same fix or check in Python with mesh_normal, or null."
    )


@dataclass(frozen=True, slots=True)
class FileInfo(Record):
    """The uploaded file."""

    name: str | None = described(description="The file's name as uploaded, or null without one.")
    format: ReportFormat = described(
        description="The format read from the bytes (else the name); memory for a mesh handed "
        "over in memory (arrays, or another library's mesh)."
    )
    bytes: int = described(
        ge=0, description="The file's size in bytes (0 for a mesh handed over already read)."
    )


@dataclass(frozen=True, slots=True)
class Bounds(Record):
    """The axis-aligned box around every vertex, used or not."""

    min: list[Finite] = described(min_length=3, max_length=3, description="Smallest x, y and z.")
    max: list[Finite] = described(min_length=3, max_length=3, description="Largest x, y and z.")


@dataclass(frozen=True, slots=True)
class ComponentFix(Record):
    """One connected part (faces joined by edges) and what orient() does to it."""

    component: int = described(ge=0, description="The part's number, 0-based.")
    faces: int = described(ge=0, description="How many faces the part has.")
    closed: bool = described(description="Whether every edge of the part joins exactly two faces.")
    orientable: bool = described(description="Whether the part can be wound consistently at all.")
    method: Method = described(
        description="How its outside was chosen: by the sign of its volume (closed parts), by "
        "visibility, the side from which rays escape the whole mesh (open parts), or not at "
        "all (one-sided parts, closed parts that enclose no volume or touch another, open "
        "parts that see the world alike from both sides). A closed part's volume is read "
        "with its depth: out at an even depth, in (a cavity) at an odd one."
    )
    faces_flipped: int = described(ge=0, description="How many of its faces orient() reverses.")
    volume: Measure = described(
        description="The part's signed volume after the fix, negative for a cavity (so that "
        "the volumes sum to the material's); null when it is open, one-sided or beyond the "
        "double range."
    )
    depth: int | None = described(
        description="How many other closed parts it lies inside: even, its faces point out; "
        "odd, it is a cavity and its faces point into it, away from the material. Null when "
        "it is not a closed part with a clear volume, or when that is not known (it touches "
        "another part, or there were too many to check)."
    )
    inside: int | None = described(
        description="The innermost closed part it lies inside (the one whose cavity or body "
        "holds it), or null."
    )
    touches: int | None = described(
        description="A closed part it touches, so that whether it is a cavity is not decided "
        "and its faces are left as they are; null otherwise."
    )


@dataclass(frozen=True, slots=True)
class Fix(Record):
    """What orient() (the fixed mesh download) changes: consistent, outward winding."""

    faces_flipped: int = described(ge=0, description="How many faces the fix reverses.")
    components_changed: int = described(ge=0, description="How many parts have a reversed face.")
    flipped_face_indices: list[int] = described(
        description=f"The first {INDEX_LIST_LIMIT} reversed faces, 0-based, in file order."
    )
    components: list[ComponentFix] = described(
        description=f"The first {INDEX_LIST_LIMIT} parts, in the order of their first face."
    )


@dataclass(frozen=True, slots=True)
class FileNormals(Record):
    """How the normals stored in the file agree with the ones computed from the winding."""

    kind: StoredKind = described(
        description="Which normals the file stores: face, corner or vertex."
    )
    compared_with: str = described(
        description="Which of our normals they are compared with: the best match of those tried."
    )
    weighting: Weighting | None = described(
        description="The weighting of our vertex or corner normals that matched best "
        "(angle, area, uniform or max); null for face normals.",
    )
    crease_angle_degrees: Finite | None = described(
        description="The crease angle of our corner normals that matched best; null unless "
        "the file stores corner normals.",
    )
    stored: int = described(ge=0, description="How many normals the file stores.")
    compared: int = described(
        ge=0, description="How many were compared: usable in the file and defined by us."
    )
    unusable: int = described(ge=0, description="How many stored normals are zero or not finite.")
    agreeing: int = described(ge=0, description="How many are within agreement_degrees of ours.")
    opposite: int = described(
        ge=0, description="How many differ from ours by more than 90 degrees."
    )
    agreement_degrees: Finite = described(description="The angle within which normals agree.")
    median_angle_degrees: Measure = described(
        description="The median angle between theirs and ours; null when none was compared."
    )
    max_angle_degrees: Measure = described(
        description="The largest angle between theirs and ours; null when none was compared."
    )


@dataclass(frozen=True, slots=True)
class ObjectReport(Record):
    """One object of the file and what the fix does to it: an OBJ ``o`` or ``g`` group, an
    ASCII STL ``solid``, a glTF primitive as a node places it, or a 3MF build item."""

    name: str = described(description="The object's name as the file gives it.")
    faces: int = described(ge=0, description="How many triangles it has.")
    area: Measure = described(description="Its surface area; null beyond the double range.")
    degenerate_faces: int = described(ge=0, description="Its faces without area.")
    components: int = described(
        ge=0, description="How many connected parts its faces belong to (shared parts count)."
    )
    closed: bool = described(
        description="Whether it is closed on its own: every edge of its faces (by position) "
        "joins exactly two of its faces."
    )
    orientation: Verdict = described(
        description="Its winding as the file has it: outward (the fix flips none of its "
        "faces), inward (it flips all its faces whose part has a decidable outside), mixed "
        "(some) or undetermined (none of its parts has a verdict)."
    )
    faces_flipped: int = described(ge=0, description="How many of its faces the fix reverses.")


@dataclass(frozen=True, slots=True)
class Weld(Record):
    """The weld tolerance the topology used: vertices this close count as one point."""

    tolerance: Finite = described(
        ge=0,
        le=WELD_LIMIT,
        description="The tolerance asked for, as a fraction of the bounding-box diagonal "
        f"(0 to {WELD_LIMIT:g}).",
    )
    distance: Measure = described(
        description="What it meant for this mesh: the tolerance times the diagonal, in the "
        "file's units; null beyond the double range."
    )
    joined_vertices: int = described(
        ge=0,
        description="How many vertices it joined beyond exact equality: the points with "
        "identical coordinates, less the points after the weld.",
    )


@dataclass(frozen=True, slots=True)
class MeshReport(Record):
    """The report on one mesh file: counts, checks, the fix and the diagnosis in plain words."""

    file: FileInfo = described(description="The file: name, format and size.")
    vertices: int = described(ge=0, description="Vertices, in file order (none merged or dropped).")
    faces: int = described(ge=0, description="Triangles, after polygons are fan-triangulated.")
    source_faces: int = described(ge=0, description="Faces (polygons) as the file stores them.")
    unused_vertices: int = described(ge=0, description="Vertices that no face uses.")
    area: Measure = described(description="Total surface area; null beyond the double range.")
    volume: Measure = described(
        description="Signed volume (positive when the normals point outward); null unless "
        "the mesh is closed and consistently wound, or beyond the double range."
    )
    watertight: bool = described(description="Whether every edge joins exactly two faces.")
    winding_consistent: bool = described(
        description="Whether the two faces of every shared edge run it in opposite directions."
    )
    orientation: Verdict = described(
        description="The winding as the file has it: outward (the fix flips no face), inward "
        "(it flips every face), mixed (it flips some: inconsistent winding, or parts that "
        "disagree) or undetermined (no part has a decidable outside: no faces, or only flat "
        "or one-sided parts)."
    )
    degenerate_faces: int = described(ge=0, description="Faces without area (and so no normal).")
    degenerate_face_indices: list[int] = described(
        description=f"The first {INDEX_LIST_LIMIT} faces without area, 0-based, in file order."
    )
    repeated_index_faces: int = described(
        ge=0, description="Faces that name a vertex twice (a kind of degenerate face)."
    )
    boundary_edges: int = described(ge=0, description="Edges that belong to one face only.")
    nonmanifold_edges: int = described(ge=0, description="Edges shared by three or more faces.")
    components: int = described(ge=0, description="Connected parts (faces joined by edges).")
    nonorientable_components: int = described(
        ge=0,
        description="Parts that cannot be wound consistently (one-sided, like a Moebius strip).",
    )
    bounds: Bounds | None = described(description="The box around the vertices; null without any.")
    fix: Fix = described(description="What the fixed mesh changes.")
    file_normals: FileNormals | None = described(
        description="How the normals stored in the file agree with ours; null without any."
    )
    object_count: int = described(
        ge=0,
        description="How many objects the file has (OBJ o and g groups, ASCII STL solids, "
        "glTF primitives placed by nodes, 3MF build items); 0 for formats without them.",
    )
    objects: list[ObjectReport] = described(
        description=f"The first {INDEX_LIST_LIMIT} objects, in the order of their first face; "
        "empty when the file has none."
    )
    weld: Weld | None = described(
        description="The weld tolerance the edges, parts, winding and fix were judged with; "
        "null when off (the default: only identical coordinates are one point).",
    )
    notes: list[str] = described(description="What the reader noticed about the file, in words.")
    problems: list[Problem] = described(description="Each problem found, the most serious first.")

    def _repr_html_(self) -> str:
        """What a notebook shows: the diagnosis, the key figures and the problems."""
        from mesh_normal.notebook.html import mesh_report_html

        return mesh_report_html(self.to_dict())
