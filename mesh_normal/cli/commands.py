"""The command line's parser and ``main``: which command runs, with which arguments."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from typing import get_args

from mesh_normal import __version__
from mesh_normal.choices import NormalsChoice, NormalsKind, OrientMode, Weighting, Winding
from mesh_normal.cli.common import EXIT_USAGE, Failure, Progress
from mesh_normal.cli.mesh import FIX_FORMATS, NORMAL_SUFFIXES, analyze, export, fix, normals
from mesh_normal.cli.points import ALL, points
from mesh_normal.files.formats import SUFFIXES
from mesh_normal.tolerances import ORIENT_MAX_ANGLE, WELD_LIMIT


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


def neighbour_count(text: str) -> int:
    """``--k``: a whole number, at least 3 (the point and two neighbours), or ``all`` (ALL)."""
    if text.strip().lower() == "all":
        return ALL
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
        "OUT.ply (face, vertex), OUT.off (vertex), OUT.stl (face): the mesh with them; "
        "- for standard output (npy unless --format says otherwise)",
    )
    normals_parser.add_argument(
        "--format",
        choices=(*(suffix.lstrip(".") for suffix in NORMAL_SUFFIXES), *FIX_FORMATS),
        metavar="FORMAT",
        help="%(choices)s: what to write, where the output's suffix does not say (-)",
    )
    normals_parser.add_argument(
        "--force", action="store_true", help="allow OUT to be the input file"
    )
    normals_parser.set_defaults(run=normals, weld=None)

    fix_parser = commands.add_parser(
        "fix",
        help="write the mesh with consistent, outward winding",
        description="Write the mesh with consistent, outward winding, keeping what the "
        "output's format holds (colours, groups, normals recomputed) and naming what it "
        "cannot. When no face needs flipping, OUT is the mesh as it was (the input's own "
        "bytes, in its own format). Never over the input without --force; another existing "
        "OUT is replaced, as cp does; - writes to standard output (with --format).",
    )
    add_output(fix_parser)
    # Accepted so that older scripts still run: fix always writes OUT now.
    fix_parser.add_argument("--write-unchanged", action="store_true", help=argparse.SUPPRESS)
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
    export_parser.set_defaults(run=export)

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
        "(n, 3) float64 normals); points without a normal get zeros; - for standard output "
        "(npy unless --format says otherwise). Default: a summary",
    )
    points_parser.add_argument(
        "--format",
        choices=("ply", "xyz", "csv", "npy"),
        metavar="FORMAT",
        help="%(choices)s: what -o writes, where its suffix does not say (-)",
    )
    points_parser.add_argument(
        "--k",
        type=neighbour_count,
        default=None,
        metavar="K",
        help="the neighbourhood's size, the point included (default: each point's own, from "
        "12 to 96, chosen from the noise and curvature); with --radius at most K within it, "
        "or all",
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
