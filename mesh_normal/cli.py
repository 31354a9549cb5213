"""The ``mesh-normal`` command: analyse, export normals, fix winding; point-cloud normals;
``batch``, the report on every file of a dataset (:mod:`mesh_normal.datasets.command`).

Exit codes a script can use:

- 0: done; for ``analyze``, the mesh has no problem of severity "error".
- 1: ``analyze`` found at least one problem of severity "error" (the report says which).
- 2: bad usage (an unknown option, a missing argument, an unsupported output type, an output
  that would overwrite the input).
- 3: the input file cannot be read or is not a valid mesh (the message names the problem).
- 4: the output file cannot be written.

It starts fast: this module imports only the standard library and the format table, and each
command imports the library (numpy, the compiled core) when it runs, so ``--help``
and usage errors answer at once.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO, TypeVar, get_args

from mesh_normal import __version__
from mesh_normal.choices import NormalsChoice, NormalsKind, OrientMode, Weighting, Winding
from mesh_normal.files.formats import SUFFIXES, WRITABLE
from mesh_normal.tolerances import ORIENT_MAX_ANGLE, WELD_LIMIT

if TYPE_CHECKING:
    from mesh_normal.files import LoadedMesh
    from mesh_normal.points import OrientMode, PointCloud, PointNormals
    from mesh_normal.report import MeshReport, Weld

Parsed = TypeVar("Parsed")

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE, EXIT_INPUT, EXIT_OUTPUT = 0, 1, 2, 3, 4
NORMAL_SUFFIXES = (".npy", ".csv", ".json")
FIX_FORMATS = WRITABLE
#: ``mesh-normal points -o``: the suffix and what it writes (``write_points``' format or npy).
POINT_OUTPUTS = {".ply": "ply", ".xyz": "xyz", ".csv": "csv", ".npy": "npy"}
#: Components listed by name in the text summary, and in the JSON one.
LISTED_COMPONENTS, JSON_COMPONENTS = 5, 100
#: Why a point has no normal, or no side, in a few words (``PointStatus`` by name).
STATUS_WORDS = {
    "ok": "a unit normal, oriented as asked",
    "not_finite": "a coordinate is NaN or infinite",
    "too_few_neighbours": "fewer than three points in the neighbourhood, itself included",
    "duplicates": "the neighbourhood's points coincide",
    "collinear": "the neighbourhood's points lie on a line",
    "ambiguous": "two directions are equally flat (a symmetric corner)",
    "unoriented": "a unit normal whose side could not be decided",
}


class Failure(Exception):
    """A message for stderr and the exit code to leave with."""

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


class Progress:
    """Stage by stage on stderr with elapsed seconds, when stderr is a terminal (or forced)."""

    def __init__(self, stream: TextIO, enabled: bool) -> None:
        self.stream, self.enabled = stream, enabled
        self.start = time.perf_counter()

    def step(self, text: str) -> None:
        if self.enabled:
            elapsed = time.perf_counter() - self.start
            self.stream.write(f"\r\033[K[{elapsed:6.1f} s] {text}")
            self.stream.flush()

    def done(self) -> None:
        if self.enabled:
            self.step("done\n")


def load(path: str, progress: Progress) -> tuple[LoadedMesh, int]:
    from mesh_normal.files import read_mesh
    from mesh_normal.files.read import mapped_binary_stl, read_mapped

    mapped = mapped_binary_stl(path)  # a large binary STL: mapped, not copied into memory
    if mapped is not None:
        progress.step(f"reading {path}")
        size = len(mapped)
        _fault_ahead(size)
        return _parsed(path, lambda: read_mapped(mapped, Path(path).name)), size
    data = read_input(path, progress)
    return _parsed(path, lambda: read_mesh(data, Path(path).name)), len(data)


def _fault_ahead(size: int) -> None:
    """For a large binary STL of ``size`` bytes, in a process of the command's own: keep freed
    memory for the next step and fault the arrays' memory in on another thread while this one
    reads (``mesh_normal.allocator``). Smaller files and the text formats gain no time from it
    and take more memory."""
    from mesh_normal import allocator

    allocator.start_job(allocator.ARRAYS_PER_STL_BYTE * size)


def read_input(path: str, progress: Progress) -> bytes:
    """The bytes of the file ``path``; one that cannot be read is a failure that says why."""
    progress.step(f"reading {path}")
    try:
        return Path(path).read_bytes()
    except OSError as error:
        raise Failure(f"cannot read {path}: {error.strerror or error}", EXIT_INPUT) from None


def _parsed(path: str, parse: Callable[[], Parsed]) -> Parsed:
    """``parse()``, its file's problem (a MeshFileError) a failure that names the file."""
    from mesh_normal.files import MeshFileError

    try:
        return parse()
    except MeshFileError as error:
        raise Failure(f"{path}: {error}", EXIT_INPUT) from None


