"""The ``mesh-normal`` command: analyse, export normals, fix winding.

Exit codes a script can use:

- 0: done; for ``analyze``, the mesh has no problem of severity "error".
- 1: ``analyze`` found at least one problem of severity "error" (the report says which).
- 2: bad usage (an unknown option, a missing argument, an unsupported output type).
- 3: the input file cannot be read or is not a valid mesh (the message names the problem).
- 4: the output file cannot be written.

It starts fast: this module imports only the standard library and the format table, and each
command imports the library (numpy, numba, pydantic) when it runs, so ``--help`` and usage
errors answer at once.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import time
from collections.abc import Collection, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from mesh_normal import __version__
from mesh_normal.files.formats import SUFFIXES, WRITABLE
from mesh_normal.tolerances import WELD_LIMIT

if TYPE_CHECKING:
    from mesh_normal.files import LoadedMesh
    from mesh_normal.report import MeshReport, Weld

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE, EXIT_INPUT, EXIT_OUTPUT = 0, 1, 2, 3, 4
NORMAL_SUFFIXES = (".npy", ".csv", ".json", ".ply")
FIX_FORMATS = WRITABLE


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
    from mesh_normal.files import MeshFileError, read_mesh

    progress.step(f"reading {path}")
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        raise Failure(f"cannot read {path}: {error.strerror or error}", EXIT_INPUT) from None
    try:
        return read_mesh(data, Path(path).name), len(data)
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
        print(json.dumps(report.model_dump(mode="json"), indent=2, allow_nan=False))
    else:
        print(summary(report))
    serious = any(item.severity == "error" for item in report.problems)
    return EXIT_PROBLEMS if serious else EXIT_OK


def summary(report: MeshReport) -> str:
    """The report as a few lines of text: counts, then each problem and what to do."""
    volume, file = report.volume, report.file
    lines = [
        f"{file.name}: {report.vertices:,} vertices, {report.faces:,} faces "
        f"({file.format.upper()}), {report.components:,} component(s)",
        f"area {report.area!r}, volume {'-' if volume is None else repr(volume)}, "
        f"orientation {report.orientation}, "
        f"{'watertight' if report.watertight else 'open'}, "
        f"winding {'consistent' if report.winding_consistent else 'inconsistent'}",
    ]
    if report.weld is not None:
        lines.append(weld_line(report.weld))
    if report.object_count > 1:  # one object is the mesh itself: the lines above say it all
        lines.append(f"{report.object_count:,} objects:")
        lines.extend(
            f"  {item.name}: {item.faces:,} faces, {item.orientation}, "
            f"{'closed' if item.closed else 'open'}, {item.faces_flipped:,} flipped by the fix"
            for item in report.objects
        )
        if report.object_count > len(report.objects):
            lines.append(f"  and {report.object_count - len(report.objects):,} more")
    if not report.problems:
        lines.append("No problems found.")
    lines.extend(f"{item.severity}: {item.title}. {item.action}" for item in report.problems)
    if report.fix.faces_flipped:
        weld = "" if report.weld is None else f" --weld {report.weld.tolerance!r}"
        lines.append(
            f"To fix the winding: mesh-normal fix{weld} {file.name} FIXED.ply (or .stl, .obj)"
        )
    return "\n".join(lines)


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
    if suffix not in NORMAL_SUFFIXES:
        raise Failure(
            f"the output must end in {', '.join(NORMAL_SUFFIXES)}, not {suffix or 'no suffix'}",
            EXIT_USAGE,
        )
    if suffix == ".ply" and args.kind == "corner":
        raise Failure(
            "corner normals do not fit in a PLY file; use .npy, .csv or .json", EXIT_USAGE
        )
    from mesh_normal.exports import NormalsFormat, compute_normals, normals_file, normals_ply

    mesh, _ = load(args.file, progress)
    progress.step(f"computing {args.kind} normals")
    values, missing = compute_normals(mesh, args.kind, args.weighting, args.crease_angle)
    progress.step(f"writing {args.output}")
    if suffix == ".ply":
        data = normals_ply(mesh, values, args.kind)
    else:  # the same files as POST /api/mesh/normals
        formats: dict[str, NormalsFormat] = {".npy": "npy", ".csv": "csv", ".json": "json"}
        data = normals_file(
            values, missing, args.kind, args.weighting, args.crease_angle, formats[suffix]
        )
    write(args.output, data)
    progress.done()
    if int(missing.sum()):
        print(
            f"{int(missing.sum()):,} {args.kind} normal(s) are zero rows (degenerate or "
            "unused); see `mesh-normal analyze`.",
            file=sys.stderr,
        )
    return EXIT_OK


def fix(args: argparse.Namespace, progress: Progress) -> int:
    chosen = args.format or Path(args.output).suffix.lower().lstrip(".")
    if chosen not in FIX_FORMATS:
        raise Failure(
            f"the output format must be one of {', '.join(FIX_FORMATS)} (from the "
            f"suffix or --format), not {chosen or 'none'}",
            EXIT_USAGE,
        )
    from mesh_normal.analysis import flips_by_component, weld_summary
    from mesh_normal.files import MeshFileError
    from mesh_normal.files.write import write_fixed
    from mesh_normal.orientation import orient

    mesh, _ = load(args.input, progress)
    progress.step("making the winding consistent and outward")
    fixed = orient(mesh.checked(), weld=args.weld)
    weld = weld_summary(mesh.vertices, args.weld)
    progress.step(f"writing {args.output}")
    try:
        data, dropped = write_fixed(mesh, fixed.faces, chosen)
    except MeshFileError as error:
        raise Failure(f"cannot write {args.output}: {error}", EXIT_OUTPUT) from None
    write(args.output, data)
    progress.done()
    if dropped:  # do no harm: never leave data out without saying so
        print(f"mesh-normal: {args.output} leaves out {'; '.join(dropped)}", file=sys.stderr)
    flipped = int(fixed.flipped.sum())
    parts = flips_by_component(fixed) or "none"
    print(
        f"flipped {flipped:,} of {len(mesh.faces):,} faces (component:faces {parts}); "
        f"orientation before: {fixed.orientation}"
    )
    if weld is not None:
        print(weld_line(weld))
    return EXIT_OK


SERVE_HINT = (
    "The web app is not part of the mesh-normal package: from a checkout of the "
    "project, run `make run` (or `uvicorn app.main:app`)."
)


def serve(_args: argparse.Namespace, _progress: Progress) -> int:
    """Say how to start the web app, which the package does not hold."""
    print(f"mesh-normal: {SERVE_HINT}", file=sys.stderr)
    return EXIT_USAGE


class Choices(Collection[str]):
    """An argument's choices named by the module that defines them, imported on first use.

    ``mesh-normal --help`` never looks at a subcommand's choices (given a ``metavar``), so it
    does not import the module (and numba behind it); ``mesh-normal normals --help`` and
    parsing do.
    """

    def __init__(self, module: str, name: str) -> None:
        self.module, self.name = module, name

    def values(self) -> tuple[str, ...]:
        return tuple(getattr(importlib.import_module(self.module), self.name))

    def __contains__(self, value: object) -> bool:
        return value in self.values()

    def __iter__(self) -> Iterator[str]:
        return iter(self.values())

    def __len__(self) -> int:
        return len(self.values())


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
        choices=Choices("mesh_normal.exports", "KINDS"),
        default="vertex",
        metavar="KIND",
        help="%(choices)s (default: %(default)s)",
    )
    normals_parser.add_argument(
        "--weighting",
        choices=Choices("mesh_normal.vertices", "WEIGHTINGS"),
        default="angle",
        metavar="WEIGHTING",
        help="of vertex normals: %(choices)s (default: %(default)s)",
    )
    normals_parser.add_argument("--crease-angle", type=float, default=30.0, metavar="DEGREES")
    normals_parser.add_argument(
        "-o",
        "--output",
        required=True,
        help="OUT.npy (float64), OUT.csv, OUT.json or OUT.ply (face/vertex)",
    )
    normals_parser.set_defaults(run=normals)

    fix_parser = commands.add_parser("fix", help="write the mesh with consistent, outward winding")
    fix_parser.add_argument("input")
    fix_parser.add_argument("output", help=f"OUT.{', OUT.'.join(FIX_FORMATS)}")
    fix_parser.add_argument("--format", choices=FIX_FORMATS)
    add_weld(fix_parser)
    fix_parser.set_defaults(run=fix)

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
    try:
        return int(args.run(args, progress))
    except Failure as failure:
        if enabled:
            sys.stderr.write("\n")
        print(f"mesh-normal: {failure}", file=sys.stderr)
        return failure.code


if __name__ == "__main__":
    sys.exit(main())
