"""The point-cloud report's models (what ``POST /api/points`` answers), apart from the analysis
that fills them (:mod:`mesh_normal.points.report`, which also exports them): this module
imports no NumPy and no kernels, so that the web app declares its routes without them."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from mesh_normal.choices import OrientMode, SourceKind
from mesh_normal.report import INDEX_LIST_LIMIT, Finite, Measure
from mesh_normal.tolerances import POINT_FAR_FROM_FLAT

#: Stored normals within this angle of ours, as lines (either side), count as agreeing.
POINT_AGREEMENT_DEGREES = 10.0
#: Under this fraction of compared points on our side, the stored normals read as flipped.
FLIPPED_FRACTION = 0.5


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", ser_json_inf_nan="null")


class PointFileInfo(_Model):
    """The file the cloud was read from."""

    name: str | None = Field(description="The file's name as uploaded, or null without one.")
    format: str = Field(description="The format read: ply, xyz, pts, pcd, las, laz or a mesh's.")
    source_kind: SourceKind = Field(description='"points", or "mesh vertices" for a mesh file.')
    bytes: int = Field(ge=0, description="The file's size in bytes (0 for a cloud handed over).")
    file_points: int = Field(ge=0, description="Points the file holds, those left out included.")
    left_out: int = Field(ge=0, description="Points left out (PCD points marked NaN).")
    has_normals: bool = Field(description="Whether the file stores normals.")
    has_colors: bool = Field(description="Whether the file stores colours.")
    viewpoint: list[Finite] | None = Field(
        description="A PCD VIEWPOINT's origin (x, y, z); null for other formats."
    )
    notes: list[str] = Field(description="What the reader did not use or left out, in words.")


class PointBounds(_Model):
    """The axis-aligned box around the finite points."""

    min: list[Finite] = Field(min_length=3, max_length=3, description="Smallest x, y and z.")
    max: list[Finite] = Field(min_length=3, max_length=3, description="Largest x, y and z.")


class Spacing(_Model):
    """The distance from each point to its nearest other point (finite points only)."""

    min: Measure = Field(description="The smallest; 0 when two points coincide.")
    median: Measure = Field(description="The median: the cloud's typical spacing.")
    max: Measure = Field(description="The largest: the most isolated point's.")
    coincident: int = Field(ge=0, description="Points that have another at exactly their place.")


class Neighbourhood(_Model):
    """The neighbourhood each normal was fitted to."""

    k: int | None = Field(description="At most this many points, the point itself included.")
    radius: Measure = Field(description="Only points within this distance; null: any distance.")


class StatusCounts(_Model):
    """How many points got each status (see PointStatus)."""

    ok: int = Field(ge=0, description="A unit normal, oriented as asked.")
    not_finite: int = Field(ge=0, description="A coordinate is NaN or infinite.")
    too_few_neighbours: int = Field(ge=0, description="Under 3 points in the neighbourhood.")
    duplicates: int = Field(ge=0, description="The neighbourhood's points coincide.")
    collinear: int = Field(ge=0, description="The neighbourhood's points lie on a line.")
    ambiguous: int = Field(ge=0, description="Two directions are equally flat.")
    unoriented: int = Field(ge=0, description="A unit normal whose side was not decided.")


class PartOrientation(_Model):
    """One connected part of the neighbour graph (or the whole cloud for per-point modes)."""

    points: int = Field(ge=0, description="Its points that have a normal.")
    flipped: int = Field(ge=0, description="Those whose normal the orientation turned.")
    unoriented: int = Field(ge=0, description="Those whose side could not be decided.")
    reason: str = Field(description="Why some were left unoriented; empty when none were.")
    seed: int = Field(ge=-1, description="The point (0-based) that decided its side, or -1.")


class Orientation(_Model):
    """How the normals' sides were chosen."""

    mode: OrientMode = Field(description="mst, riemannian, viewpoint, direction, file or none.")
    viewpoint: list[Finite] | None = Field(description="The sensor position used, or null.")
    viewpoint_from_file: bool = Field(description="Whether it is the PCD file's VIEWPOINT.")
    direction: list[Finite] | None = Field(description="The direction used, or null.")
    flipped: int = Field(ge=0, description="Normals turned, in all parts.")
    unoriented: int = Field(ge=0, description="Normals whose side could not be decided.")
    part_count: int = Field(ge=0, description="How many parts were oriented on their own.")
    parts: list[PartOrientation] = Field(
        description=f"The first {INDEX_LIST_LIMIT} parts, largest first."
    )


class StoredNormals(_Model):
    """How the normals stored in the file agree with the estimated ones."""

    stored: int = Field(ge=0, description="Points with a stored normal row.")
    unusable: int = Field(ge=0, description="Stored rows that are zero or not finite.")
    compared: int = Field(ge=0, description="Points with a usable stored normal and ours.")
    agreement_degrees: Finite = Field(description="The angle within which lines agree.")
    agreeing: int = Field(
        ge=0, description="Compared points whose lines agree within agreement_degrees."
    )
    median_angle_degrees: Measure = Field(
        description="The median angle between the lines (either side); null if none compared."
    )
    max_angle_degrees: Measure = Field(
        description="The largest angle between the lines; null when none was compared."
    )
    same_side_fraction: Measure = Field(
        description="Of the compared points we oriented, the fraction whose stored normal is "
        "on our side (dot product positive); null when none."
    )


class PointReport(_Model):
    """The report on one point cloud: the file, spacing, normals by status, orientation and
    the diagnosis in plain sentences."""

    file: PointFileInfo = Field(description="The file: name, format, size and what it holds.")
    points: int = Field(ge=0, description="Points kept, in file order.")
    bounds: PointBounds | None = Field(description="The box around the finite points, or null.")
    spacing: Spacing | None = Field(description="Nearest-neighbour distances; null under 2.")
    neighbourhood: Neighbourhood = Field(description="The neighbourhood used: k and radius.")
    counts: StatusCounts = Field(description="How many points got each status.")
    with_normal: int = Field(ge=0, description="Points with a normal: ok or unoriented.")
    far_from_flat: int = Field(
        ge=0,
        description=f"Points with a normal whose neighbourhood is far from flat (surface "
        f"variation over {POINT_FAR_FROM_FLAT:g}): a thin wall or two sheets within its reach, "
        "a sharp edge or heavy noise, where the normal and its side are unsure.",
    )
    orientation: Orientation = Field(description="How the sides were chosen, part by part.")
    stored_normals: StoredNormals | None = Field(
        description="How the file's normals agree with ours; null when it stores none."
    )
    diagnosis: list[str] = Field(description="What was found, in plain sentences.")
