"""The reports as HTML for a notebook: the diagnosis first, then the key figures, then each
problem with what to do about it.

Built from a report's :meth:`~mesh_normal.record.Record.to_dict` (so that this module needs
nothing of the reports' classes), with inline styles only: a notebook, or a page saved from it,
loads no style sheet or script. Every text from the report (a file name, an object's name, a
note) is escaped.
"""

from __future__ import annotations

from html import escape
from typing import Any

#: Each severity's colour (the web page's) and word; "ok" for a report without problems.
SEVERITY = {
    "error": ("#c92a2a", "Error"),
    "warning": ("#e67700", "Warning"),
    "info": ("#1971c2", "Note"),
    "ok": ("#2b8a3e", "OK"),
}
_BOX = (
    "font-family:system-ui,-apple-system,'Segoe UI',sans-serif;font-size:14px;"
    "line-height:1.45;max-width:52em;border:1px solid #d0d5e0;border-radius:6px;"
    "padding:10px 14px;color:#1f2430;background:#fff"
)
_CELL = "padding:2px 12px 2px 0;text-align:left;vertical-align:top;border:none"
_MUTED = "color:#5c6375"


def mesh_report_html(report: dict[str, Any]) -> str:
    """A mesh report (``MeshReport.to_dict()``) as HTML."""
    problems = report["problems"]
    worst = problems[0]["severity"] if problems else "ok"
    headline = (
        problems[0]["title"]
        if problems
        else "No problems found: the normals and the volume can be trusted as the file stands."
    )
    file = report["file"]
    fix = report["fix"]
    figures = [
        ("Vertices", _count(report["vertices"])),
        ("Faces", _count(report["faces"])),
        ("Parts", _count(report["components"])),
        ("Watertight", _yes(report["watertight"])),
        ("Winding consistent", _yes(report["winding_consistent"])),
        ("Orientation", report["orientation"]),
        ("Faces the fix flips", _count(fix["faces_flipped"])),
        ("Boundary edges", _count(report["boundary_edges"])),
        ("Non-manifold edges", _count(report["nonmanifold_edges"])),
        ("Degenerate faces", _count(report["degenerate_faces"])),
        ("Area", _number(report["area"])),
        ("Volume", _number(report["volume"])),
    ]
    items = [_problem(problem) for problem in problems]
    notes = [escape(note) for note in report["notes"]]
    return _page(
        _title(file["name"], file["format"], "mesh"),
        worst,
        headline,
        _count_line(len(problems)),
        figures,
        items,
        notes,
    )


def point_report_html(report: dict[str, Any]) -> str:
    """A point-cloud report (``PointReport.to_dict()``) as HTML."""
    diagnosis = report["diagnosis"]
    counts, orientation = report["counts"], report["orientation"]
    with_normal = report["with_normal"]
    worst = "ok" if with_normal == report["points"] and not orientation["unoriented"] else "warning"
    spacing = report["spacing"]
    neighbourhood = report["neighbourhood"]
    figures = [
        ("Points", _count(report["points"])),
        ("With a normal", _count(with_normal)),
        ("Unoriented", _count(counts["unoriented"])),
        ("Without a normal", _count(report["points"] - with_normal)),
        ("Parts oriented", _count(orientation["part_count"])),
        ("Orientation", orientation["mode"]),
        ("Neighbours (k)", "any" if neighbourhood["k"] is None else str(neighbourhood["k"])),
        ("Radius", "any" if neighbourhood["radius"] is None else _number(neighbourhood["radius"])),
        ("Typical spacing", "-" if spacing is None else _number(spacing["median"])),
        ("Far from flat", _count(report["far_from_flat"])),
    ]
    stored = report["stored_normals"]
    if stored is not None:
        figures.append(
            (
                "Agreeing with the file's",
                f"{_count(stored['agreeing'])} of {_count(stored['compared'])}",
            )
        )
    file = report["file"]
    items = [f'<li style="margin:2px 0">{escape(sentence)}</li>' for sentence in diagnosis[1:]]
    notes = [escape(note) for note in file["notes"]]
    headline = diagnosis[0] if diagnosis else "No normals were estimated."
    return _page(
        _title(file["name"], file["format"], "point cloud"),
        worst,
        headline,
        "",
        figures,
        items,
        notes,
    )


def _page(
    title: str,
    worst: str,
    headline: str,
    count_line: str,
    figures: list[tuple[str, str]],
    items: list[str],
    notes: list[str],
) -> str:
    color, word = SEVERITY[worst]
    # Two figures a row: the box stays short beside a notebook's code.
    cells = [
        f'<th style="{_CELL};font-weight:normal;{_MUTED}">{escape(name)}</th>'
        f'<td style="{_CELL};padding-right:28px;font-variant-numeric:tabular-nums">'
        f"{escape(value)}</td>"
        for name, value in figures
    ]
    rows = "".join(f"<tr>{''.join(cells[i : i + 2])}</tr>" for i in range(0, len(cells), 2))
    parts = [
        f'<div style="{_BOX}">',
        f'<div style="{_MUTED};font-size:12px">{title}</div>',
        f'<div style="margin:4px 0 8px;padding:6px 10px;border-left:4px solid {color};'
        f'background:#f6f7fa"><strong style="color:{color}">{word}</strong> '
        f"<strong>{escape(headline)}</strong>"
        + (f' <span style="{_MUTED}">{count_line}</span>' if count_line else "")
        + "</div>",
        f'<table style="border-collapse:collapse;margin:0 0 6px">{rows}</table>',
    ]
    if items:
        parts.append(f'<ul style="margin:6px 0;padding-left:20px">{"".join(items)}</ul>')
    if notes:
        joined = "".join(f'<li style="margin:2px 0">{note}</li>' for note in notes)
        parts.append(
            f'<div style="{_MUTED};font-size:12px">Reading the file:<ul style="margin:2px 0;'
            f'padding-left:20px">{joined}</ul></div>'
        )
    parts.append("</div>")
    return "".join(parts)


def _problem(problem: dict[str, Any]) -> str:
    color, word = SEVERITY[problem["severity"]]
    python = problem["python"]
    code = (
        ""
        if python is None
        else '<pre style="margin:4px 0;padding:6px 8px;background:#f6f7fa;border-radius:4px;'
        f'font-size:12px;white-space:pre-wrap">{escape(python)}</pre>'
    )
    return (
        f'<li style="margin:6px 0"><strong style="color:{color}">{word}:</strong> '
        f"<strong>{escape(problem['title'])}</strong><br>{escape(problem['detail'])}"
        f'<br><span style="{_MUTED}">What to do:</span> {escape(problem["action"])}{code}</li>'
    )


def _title(name: str | None, file_format: str, kind: str) -> str:
    if file_format == "memory":
        return f"A {kind} in memory"
    if name is None:
        return f"A {escape(file_format.upper())} file"
    return f"{escape(name)} ({escape(file_format.upper())})"


def _count_line(count: int) -> str:
    if count < 2:
        return ""
    return f"(and {count - 1} more below)"


def _count(value: int) -> str:
    return f"{value:,}"


def _yes(value: bool) -> str:
    return "yes" if value else "no"


def _number(value: float | None) -> str:
    return "-" if value is None else f"{value:.6g}"
