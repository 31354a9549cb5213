"""The table's columns: one row a file, the same from every engine.

:data:`SCHEMA` is the Arrow schema of ``report.parquet``; each field carries its description in
its metadata (``field.metadata[b"description"]``), and :data:`COLUMNS` lists them for the
datasets page (docs/datasets.md) and ``mesh-normal batch --help``. Figures a row cannot have
(an unreadable file's, a point cloud's faces) are null.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

from mesh_normal.datasets.tasks import FileTask

if TYPE_CHECKING:
    import pyarrow as pa

Status = Literal["ok", "problems", "unreadable", "too_large", "timed_out"]
#: Every status, in the order the summary lists them.
STATUSES: tuple[Status, ...] = ("ok", "problems", "unreadable", "too_large", "timed_out")

_STRING, _INT, _FLOAT, _BOOL, _STRINGS = "string", "int64", "double", "bool", "list<string>"

#: (name, Arrow type, nullable, description), in column order.
COLUMNS: tuple[tuple[str, str, bool, str], ...] = (
    ("path", _STRING, False, "The file as the inputs named it: a path, or a URL."),
    ("size", _INT, False, "Its size in bytes, as listed."),
    ("hash", _STRING, True, "BLAKE2b (128-bit, hex) of its bytes; null when it was not read."),
    ("kind", _STRING, False, 'What it was read as: "mesh", or "points" (with --points).'),
    ("format", _STRING, True, "The format read (stl, obj, ply, ...); null when unreadable."),
    (
        "status",
        _STRING,
        False,
        "ok (read; no problem, or only notes of severity info), problems (an error or a warning "
        "of the diagnosis: problems_found), unreadable, too_large "
        "(over --max-file-mb or the memory limit), timed_out (over --timeout).",
    ),
    ("error", _STRING, True, "Why the file has no report, in one sentence; null otherwise."),
    ("vertices", _INT, True, "Mesh vertices, in file order (none merged or dropped)."),
    ("faces", _INT, True, "Triangles, after polygons are fan-triangulated."),
    ("components", _INT, True, "Connected parts (faces joined by edges)."),
    ("area", _FLOAT, True, "Total surface area; null beyond the double range."),
    ("volume", _FLOAT, True, "Signed volume (positive: normals point outward); null if open."),
    ("watertight", _BOOL, True, "Whether every edge joins exactly two faces."),
    ("winding_consistent", _BOOL, True, "Whether every shared edge is run both ways."),
    ("orientation", _STRING, True, "outward, inward, mixed or undetermined (as the file is)."),
    ("degenerate_faces", _INT, True, "Faces without area (and so no normal)."),
    ("boundary_edges", _INT, True, "Edges that belong to one face only."),
    ("nonmanifold_edges", _INT, True, "Edges shared by three or more faces."),
    ("unused_vertices", _INT, True, "Vertices that no face uses."),
    ("faces_flipped", _INT, True, "How many faces the fix (--fix, mn.orient) reverses."),
    ("stored_normals", _STRING, True, "Which normals the file stores (face, vertex, corner)."),
    ("stored_compared", _INT, True, "Stored normals compared with ours."),
    (
        "stored_agreeing",
        _INT,
        True,
        "Of those, how many agree with ours (1 degree; clouds: 10, as lines).",
    ),
    ("stored_opposite", _INT, True, "Of those, how many point against ours (over 90 degrees)."),
    (
        "stored_median_degrees",
        _FLOAT,
        True,
        "The median angle between the stored normals and ours; null when none were compared.",
    ),
    ("points", _INT, True, "Point clouds: the points kept."),
    ("points_with_normal", _INT, True, "Point clouds: points that got a normal."),
    ("points_unoriented", _INT, True, "Point clouds: normals whose side was not decided."),
    ("spacing_median", _FLOAT, True, "Point clouds: the median nearest-neighbour distance."),
    (
        "problems_found",
        _STRINGS,
        False,
        "The problem codes found, every severity (meshes: the report's, such as winding, "
        "inward, open, degenerate, nonmanifold, components; point clouds: without_normal, "
        "unoriented, file_normals); empty when none.",
    ),
    ("outputs", _STRINGS, False, "The files written for it under --out, as URLs."),
    ("wall_seconds", _FLOAT, False, "The time its job took, reading and writing included."),
)

#: Every column's name, in order.
NAMES: tuple[str, ...] = tuple(column[0] for column in COLUMNS)

if TYPE_CHECKING:
    #: The Arrow schema of one row (and of report.parquet); made on first use, so that the
    #: worker processes, which only make rows, never import pyarrow.
    SCHEMA: pa.Schema


def __getattr__(name: str) -> Any:
    if name == "SCHEMA":
        return arrow_schema()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def arrow_schema() -> pa.Schema:
    """:data:`SCHEMA`, made once."""
    global _schema
    if _schema is None:
        import pyarrow as pa

        types = {
            "string": pa.string(),
            "int64": pa.int64(),
            "double": pa.float64(),
            "bool": pa.bool_(),
            "list<string>": pa.list_(pa.string()),
        }
        fields = [
            pa.field(name, types[kind], nullable=nullable, metadata={"description": text})
            for name, kind, nullable, text in COLUMNS
        ]
        _schema = pa.schema(fields, metadata={"mesh_normal": "batch report, one row a file"})
    return _schema


_schema: pa.Schema | None = None


def empty_row(task: FileTask, kind: str) -> dict[str, Any]:
    """A row with every figure null: the file, and nothing found yet."""
    row: dict[str, Any] = dict.fromkeys(NAMES)
    row.update(
        path=task.path,
        size=task.size,
        kind=kind,
        status="unreadable",
        problems_found=[],
        outputs=[],
        wall_seconds=0.0,
    )
    return row


def failed_row(
    task: FileTask, status: Status, error: str, *, kind: str = "mesh", seconds: float = 0.0
) -> dict[str, Any]:
    """The row of a file without a report: ``status`` and the ``error`` sentence saying why."""
    row = empty_row(task, kind)
    row.update(status=status, error=error, wall_seconds=seconds)
    return row


def rows_table(rows: list[dict[str, Any]]) -> pa.Table:
    """Rows as a table of :data:`SCHEMA`, sorted by path."""
    import pyarrow as pa

    ordered = sorted(rows, key=lambda row: row["path"])
    return pa.Table.from_pylist(ordered, schema=arrow_schema())