def write(path: str, data: bytes) -> None:
    """Write through a temporary file beside ``path`` and rename it: never a half-written
    file, and ``mesh-normal fix a.obj a.obj`` cannot lose the input."""
    from mesh_normal.files.write import replace_file

    try:
        replace_file(path, data)
    except OSError as error:
        raise Failure(f"cannot write {path}: {error.strerror or error}", EXIT_OUTPUT) from None


def analyze(args: argparse.Namespace, progress: Progress) -> int:
    from mesh_normal.analysis import analyse_mesh, build_report

    mesh, size = load(args.file, progress)
    progress.step("checking faces, edges and winding")
    report = build_report(analyse_mesh(mesh, Path(args.file).name, size, weld=args.weld))
    progress.done()
    if args.json:  # the JSON of POST /api/mesh, indented; allow_nan=False: never NaN
        print(json.dumps(report.to_dict(), indent=2, allow_nan=False))
    else:
        print(summary(report))
    serious = any(item.severity == "error" for item in report.problems)
    return EXIT_PROBLEMS if serious else EXIT_OK


def summary(report: MeshReport) -> str:
    """The report as a few lines of text: counts, then each problem and what to do."""
    volume, file = report.volume, report.file
    lines = [
        f"{file.name}: {count(report.vertices, 'vertex', 'vertices')}, "
        f"{count(report.faces, 'face')} ({file.format.upper()}), "
        f"{count(report.components, 'component')}",
        f"area {report.area:.6g}, volume {'-' if volume is None else f'{volume:.6g}'}, "
        f"orientation {report.orientation}, "
        f"{'watertight' if report.watertight else 'open'}, "
        f"winding {'consistent' if report.winding_consistent else 'inconsistent'}",
    ]
    if report.weld is not None:
        lines.append(weld_line(report.weld))
    if report.object_count > 1:  # one object is the mesh itself: the lines above say it all
        lines.append(f"{report.object_count:,} objects:")  # more than one
        lines.extend(
            f"  {item.name}: {count(item.faces, 'face')}, {item.orientation}, "
            f"{'closed' if item.closed else 'open'}, {item.faces_flipped:,} flipped by the fix"
            for item in report.objects
        )
        if report.object_count > len(report.objects):
            lines.append(f"  and {report.object_count - len(report.objects):,} more")
    if not report.problems:
        lines.append("No problems found.")
    lines.extend(
        f"{item.severity}: {item.title}. {terminal_words(item.action)}" for item in report.problems
    )
    if report.fix.faces_flipped:
        weld = "" if report.weld is None else f" --weld {report.weld.tolerance!r}"
        others = ", ".join(f".{name}" for name in FIX_FORMATS if name != "ply")
        lines.append(
            f"To fix the winding: mesh-normal fix{weld} {file.name} FIXED.ply (or {others})"
        )
    return "\n".join(lines)


#: The report's words for the page, as a terminal reads them.
TERMINAL_WORDS = {
    "Download the fixed mesh": "Write the fixed mesh (the command below)",
}


def terminal_words(text: str) -> str:
    """A report sentence written for the page, in the terminal's words."""
    for page, terminal in TERMINAL_WORDS.items():
        text = text.replace(page, terminal)
    return text


def weld_line(weld: Weld) -> str:
    """The weld in words: ``weld 1e-06 of the diagonal (2.7e-06): 34 vertices joined``."""
    distance = "beyond the double range" if weld.distance is None else f"{weld.distance:.3g}"
    joined = weld.joined_vertices
    return (
        f"weld {weld.tolerance!r} of the diagonal ({distance}): {joined:,} "
        f"{'vertex' if joined == 1 else 'vertices'} joined beyond exact equality"
    )


