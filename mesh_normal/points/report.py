"""The point-cloud report as frozen dataclasses (what ``POST /api/points`` answers), apart from
the analysis that fills them (:mod:`mesh_normal.points.analysis`), as the mesh report is: this
module imports no NumPy and no kernels, so that the web app declares its routes without them."""

from __future__ import annotations

from dataclasses import dataclass

from mesh_normal.choices import OrientMode, SourceKind
from mesh_normal.record import INDEX_LIST_LIMIT, Finite, Measure, Record, described
from mesh_normal.tolerances import POINT_FAR_FROM_FLAT

#: Stored normals within this angle of ours, as lines (either side), count as agreeing.
POINT_AGREEMENT_DEGREES = 10.0
#: Under this fraction of compared points on our side, the stored normals read as flipped.
FLIPPED_FRACTION = 0.5
#: The diagnosis when nothing was found: its one sentence.
ALL_CLEAR = "Every point has a normal, oriented as asked."


@dataclass(frozen=True, slots=True)
class PointFileInfo(Record):
    """The file the cloud was read from."""

    name: str | None = described(description="The file's name as uploaded, or null without one.")
    format: str = described(
        description="The format read: ply, xyz, pts, pcd, las, laz or a mesh's; memory for a "
        "cloud handed over in memory (an array, another library's cloud)."
    )
    source_kind: SourceKind = described(description='"points", or "mesh vertices" for a mesh file.')
    bytes: int = described(
        ge=0, description="The file's size in bytes (0 for a cloud handed over)."
    )
    file_points: int = described(
        ge=0, description="Points the file holds, those left out included."
    )
    left_out: int = described(ge=0, description="Points left out (PCD points marked NaN).")
    has_normals: bool = described(description="Whether the file stores normals.")
    has_colors: bool = described(description="Whether the file stores colours.")
    viewpoint: list[Finite] | None = described(
        description="A PCD VIEWPOINT's origin (x, y, z); null for other formats."
    )
    notes: list[str] = described(description="What the reader did not use or left out, in words.")


@dataclass(frozen=True, slots=True)
class PointBounds(Record):
    """The axis-aligned box around the finite points."""

    min: list[Finite] = described(min_length=3, max_length=3, description="Smallest x, y and z.")
    max: list[Finite] = described(min_length=3, max_length=3, description="Largest x, y and z.")


@dataclass(frozen=True, slots=True)
class Spacing(Record):
    """The distance from each point to its nearest other point (finite points only)."""

    min: Measure = described(description="The smallest; 0 when two points coincide.")
    median: Measure = described(description="The median: the cloud's typical spacing.")
    max: Measure = described(description="The largest: the most isolated point's.")
    coincident: int = described(
        ge=0, description="Points that have another at exactly their place."
    )


@dataclass(frozen=True, slots=True)
class Neighbourhood(Record):
    """The neighbourhood each normal was fitted to."""

    k: int | None = described(
        description="At most this many points, the point itself included; null with a null "
        "radius: each point's own scale, chosen from the data (the default)."
    )
    radius: Measure = described(description="Only points within this distance; null: any distance.")


@dataclass(frozen=True, slots=True)
class StatusCounts(Record):
    """How many points got each status (see PointStatus)."""

    ok: int = described(ge=0, description="A unit normal, oriented as asked.")
    not_finite: int = described(ge=0, description="A coordinate is NaN or infinite.")
    too_few_neighbours: int = described(ge=0, description="Under 3 points in the neighbourhood.")
    duplicates: int = described(ge=0, description="The neighbourhood's points coincide.")
    collinear: int = described(ge=0, description="The neighbourhood's points lie on a line.")
    ambiguous: int = described(ge=0, description="Two directions are equally flat.")
    unoriented: int = described(ge=0, description="A unit normal whose side was not decided.")
    sharp: int = described(
        ge=0, description="A unit normal near a sharp edge: the side's it lies on, not a blend."
    )


@dataclass(frozen=True, slots=True)
class PartOrientation(Record):
    """One connected part of the neighbour graph (or the whole cloud for per-point modes)."""

    points: int = described(ge=0, description="Its points that have a normal.")
    flipped: int = described(ge=0, description="Those whose normal the orientation turned.")
    unoriented: int = described(ge=0, description="Those whose side could not be decided.")
    reason: str = described(description="Why some were left unoriented; empty when none were.")
    seed: int = described(ge=-1, description="The point (0-based) that decided its side, or -1.")


@dataclass(frozen=True, slots=True)
class Orientation(Record):
    """How the normals' sides were chosen."""

    mode: OrientMode = described(description="mst, riemannian, viewpoint, direction, file or none.")
    viewpoint: list[Finite] | None = described(description="The sensor position used, or null.")
    viewpoint_from_file: bool = described(description="Whether it is the PCD file's VIEWPOINT.")
    direction: list[Finite] | None = described(description="The direction used, or null.")
    flipped: int = described(ge=0, description="Normals turned, in all parts.")
    unoriented: int = described(ge=0, description="Normals whose side could not be decided.")
    part_count: int = described(ge=0, description="How many parts were oriented on their own.")
    parts: list[PartOrientation] = described(
        description=f"The first {INDEX_LIST_LIMIT} parts, largest first."
    )


@dataclass(frozen=True, slots=True)
class StoredNormals(Record):
    """How the normals stored in the file agree with the estimated ones."""

    stored: int = described(ge=0, description="Points with a stored normal row.")
    unusable: int = described(ge=0, description="Stored rows that are zero or not finite.")
    compared: int = described(ge=0, description="Points with a usable stored normal and ours.")
    agreement_degrees: Finite = described(description="The angle within which lines agree.")
    agreeing: int = described(
        ge=0, description="Compared points whose lines agree within agreement_degrees."
    )
    median_angle_degrees: Measure = described(
        description="The median angle between the lines (either side); null if none compared."
    )
    max_angle_degrees: Measure = described(
        description="The largest angle between the lines; null when none was compared."
    )
    same_side_fraction: Measure = described(
        description="Of the compared points we oriented, the fraction whose stored normal is "
        "on our side (dot product positive); null when none."
    )


@dataclass(frozen=True, slots=True)
class PointReport(Record):
    """The report on one point cloud: the file, spacing, normals by status, orientation and
    the diagnosis in plain sentences."""

    file: PointFileInfo = described(description="The file: name, format, size and what it holds.")
    points: int = described(ge=0, description="Points kept, in file order.")
    bounds: PointBounds | None = described(description="The box around the finite points, or null.")
    spacing: Spacing | None = described(description="Nearest-neighbour distances; null under 2.")
    neighbourhood: Neighbourhood = described(description="The neighbourhood used: k and radius.")
    counts: StatusCounts = described(description="How many points got each status.")
    with_normal: int = described(ge=0, description="Points with a normal: ok, sharp or unoriented.")
    far_from_flat: int = described(
        ge=0,
        description=f"Points with a normal whose neighbourhood is far from flat (surface "
        f"variation over {POINT_FAR_FROM_FLAT:g}): a thin wall or two sheets within its reach, "
        "a sharp edge or heavy noise, where the normal and its side are unsure.",
    )
    orientation: Orientation = described(description="How the sides were chosen, part by part.")
    stored_normals: StoredNormals | None = described(
        description="How the file's normals agree with ours; null when it stores none."
    )
    diagnosis: list[str] = described(description="What was found, in plain sentences.")

    def _repr_html_(self) -> str:
        """What a notebook shows: the diagnosis, the key figures and the findings."""
        from mesh_normal.notebook.html import point_report_html

        return point_report_html(self.to_dict())
