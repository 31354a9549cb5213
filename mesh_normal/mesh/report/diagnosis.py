"""The report in plain words: each problem found, why it matters and what to do about it.

Built from the :class:`~mesh_normal.mesh.report.models.MeshReport` alone, so the page, the JSON
twin and the CLI say the same. Each item is a :class:`Problem` with severity ``"error"`` (normals
or volume are wrong as the file stands), ``"warning"`` (some results are missing or need care) or
``"info"``.
"""

from __future__ import annotations

from collections.abc import Sequence

from mesh_normal.mesh.report.models import (
    ComponentFix,
    FileNormals,
    MeshReport,
    ObjectReport,
    Problem,
    ProblemCode,
    Severity,
)

#: How many objects a sentence names before "and N more".
NAMED_OBJECTS = 3


def _count(number: int, one: str, many: str | None = None) -> str:
    return f"{number:,} {one if number == 1 else (many or one + 's')}"


def _names(items: Sequence[ObjectReport], label: str = "{}") -> str:
    """'a', 'b' and 'c', or 'a', 'b', 'c' and 4 more; ``label`` formats each name."""
    named = [label.format(repr(item.name), item=item) for item in items[:NAMED_OBJECTS]]
    rest = len(items) - len(named)
    if rest:
        return f"{', '.join(named)} and {rest:,} more"
    return named[0] if len(named) == 1 else f"{', '.join(named[:-1])} and {named[-1]}"


def _listed(report: MeshReport) -> str:
    """Where the file has more objects than the report lists, which ones were looked at."""
    if report.object_count > len(report.objects):
        return f" (of the first {len(report.objects):,} objects)"
    return ""


def _flipped_objects(report: MeshReport) -> str:
    """Which objects the fix turns, in words: empty unless the file has several objects."""
    if report.object_count < 2:
        return ""
    flipped = [item for item in report.objects if item.faces_flipped]
    inward = [item for item in flipped if item.orientation == "inward"]
    partly = [item for item in flipped if item.orientation != "inward"]
    sentences = []
    if len(inward) == 1:
        [item] = inward
        whole = "its" if item.faces_flipped == item.faces else f"{item.faces_flipped:,} of its"
        sentences.append(
            f"The object {item.name!r} is wound inward: the fix flips {whole} "
            f"{_count(item.faces, 'face')}{_listed(report)}."
        )
    elif inward:
        names = _names(inward, "{} ({item.faces_flipped:,} faces)")
        sentences.append(
            f"The objects {names} are wound inward: the fix flips their faces{_listed(report)}."
        )
    if partly:
        names = _names(partly, "{} ({item.faces_flipped:,} of {item.faces:,})")
        which = "object" if len(partly) == 1 else "objects"
        sentences.append(f"The fix flips some faces of the {which} {names}{_listed(report)}.")
    return "".join(" " + sentence for sentence in sentences)


def _open_objects(report: MeshReport) -> str:
    """Which objects are open on their own, in words: empty unless there are several."""
    if report.object_count < 2:
        return ""
    open_ones = [item for item in report.objects if not item.closed and item.faces]
    if not open_ones:
        return ""
    if len(open_ones) == 1:
        return f" The object {open_ones[0].name!r} is not closed on its own{_listed(report)}."
    return f" The objects {_names(open_ones)} are not closed on their own{_listed(report)}."


def _weld_argument(report: MeshReport) -> str:
    """``, weld=1e-06`` when the report was made with a weld: the snippets repeat it."""
    return "" if report.weld is None else f", weld={report.weld.tolerance!r}"


def problems(report: MeshReport) -> list[Problem]:
    """Every problem of the report, the most serious first; empty when the mesh is clean."""
    found = [item for check in CHECKS if (item := check(report)) is not None]
    rank = {"error": 0, "warning": 1, "info": 2}
    return sorted(found, key=lambda item: rank[item.severity])


def _problem(
    code: ProblemCode,
    severity: Severity,
    title: str,
    detail: str,
    action: str,
    python: str | None = None,
) -> Problem:
    return Problem(
        code=code, severity=severity, title=title, detail=detail, action=action, python=python
    )