def weld_fraction(text: str) -> float:
    """``--weld``: a number from 0 to WELD_LIMIT, or argparse's usage error naming it."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 <= value <= WELD_LIMIT):
        raise argparse.ArgumentTypeError(
            f"must be a number from 0 to {WELD_LIMIT:g} (a fraction of the bounding-box "
            f"diagonal), not {text!r}"
        )
    return value


def normals(args: argparse.Namespace, progress: Progress) -> int:
    suffix = Path(args.output).suffix.lower()
    mesh_suffixes = tuple(f".{name}" for name in FIX_FORMATS)
    if suffix not in (*NORMAL_SUFFIXES, *mesh_suffixes):
        raise Failure(
            f"the output must end in {', '.join((*NORMAL_SUFFIXES, *mesh_suffixes))}, not "
            f"{suffix or 'no suffix'}",
            EXIT_USAGE,
        )
    if suffix in mesh_suffixes:  # the mesh itself, with the normals in it
        from mesh_normal.files.formats import FORMATS, HOLDS_NORMALS

        name = suffix.lstrip(".")
        held = HOLDS_NORMALS.get(name, ())
        if args.kind not in held:
            holds = f"only {' and '.join(held)} normals" if held else "no normals"
            raise Failure(
                f"{args.kind} normals do not fit in a {FORMATS[name].title} file, which holds "
                f"{holds}; use .obj or .glb (any kind), or .npy, .csv, .json",
                EXIT_USAGE,
            )
        args.input, args.format, args.normals, args.winding = args.file, name, args.kind, "keep"
        return export(args, progress)
    from mesh_normal.exports import NormalsFormat, normals_file, normals_to_write

    if same_file(args.output, args.file):
        raise Failure(f"{args.output} is the input file; write the normals to another file", 2)
    mesh, _ = load(args.file, progress)
    progress.step(f"computing {args.kind} normals")
    values, missing = normals_to_write(mesh, args.kind, args.weighting, args.crease_angle)
    progress.step(f"writing {args.output}")
    formats: dict[str, NormalsFormat] = {".npy": "npy", ".csv": "csv", ".json": "json"}
    # the same files as POST /api/mesh/normals
    data = normals_file(
        values, missing, args.kind, args.weighting, args.crease_angle, formats[suffix]
    )
    write(args.output, data)
    progress.done()
    if int(missing.sum()):
        zero = count(int(missing.sum()), f"{args.kind} normal")
        print(
            f"{zero} {'is a zero row' if int(missing.sum()) == 1 else 'are zero rows'} "
            "(degenerate or unused); see `mesh-normal analyze`.",
            file=sys.stderr,
        )
    return EXIT_OK


def fix(args: argparse.Namespace, progress: Progress) -> int:
    """Write the mesh with consistent, outward winding; nothing when nothing needs fixing."""
    args.winding = "fix"
    return export(args, progress)


def export(args: argparse.Namespace, progress: Progress) -> int:
    """Write the mesh again: winding kept, fixed or flipped, normals as asked, the rest kept
    where the output's format holds it and named where it does not."""
    chosen = output_format(args.output, args.format)
    if same_file(args.output, args.input) and not args.force:
        raise Failure(
            f"{args.output} is the input file; write to another file, or give --force to "
            "replace the input",
            EXIT_USAGE,
        )
    from mesh_normal.analysis import flips_by_component, weld_summary
    from mesh_normal.files import MeshFileError
    from mesh_normal.mesh_export import export_mesh

    mesh, _ = load(args.input, progress)
    progress.step(f"writing the mesh ({args.winding} the winding)")
    try:
        result = export_mesh(
            mesh,
            chosen,
            normals=args.normals,
            winding=args.winding,
            weighting=args.weighting,
            crease_angle=args.crease_angle,
            weld=args.weld,
        )
    except MeshFileError as error:
        raise Failure(f"cannot write {args.output}: {error}", EXIT_OUTPUT) from None
    faces = len(mesh.faces)
    unchanged = args.command == "fix" and not result.faces_flipped
    if unchanged and not (args.write_unchanged or args.force):
        progress.done()
        verdict = result.orientation.orientation if result.orientation else "unknown"
        print(
            f"nothing to fix: none of the {count(faces, 'face')} of {args.input} needs "
            f"flipping (orientation {verdict}); wrote nothing (--write-unchanged writes "
            f"{args.output} anyway)"
        )
        return EXIT_OK
    progress.step(f"writing {args.output}")
    write(args.output, result.data)
    progress.done()
    if result.dropped:  # do no harm: never leave data out without saying so
        print(f"mesh-normal: {args.output} leaves out {'; '.join(result.dropped)}", file=sys.stderr)
    kept = f"; kept {', '.join(result.kept)}" if result.kept else ""
    if result.orientation is not None:
        parts = flips_by_component(result.orientation)
        where = f" (component:faces {parts})" if parts else ""
        print(
            f"wrote {args.output}: flipped {result.faces_flipped:,} of {count(faces, 'face')}"
            f"{where}; orientation before: {result.orientation.orientation}{kept}"
        )
    else:
        done = "every face flipped" if args.winding == "flip" else "winding as it was"
        print(f"wrote {args.output}: {count(faces, 'face')}, {done}{kept}")
    weld = weld_summary(mesh.vertices, args.weld)
    if weld is not None:
        print(weld_line(weld))
    return EXIT_OK


def output_format(output: str, given: str | None) -> str:
    """The mesh format ``--format`` or the output's suffix names; a usage failure otherwise."""
    chosen = given or Path(output).suffix.lower().lstrip(".")
    if chosen not in FIX_FORMATS:
        raise Failure(
            f"the output format must be one of {', '.join(FIX_FORMATS)} (from the "
            f"suffix or --format), not {chosen or 'none'}",
            EXIT_USAGE,
        )
    return chosen


def count(number: int, noun: str, plural: str | None = None) -> str:
    """``1 face``, ``2 faces``, ``1,000 vertices``: a count with its noun, in the right number."""
    return f"{number:,} {noun if number == 1 else plural or noun + 's'}"


def points(args: argparse.Namespace, progress: Progress) -> int:
    """Normals of a point cloud: a file of them with ``-o``, else a summary on stdout."""
    output_format = point_output(args.file, args.output)
    if args.k is None and args.radius is None:
        raise Failure("--k all needs --radius", EXIT_USAGE)
    from mesh_normal.points import point_normals

    cloud = load_points(args.file, progress)
    orient, references = point_references(args, cloud)
    bar = PointsBar(progress, orient)
    try:
        result = point_normals(
            cloud.points,
            k=args.k,
            radius=args.radius,
            orient=orient,
            max_angle=args.max_angle,
            progress=bar.update,
            **references,
        )
    except ValueError as error:  # a neighbourhood or reference the library refuses
        raise Failure(str(error), EXIT_USAGE) from None
    found = points_summary(args, cloud, result, orient)
    if args.output is not None:
        progress.step(f"writing {args.output}")
        write(args.output, point_bytes(cloud, result, output_format))
    progress.done()
    if args.json:  # allow_nan=False: never NaN
        print(json.dumps(found, indent=2, allow_nan=False))
    elif args.output is not None:
        print(written_line(found, args.output))
    else:
        print(points_text(found))
    return EXIT_OK


def point_output(source: str, output: str | None) -> str | None:
    """The output's format from its suffix; refuses another suffix and the input's own path."""
    if output is None:
        return None
    suffix = Path(output).suffix.lower()
    if suffix not in POINT_OUTPUTS:
        raise Failure(
            f"the output must end in {', '.join(POINT_OUTPUTS)}, not {suffix or 'no suffix'}",
            EXIT_USAGE,
        )
    if same_file(output, source):
        raise Failure(f"{output} is the input file; write the normals to another file", EXIT_USAGE)
    return POINT_OUTPUTS[suffix]


def same_file(one: str, other: str) -> bool:
    """Whether two paths name one file: the same path once resolved, or a (hard) link."""
    if Path(one).resolve() == Path(other).resolve():
        return True
    try:
        return Path(one).samefile(other)
    except OSError:  # either does not exist (yet)
        return False


def load_points(path: str, progress: Progress) -> PointCloud:
    from mesh_normal.points import read_points

    data = read_input(path, progress)
    return _parsed(path, lambda: read_points(data, Path(path).name))


def point_references(
    args: argparse.Namespace, cloud: PointCloud
) -> tuple[OrientMode, dict[str, Any]]:
    """The orientation mode and the keyword it needs: ``--viewpoint`` or the file's, the
    ``--direction``, or the file's normals. Without ``--orient``, a viewpoint or direction
    given chooses it."""
    orient: OrientMode = args.orient or (
        "viewpoint" if args.viewpoint else "direction" if args.direction else "mst"
    )
    for option in ("viewpoint", "direction"):
        if getattr(args, option) is not None and orient != option:
            raise Failure(f"--{option} is only used with --orient {option}", EXIT_USAGE)
    if orient == "viewpoint":
        if args.viewpoint is not None:
            return orient, {"viewpoint": args.viewpoint}
        if cloud.viewpoint is None:
            raise Failure(
                "--orient viewpoint needs --viewpoint X,Y,Z: the file stores no viewpoint",
                EXIT_USAGE,
            )
        return orient, {"viewpoint": cloud.viewpoint[0]}
    if orient == "direction":
        if args.direction is None:
            raise Failure("--orient direction needs --direction X,Y,Z", EXIT_USAGE)
        return orient, {"direction": args.direction}
    if orient == "file":
        if cloud.normals is None:
            raise Failure(f"--orient file needs normals, and {args.file} stores none", EXIT_USAGE)
        return orient, {"stored": cloud.normals}
    return orient, {}