def _winding(report: MeshReport) -> Problem | None:
    flipped = report.fix.faces_flipped
    if report.winding_consistent or (report.nonorientable_components and not flipped):
        return None  # a one-sided part has no consistent winding: see _nonorientable
    return _problem(
        "winding",
        "error",
        "Faces are wound against their neighbours",
        f"Across some shared edges the two faces run the same way, so their normals point to "
        f"opposite sides of the surface: shading shows dark patches, and the volume is "
        f"meaningless. Making the winding consistent flips {_count(flipped, 'face')}."
        + _flipped_objects(report),
        "Download the fixed mesh, or call orient() in your own code.",
        f"import mesh_normal as mn\n\nfixed = mn.orient(vertices, faces{_weld_argument(report)})\n"
        "faces = fixed.faces  # fixed.flipped marks the faces that were reversed",
    )


def _inward(report: MeshReport) -> Problem | None:
    if report.orientation != "inward":
        return None
    return _problem(
        "inward",
        "error",
        "The normals point inward",
        "The winding is consistent, but every part whose outside can be decided is wound "
        "clockwise seen from outside: "
        "normals point into the solid, back-face culling hides the outside, and a closed "
        "part's signed volume is negative." + _flipped_objects(report),
        "Download the fixed mesh (every face reversed), or reverse each face's winding.",
        "faces = faces[:, ::-1]  # reverses every face: A, B, C becomes C, B, A",
    )


def _mixed(report: MeshReport) -> Problem | None:
    if report.orientation != "mixed" or not report.winding_consistent:
        return None
    cavities = any(part.depth and part.depth % 2 for part in report.fix.components)
    way = "away from the material (out, or into their cavity)" if cavities else "outward"
    return _problem(
        "mixed",
        "error",
        "Some parts point outward, others inward",
        f"Each part is wound consistently, but not all of them face "
        f"{'away from the material' if cavities else 'out'}." + _flipped_objects(report),
        f"Download the fixed mesh: each part is turned to face {way} on its own.",
        "import mesh_normal as mn\n\n"
        f"faces = mn.orient(vertices, faces{_weld_argument(report)}).faces",
    )


def _degenerate(report: MeshReport) -> Problem | None:
    count = report.degenerate_faces
    if not count:
        return None
    repeated = report.repeated_index_faces
    which = f" ({_count(repeated, 'face')} repeat a vertex index)" if repeated else ""
    return _problem(
        "degenerate",
        "warning",
        f"{_count(count, 'face has', 'faces have')} no area",
        f"Their corners coincide or lie on one line{which}, so they have no normal. They get "
        "a zero normal and count for nothing in vertex normals; naive code gets NaN here.",
        "Remove them before export (Blender: Merge by Distance, then Delete Loose / "
        "Degenerate Dissolve; trimesh: update_faces with nondegenerate_faces()).",
        "import mesh_normal as mn\n\nkeep = ~mn.face_normals(vertices, faces).degenerate\n"
        "faces = faces[keep]",
    )


def _open(report: MeshReport) -> Problem | None:
    edges = report.boundary_edges
    if not edges:
        return None
    return _problem(
        "open",
        "warning",
        f"The mesh is open: {_count(edges, 'boundary edge')}",
        "Some edges belong to one face only, so the surface has holes or borders. A volume "
        "is not defined, so which side is outside is decided by visibility: the side from "
        "which rays escape past the rest of the mesh (as libigl's reorient_facets_raycast "
        "does). Where both sides see alike, nothing is turned." + _open_objects(report),
        "If the mesh should be closed, fill the holes in your modeller (Blender: select "
        "the border, then Fill). Open sheets such as terrain are fine as they are."
        + _weld_hint(report),
    )


def _weld_hint(report: MeshReport) -> str:
    if report.weld is not None and report.weld.tolerance > 0:
        return ""
    return (
        " If its pieces should meet but miss each other by rounding, analyse it again with "
        "a weld tolerance such as 1e-6 of the mesh's size (weld=1e-6 in Python and the API, "
        "--weld 1e-6 on the command line)."
    )