class PointsBar:
    """The estimation's progress over the points as a bar, then the orientation's step."""

    WIDTH = 24

    def __init__(self, progress: Progress, orient: str) -> None:
        self.progress, self.orient = progress, orient

    def update(self, done: int, total: int) -> None:
        filled = self.WIDTH * done // max(total, 1)
        bar = "#" * filled + "." * (self.WIDTH - filled)
        self.progress.step(f"estimating normals [{bar}] {done:,} of {total:,} points")
        if done == total and self.orient != "none":
            self.progress.step(f"orienting them ({self.orient})")


def point_bytes(cloud: PointCloud, result: PointNormals, output_format: str | None) -> bytes:
    """The file ``-o`` names: the normals alone (``.npy``), a row for each of the file's rows
    (those it left out, a PCD's NaN points, as zeros, so that row i is the file's point i),
    or the points read with their normals. Points without a normal have zero rows."""
    if output_format == "npy":
        import numpy as np

        from mesh_normal.exports import npy_bytes

        rows = np.zeros((cloud.file_points, 3))
        rows[cloud.kept] = result.normals
        return npy_bytes(rows)
    from mesh_normal.points import write_points

    return write_points(cloud.points, result.normals, output_format or "ply")


def points_summary(
    args: argparse.Namespace, cloud: PointCloud, result: PointNormals, orient: str
) -> dict[str, Any]:
    """What ``mesh-normal points`` says, as the JSON of ``--json`` (and the text's source)."""
    with_normal = int(result.valid.sum())
    parts = result.components
    references: dict[str, list[float] | None] = {"viewpoint": None, "direction": None}
    if orient in references:
        value = args.viewpoint if orient == "viewpoint" else args.direction
        if value is None:  # the file's viewpoint
            value = cloud.viewpoint[0] if cloud.viewpoint is not None else None
        references[orient] = None if value is None else [float(x) for x in value]
    return {
        "file": Path(args.file).name,
        "format": cloud.format,
        "source_kind": cloud.source_kind,
        "points": len(cloud.points),
        "file_points": cloud.file_points,
        "notes": list(cloud.notes),
        "neighbourhood": {"k": args.k, "radius": args.radius},
        "orient": orient,
        **references,
        "max_angle": args.max_angle,
        "with_normal": with_normal,
        "without_normal": len(cloud.points) - with_normal,
        "counts": result.counts(),
        "flipped": result.flipped,
        "unoriented": result.unoriented,
        "component_count": len(parts),
        "components": [
            {
                "points": part.points,
                "flipped": part.flipped,
                "unoriented": part.unoriented,
                "reason": part.reason,
                "seed": part.seed,
            }
            for part in parts[:JSON_COMPONENTS]
        ],
        "stored_normals": stored_agreement(cloud, result),
        "output": args.output,
    }


def stored_agreement(cloud: PointCloud, result: PointNormals) -> dict[str, Any] | None:
    """How the normals agree with the file's, where both exist: the median angle between
    their lines (0-90 degrees: the estimate, whatever the sides) and how many point the same
    way (the orientation)."""
    if cloud.normals is None:
        return None
    import numpy as np

    from mesh_normal.stored_normals import unit_rows

    unit, usable = unit_rows(np.asarray(cloud.normals))
    both = usable & result.valid
    ours, theirs = result.normals[both], unit[both]
    # 2 atan2(|a - b|, |a + b|) (Kahan): accurate at every angle, unlike acos of a dot product.
    apart = np.linalg.norm(ours - theirs, axis=1)
    together = np.linalg.norm(ours + theirs, axis=1)
    angles = np.degrees(2 * np.arctan2(apart, together))
    lines = np.minimum(angles, 180.0 - angles)
    same = int(np.count_nonzero(apart < together))
    return {
        "compared": int(both.sum()),
        "median_line_degrees": float(np.median(lines)) if len(lines) else None,
        "same_way": same,
        "opposite": int(both.sum()) - same,
    }


def points_text(found: dict[str, Any]) -> str:
    """The summary in plain words, a few lines."""
    kind = " vertices" if found["source_kind"] == "mesh vertices" else ""
    lines = [
        f"{found['file']}: {count(found['points'], 'point')} ({found['format'].upper()}{kind}), "
        f"{found['with_normal']:,} with a normal, {found['without_normal']:,} without"
    ]
    if found["file_points"] != found["points"]:
        left_out = found["file_points"] - found["points"]
        lines.append(f"the file holds {count(found['file_points'], 'row')}: {left_out:,} left out")
    lines.extend(f"note: {note}" for note in found["notes"])
    lines.append(f"neighbourhood: {neighbourhood_words(found)}; {orientation_words(found)}")
    lines.extend(
        f"  {name}: {count:,} ({STATUS_WORDS.get(name, name)})"
        for name, count in found["counts"].items()
        if count
    )
    lines.extend(component_lines(found))
    stored = found["stored_normals"]
    if stored is not None:
        lines.append(stored_line(stored))
    return "\n".join(lines)


def neighbourhood_words(found: dict[str, Any]) -> str:
    k, radius = found["neighbourhood"]["k"], found["neighbourhood"]["radius"]
    if radius is None:
        return f"the {k} nearest points, itself included"
    if k is None:
        return f"every point within {radius:g}"
    return f"at most {k} points within {radius:g}, itself included"


def orientation_words(found: dict[str, Any]) -> str:
    orient = found["orient"]
    if orient in ("mst", "riemannian"):
        return f"oriented by {orient} (max angle {found['max_angle']:g} degrees)"
    if orient == "viewpoint":
        return f"oriented towards the viewpoint {vector_words(found['viewpoint'])}"
    if orient == "direction":
        return f"oriented along {vector_words(found['direction'])}"
    if orient == "file":
        return "oriented to agree with the file's normals"
    return "not oriented (each normal's largest component positive)"


def vector_words(vector: list[float]) -> str:
    return "(" + ", ".join(f"{x:g}" for x in vector) + ")"


def component_lines(found: dict[str, Any]) -> list[str]:
    total, parts = found["component_count"], found["components"]
    if not total:
        return []
    lines = [
        f"orientation: {count(total, 'part')}; {count(found['flipped'], 'normal')} flipped, "
        f"{found['unoriented']:,} unoriented"
    ]
    for number, part in enumerate(parts[:LISTED_COMPONENTS], 1):
        seed = f", seed point {part['seed']:,}" if part["seed"] >= 0 else ", no seed"
        if found["orient"] not in ("mst", "riemannian"):  # each point decided alone
            seed = ""
        reason = f"; {part['reason']}" if part["reason"] else ""
        lines.append(
            f"  part {number}: {count(part['points'], 'point')}, {part['flipped']:,} flipped, "
            f"{part['unoriented']:,} unoriented{seed}{reason}"
        )
    if total > LISTED_COMPONENTS:
        lines.append(f"  and {total - LISTED_COMPONENTS:,} more")
    return lines


def stored_line(stored: dict[str, Any]) -> str:
    if not stored["compared"]:
        return "the file's normals: none to compare (zero, not finite, or no normal of ours)"
    return (
        f"the file's normals: {stored['compared']:,} compared, median angle between the lines "
        f"{stored['median_line_degrees']:.3g} degrees; {stored['same_way']:,} "
        f"{'points' if stored['same_way'] == 1 else 'point'} the same way, "
        f"{stored['opposite']:,} the opposite way"
    )


def written_line(found: dict[str, Any], output: str) -> str:
    """What ``-o`` wrote, and what in it is not a normal oriented as asked."""
    rows = found["file_points"] if output.lower().endswith(".npy") else found["points"]
    line = f"wrote {count(rows, 'normal')} to {output}"
    missing, unoriented = found["without_normal"], found["counts"]["unoriented"]
    if missing:
        reasons = ", ".join(
            f"{number:,} {name}"
            for name, number in found["counts"].items()
            if number and name not in ("ok", "unoriented")
        )
        are = "is a zero row" if missing == 1 else "are zero rows"
        line += f"; {count(missing, 'point')} without a normal {are} ({reasons})"
    if unoriented:
        its = "its side" if unoriented == 1 else "their side"
        line += f"; {count(unoriented, 'normal')} unoriented ({its} could not be decided)"
    left_out = found["file_points"] - found["points"]
    if left_out and output.lower().endswith(".npy"):
        rows_left = (
            "row the file left out is a zero row"
            if left_out == 1
            else ("rows the file left out are zero rows")
        )
        line += f"; {left_out:,} {rows_left} too"
    return line + ("; see `mesh-normal points FILE`" if missing or unoriented else "")


def vector3(text: str) -> list[float]:
    """``--viewpoint``, ``--direction``: three finite numbers apart by commas."""
    values = [value.strip() for value in text.split(",")]
    try:
        numbers = [float(value) for value in values]
    except ValueError:
        numbers = []
    if len(numbers) != 3 or not all(math.isfinite(x) for x in numbers):
        raise argparse.ArgumentTypeError(
            f"must be three finite numbers apart by commas, like 0,0,1, not {text!r}"
        )
    return numbers


def neighbour_count(text: str) -> int | None:
    """``--k``: a whole number, at least 3 (the point and two neighbours), or ``all``."""
    if text.strip().lower() == "all":
        return None
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 3:
        raise argparse.ArgumentTypeError(
            f"must be a whole number of at least 3 (the point and two neighbours), or all "
            f"with --radius, not {text!r}"
        )
    return value