def _nonmanifold(report: MeshReport) -> Problem | None:
    edges = report.nonmanifold_edges
    if not edges:
        return None
    return _problem(
        "nonmanifold",
        "error",
        f"{_count(edges, 'edge is', 'edges are')} shared by three or more faces",
        "Such edges are non-manifold: no surface has a single inside and outside there, so "
        "the winding cannot be made consistent across them. We report them and leave them "
        "as they are.",
        "Separate or delete the extra faces in your modeller (Blender: Select > All by "
        "Trait > Non Manifold).",
    )


def _nonorientable(report: MeshReport) -> Problem | None:
    parts = report.nonorientable_components
    if not parts:
        return None
    return _problem(
        "nonorientable",
        "error",
        f"{_count(parts, 'part is', 'parts are')} one-sided",
        "Like a Moebius strip, these parts have no consistent winding at all: going around "
        "them turns the front into the back. Their faces were left unflipped.",
        "Cut the part along an edge in your modeller, or accept per-face normals there.",
    )


def _file_normals(report: MeshReport) -> Problem | None:
    # Only normals turned around are a problem: ones within 90 degrees that miss the agreement
    # angle are another exporter's rounding or weighting, and the page counts them.
    stored = report.file_normals
    if not stored or not stored.compared or not stored.opposite:
        return None
    return _problem(
        "file_normals",
        "warning",
        f"{_count(stored.opposite, 'normal')} stored in the file point the other way",
        f"Of {stored.compared:,} {stored.kind} normals in the file, "
        f"{stored.opposite:,} differ from {stored.compared_with} by more than 90°: "
        "the file's normals and its winding disagree, which renderers show as dark or "
        "inside-out faces.",
        "Recompute the normals from the (fixed) winding and export them again.",
        "import mesh_normal as mn\n\n" + _recompute(stored),
    )


def _recompute(stored: FileNormals) -> str:
    """The call that makes normals of the kind (and the weighting) the file's matched best."""
    weighting = f'weighting="{stored.weighting or "angle"}"'
    if stored.kind == "face":
        return "normals = mn.face_normals(vertices, faces).normals"
    if stored.kind == "corner":
        crease = f"crease_angle={stored.crease_angle_degrees or 30:g}"
        return f"normals = mn.corner_normals(vertices, faces, {crease}, {weighting}).normals"
    return f"normals = mn.vertex_normals(vertices, faces, {weighting}).normals"


def _unused(report: MeshReport) -> Problem | None:
    count = report.unused_vertices
    if not count:
        return None
    return _problem(
        "unused_vertices",
        "info",
        f"{_count(count, 'vertex is', 'vertices are')} used by no face",
        "They keep their place in the file's order, so arrays line up with yours; their "
        "vertex normal is a zero row.",
        "Nothing to do unless you want them gone (trimesh: remove_unreferenced_vertices).",
    )


def _components(report: MeshReport) -> Problem | None:
    count = report.components
    if count <= 1:
        return None
    return _problem(
        "components",
        "info",
        f"The mesh has {count:,} separate parts",
        "Parts share no edge. Each is checked and oriented on its own.",
        "Nothing to do, unless the parts should be joined (Blender: Merge by Distance).",
    )


def _of_listed_parts(report: MeshReport) -> str:
    """Where the mesh has more parts than the report lists, which ones were looked at."""
    if report.components > len(report.fix.components):
        return f" (of the first {len(report.fix.components):,} parts)"
    return ""


def _nesting_sentence(part: ComponentFix) -> str:
    """Where a part inside others lies and which way its faces point, as the fix leaves them."""
    where = f"Part {part.component} "
    where += (
        f"is a cavity inside part {part.inside}"
        if part.depth is not None and part.depth % 2
        else f"is a body in the cavity part {part.inside}"
    )
    into = "into the cavity" if part.depth is not None and part.depth % 2 else "out of it"
    if not part.faces_flipped:
        return f"{where}; its faces point {into}, as they should."
    if part.faces_flipped == part.faces:
        return f"{where}; its faces point the other way: the fix turns them to point {into}."
    return f"{where}; the fix turns {_count(part.faces_flipped, 'face')} of it to point {into}."