def positive_number(text: str) -> float:
    """``--radius``: a positive finite number."""
    return _number(text, lambda value: math.isfinite(value) and value > 0, "a positive number")


def max_angle(text: str) -> float:
    """``--max-angle``: degrees, over 0 and at most 90."""
    return _number(text, lambda value: 0 < value <= 90, "in degrees, over 0 and at most 90")


def _number(text: str, accepted: Callable[[float], bool], what: str) -> float:
    """``text`` as a float that ``accepted`` takes (NaN never is), or argparse's error."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not accepted(value):
        raise argparse.ArgumentTypeError(f"must be {what}, not {text!r}")
    return value


SERVE_HINT = (
    "The web app is not part of the mesh-normal package: from a checkout of the "
    "project, run `make run` (or `uvicorn app.main:app`)."
)


def serve(_args: argparse.Namespace, _progress: Progress) -> int:
    """Say how to start the web app, which the package does not hold."""
    print(f"mesh-normal: {SERVE_HINT}", file=sys.stderr)
    return EXIT_USAGE


def parser() -> argparse.ArgumentParser:
    formats = ", ".join(sorted(SUFFIXES))
    main_parser = argparse.ArgumentParser(
        prog="mesh-normal",
        description="Surface normals of triangle meshes: check, export, fix.",
        epilog="Exit codes: 0 done, 1 analyze found errors, 2 usage, 3 unreadable input, "
        "4 unwritable output.",
    )
    main_parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    main_parser.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show stages on stderr (default: when stderr is a terminal)",
    )
    commands = main_parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    analyze_parser = commands.add_parser(
        "analyze", help="report on a mesh file", description=f"Report on a mesh file ({formats})."
    )
    analyze_parser.add_argument("file")
    analyze_parser.add_argument("--json", action="store_true", help="the full report as JSON")
    add_weld(analyze_parser)
    analyze_parser.set_defaults(run=analyze)

    normals_parser = commands.add_parser("normals", help="write face, vertex or corner normals")
    normals_parser.add_argument("file")
    # A metavar, because argparse formats a metavar from the choices as each is added.
    normals_parser.add_argument(
        "--kind",
        choices=get_args(NormalsKind),
        default="vertex",
        metavar="KIND",
        help="%(choices)s (default: %(default)s)",
    )
    normals_parser.add_argument(
        "--weighting",
        choices=get_args(Weighting),
        default="angle",
        metavar="WEIGHTING",
        help="of vertex normals: %(choices)s (default: %(default)s)",
    )
    add_crease_angle(normals_parser)
    normals_parser.add_argument(
        "-o",
        "--output",
        required=True,
        help="OUT.npy (float64), OUT.csv, OUT.json: the normals; OUT.obj, OUT.glb (any kind), "
        "OUT.ply (face, vertex), OUT.off (vertex), OUT.stl (face): the mesh with them",
    )
    normals_parser.add_argument(
        "--force", action="store_true", help="allow OUT to be the input file"
    )
    normals_parser.set_defaults(run=normals, weld=None, write_unchanged=True)

    fix_parser = commands.add_parser(
        "fix",
        help="write the mesh with consistent, outward winding",
        description="Write the mesh with consistent, outward winding, keeping what the "
        "output's format holds (colours, groups, normals recomputed) and naming what it "
        "cannot. Writes nothing when no face needs flipping (see --write-unchanged), and "
        "never over the input without --force; another existing OUT is replaced, as cp does.",
    )
    add_output(fix_parser)
    fix_parser.add_argument(
        "--write-unchanged",
        action="store_true",
        help="write OUT even when no face needs flipping",
    )
    fix_parser.set_defaults(run=fix, winding="fix")

    export_parser = commands.add_parser(
        "export",
        help="write the mesh again, with normals, its winding kept, fixed or flipped",
        description="Write the mesh in another format or with its normals (OBJ vn, PLY and "
        "OFF vertex nx ny nz, GLB NORMAL, STL facet normals), keeping what the format "
        "holds and naming what it cannot. Never over the input without --force.",
    )
    add_output(export_parser)
    export_parser.add_argument(
        "--winding",
        choices=get_args(Winding),
        default="keep",
        metavar="WINDING",
        help="%(choices)s: keep the faces, fix them (consistent and outward) or flip every "
        "one (default: %(default)s)",
    )
    export_parser.set_defaults(run=export, write_unchanged=True)

    points_parser = commands.add_parser(
        "points",
        help="estimate the normals of a point cloud",
        description="Estimate the normals of a point cloud (PLY, XYZ/PTS/TXT/CSV, PCD, "
        "LAS/LAZ, or a mesh file's vertices): a file of them with -o, else a summary.",
        epilog="Negative numbers in a vector need the = form: --viewpoint=-1,0,5.",
    )
    points_parser.add_argument("file")
    points_parser.add_argument(
        "-o",
        "--output",
        help="OUT.ply, OUT.xyz or OUT.csv (the points with their normals) or OUT.npy (the "
        "(n, 3) float64 normals); points without a normal get zeros. Default: a summary",
    )
    points_parser.add_argument(
        "--k",
        type=neighbour_count,
        default=30,
        metavar="K",
        help="the neighbourhood's size, the point included (default: %(default)s); with "
        "--radius at most K within it, or all",
    )
    points_parser.add_argument(
        "--radius", type=positive_number, metavar="R", help="only neighbours within R"
    )
    points_parser.add_argument(
        "--orient",
        choices=get_args(OrientMode),
        metavar="MODE",
        help="%(choices)s (default: mst, or viewpoint/direction when that option is given)",
    )
    points_parser.add_argument(
        "--viewpoint",
        type=vector3,
        metavar="X,Y,Z",
        help="the sensor's position, for --orient viewpoint (default: a PCD file's VIEWPOINT)",
    )
    points_parser.add_argument(
        "--direction", type=vector3, metavar="X,Y,Z", help="for --orient direction, e.g. 0,0,1"
    )
    points_parser.add_argument(
        "--max-angle",
        type=max_angle,
        default=ORIENT_MAX_ANGLE,
        metavar="DEGREES",
        help="mst and riemannian: the sharpest turn a side is carried across "
        "(default: %(default)s)",
    )
    points_parser.add_argument("--json", action="store_true", help="the summary as JSON")
    points_parser.set_defaults(run=points)

    from mesh_normal.datasets.command import add_batch

    add_batch(commands)

    serve_parser = commands.add_parser(
        "serve",
        help="say how to start the web app (not part of this package)",
        description=SERVE_HINT,
    )
    # The old options are accepted and ignored, so that old scripts get the sentence.
    serve_parser.add_argument("--host", help=argparse.SUPPRESS)
    serve_parser.add_argument("--port", help=argparse.SUPPRESS)
    serve_parser.add_argument("--upload-limit-mb", help=argparse.SUPPRESS)
    serve_parser.set_defaults(run=serve)
    return main_parser


def add_output(command: argparse.ArgumentParser) -> None:
    """The arguments ``fix`` and ``export`` share."""
    command.add_argument("input")
    command.add_argument("output", help=f"OUT.{', OUT.'.join(FIX_FORMATS)}")
    command.add_argument("--format", choices=FIX_FORMATS)
    command.add_argument(
        "--normals",
        choices=get_args(NormalsChoice),
        default="auto",
        metavar="KIND",
        help="%(choices)s: the normals to write, computed on the faces written (default: "
        "%(default)s, the kind the input stored, none for STL)",
    )
    command.add_argument(
        "--weighting",
        choices=get_args(Weighting),
        default="angle",
        metavar="WEIGHTING",
        help="of vertex and corner normals: %(choices)s (default: %(default)s)",
    )
    add_crease_angle(command)
    command.add_argument(
        "--force", action="store_true", help="allow OUT to be the input file (replacing it)"
    )
    add_weld(command)


def add_crease_angle(command: argparse.ArgumentParser) -> None:
    command.add_argument(
        "--crease-angle",
        type=float,
        default=30.0,
        metavar="DEGREES",
        help="corner normals: edges sharper than this stay sharp (default: %(default)s)",
    )


def add_weld(command: argparse.ArgumentParser) -> None:
    command.add_argument(
        "--weld",
        type=weld_fraction,
        default=None,
        metavar="FRACTION",
        help="also treat vertices closer than FRACTION of the bounding-box diagonal as one "
        "point, for pieces that miss each other by rounding (e.g. 1e-6; at most "
        f"{WELD_LIMIT:g}); the vertices are kept. Default: off, only identical coordinates",
    )


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    if not 0 <= getattr(args, "crease_angle", 0.0) <= 180:
        print("mesh-normal: --crease-angle must be between 0 and 180 degrees", file=sys.stderr)
        return EXIT_USAGE
    enabled = sys.stderr.isatty() if args.progress is None else args.progress
    progress = Progress(sys.stderr, enabled)
    if argv is None:  # a process of its own: one job, whose allocator it may tune
        from mesh_normal import allocator

        allocator.enable_jobs()
    try:
        return int(args.run(args, progress))
    except Failure as failure:
        if enabled:
            sys.stderr.write("\n")
        print(f"mesh-normal: {failure}", file=sys.stderr)
        return failure.code


if __name__ == "__main__":
    sys.exit(main())