def _cavities(report: MeshReport) -> Problem | None:
    nested = [part for part in report.fix.components if part.depth and part.inside is not None]
    cavities = [part for part in nested if part.depth is not None and part.depth % 2]
    if not cavities:
        return None
    sentences = [_nesting_sentence(part) for part in nested[:NAMED_OBJECTS]]
    if len(nested) > NAMED_OBJECTS:
        sentences.append(f"{_count(len(nested) - NAMED_OBJECTS, 'more part')} lie inside others.")
    wrong = any(part.faces_flipped for part in nested)
    return _problem(
        "cavities",
        "info",
        f"The mesh has {_count(len(cavities), 'cavity', 'cavities')}{_of_listed_parts(report)}",
        " ".join(sentences) + " A closed part inside an odd number of others is a cavity: its "
        "faces point into it, away from the material, and its volume counts negative, so the "
        "parts' volumes sum to the material's.",
        ("The fix turns the parts that face the wrong way. " if wrong else "Nothing to do. ")
        + "If a part should be a body of its own rather than a cavity, move it out of the other.",
    )


def _touching(report: MeshReport) -> Problem | None:
    parts = [part for part in report.fix.components if part.touches is not None]
    if not parts:
        return None
    sentences = [
        f"Part {part.component} touches part {part.touches}." for part in parts[:NAMED_OBJECTS]
    ]
    if len(parts) > NAMED_OBJECTS:
        sentences.append(f"{_count(len(parts) - NAMED_OBJECTS, 'more part')} touch others.")
    return _problem(
        "touching",
        "warning",
        f"{_count(len(parts), 'closed part touches another', 'closed parts touch others')}"
        + _of_listed_parts(report),
        " ".join(sentences) + " A surface on another one (or within rounding of it) leaves "
        "unknown whether it is a cavity or a body: its faces are left as they are.",
        "If it is a cavity, give the wall between it and the outer surface some thickness; if "
        "the parts are one solid, join them (a boolean union in your modeller).",
    )


def _area(report: MeshReport) -> Problem | None:
    volume_lost = (
        report.volume is None
        and report.watertight
        and report.winding_consistent
        and not report.nonorientable_components
    )
    if report.area is not None and not volume_lost:
        return None
    which = (
        "area and volume"
        if report.area is None and volume_lost
        else ("area" if report.area is None else "volume")
    )
    both = " and " in which
    return _problem(
        "overflow",
        "warning",
        f"The total {which} {'are' if both else 'is'} beyond the double range",
        f"The coordinates are so large that the {which} {'overflow' if both else 'overflows'} "
        "a 64-bit float (areas beyond coordinates of about 1e154, volumes beyond about 1e102); "
        f"{'they are' if both else 'it is'} reported as null. Normals are unaffected.",
        "Scale the mesh down (by a power of two, which is exact) before measuring.",
    )


def _underflow(report: MeshReport) -> Problem | None:
    """A total area of 0.0 from faces that have a normal: it is below the smallest double."""
    if report.area != 0.0 or report.faces <= report.degenerate_faces:
        return None
    return _problem(
        "underflow",
        "warning",
        "The total area is below the smallest double",
        "The coordinates are so small that the area underflows a 64-bit float (areas below "
        "coordinates of about 1e-162); it is reported as 0.0, though the faces are not flat. "
        "Normals are unaffected.",
        "Scale the mesh up (by a power of two, which is exact) before measuring.",
    )


CHECKS = (
    _winding,
    _inward,
    _mixed,
    _nonmanifold,
    _nonorientable,
    _degenerate,
    _open,
    _file_normals,
    _unused,
    _components,
    _cavities,
    _touching,
    _area,
    _underflow,
)
