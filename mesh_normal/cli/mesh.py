"""The mesh commands: ``analyze``, ``normals``, ``fix`` and ``export``."""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, cast

from mesh_normal.cli.common import (
    EXIT_OK,
    EXIT_OUTPUT,
    EXIT_PROBLEMS,
    EXIT_USAGE,
    STDOUT,
    Failure,
    Progress,
    count,
    load,
    output_form,
    read_input,
    same_file,
    tell,
    where,
    write,
)
from mesh_normal.files.formats import WRITABLE

if TYPE_CHECKING:
    from mesh_normal.mesh.report.models import MeshReport, Weld

NORMAL_SUFFIXES = (".npy", ".csv", ".json")
FIX_FORMATS = WRITABLE


def analyze(args: argparse.Namespace, progress: Progress) -> int:
    from mesh_normal.mesh.report.analysis import analyse_mesh, build_report

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


#: The page's button in the report's advice ("Download the fixed mesh", with a note in brackets
#: or not), and the same advice as a terminal reads it: the command is printed below it.
PAGE_ADVICE = re.compile(r"Download the fixed mesh( \([^)]*\))?")


def terminal_words(text: str) -> str:
    """A report sentence written for the page, in the terminal's words."""
    return PAGE_ADVICE.sub(
        lambda found: f"Write the fixed mesh{found.group(1) or ''} with the command below", text
    )


def weld_line(weld: Weld) -> str:
    """The weld in words: ``weld 1e-06 of the diagonal (2.7e-06): 34 vertices joined``."""
    distance = "beyond the double range" if weld.distance is None else f"{weld.distance:.3g}"
    joined = weld.joined_vertices
    return (
        f"weld {weld.tolerance!r} of the diagonal ({distance}): {joined:,} "
        f"{'vertex' if joined == 1 else 'vertices'} joined beyond exact equality"
    )


def normals(args: argparse.Namespace, progress: Progress) -> int:
    chosen = normals_format(args.output, args.format)
    if chosen in FIX_FORMATS:  # the mesh itself, with the normals in it
        from mesh_normal.files.formats import FORMATS, HOLDS_NORMALS

        held = HOLDS_NORMALS.get(chosen, ())
        if args.kind not in held:
            holds = f"only {' and '.join(held)} normals" if held else "no normals"
            raise Failure(
                f"{args.kind} normals do not fit in a {FORMATS[chosen].title} file, which holds "
                f"{holds}; use .obj or .glb (any kind), or .npy, .csv, .json",
                EXIT_USAGE,
            )
        args.input, args.format, args.normals, args.winding = args.file, chosen, args.kind, "keep"
        return export(args, progress)
    from mesh_normal.files.normals import NormalsFormat, normals_file, normals_to_write

    if same_file(args.output, args.file):
        raise Failure(f"{args.output} is the input file; write the normals to another file", 2)
    mesh, _ = load(args.file, progress)
    progress.step(f"computing {args.kind} normals")
    values, missing = normals_to_write(mesh, args.kind, args.weighting, args.crease_angle)
    progress.step(f"writing {where(args.output)}")
    # the same files as POST /api/mesh/normals
    data = normals_file(
        values, missing, args.kind, args.weighting, args.crease_angle, cast(NormalsFormat, chosen)
    )
    write(args.output, data)
    progress.done()
    line = f"wrote {count(len(values), f'{args.kind} normal')} to {where(args.output, chosen)}"
    zero = int(missing.sum())
    if zero:
        are = "is a zero row" if zero == 1 else "are zero rows"
        line += f"; {count(zero, 'of them', 'of them')} {are} (degenerate or unused faces)"
    tell(line + ("; see `mesh-normal analyze`" if zero else ""), args.output)
    return EXIT_OK


def normals_format(output: str, given: str | None) -> str:
    """What ``normals -o OUTPUT`` writes: the normals alone, or the mesh with them."""
    suffixes = {
        **{suffix: suffix.lstrip(".") for suffix in NORMAL_SUFFIXES},
        **{f".{name}": name for name in FIX_FORMATS},
    }
    return output_form(output, given, suffixes)


def fix(args: argparse.Namespace, progress: Progress) -> int:
    """Write the mesh with consistent, outward winding (as it was when nothing needs it)."""
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
    from mesh_normal.files import MeshFileError
    from mesh_normal.files.rewrite import export_mesh
    from mesh_normal.mesh.report.analysis import flips_by_component, weld_summary

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
        raise Failure(f"cannot write {where(args.output)}: {error}", EXIT_OUTPUT) from None
    faces, shown = len(mesh.faces), where(args.output, chosen)
    # Nothing to flip, in the input's own format, normals as stored: the input's bytes are that
    # mesh exactly, with all it holds (texture coordinates, materials, comments included).
    as_it_was = (
        args.command == "fix"
        and not result.faces_flipped
        and chosen == mesh.format
        and args.normals == "auto"
    )
    progress.step(f"writing {shown}")
    write(args.output, read_input(args.input, progress) if as_it_was else result.data)
    progress.done()
    if result.dropped and not as_it_was:  # do no harm: never leave data out without saying so
        print(f"mesh-normal: {shown} leaves out {'; '.join(result.dropped)}", file=sys.stderr)
    kept = f"; kept {', '.join(result.kept)}" if result.kept and not as_it_was else ""
    if result.orientation is not None and not result.faces_flipped and args.command == "fix":
        again = "the input as it was" if as_it_was else "the same faces"
        tell(
            f"wrote {shown}: {again}, since none of the {count(faces, 'face')} needs "
            f"flipping (orientation {result.orientation.orientation}){kept}",
            args.output,
        )
    elif result.orientation is not None:
        parts = flips_by_component(result.orientation)
        within = f" (component:faces {parts})" if parts else ""
        tell(
            f"wrote {shown}: flipped {result.faces_flipped:,} of {count(faces, 'face')}"
            f"{within}; orientation before: {result.orientation.orientation}{kept}",
            args.output,
        )
    else:
        done = "every face flipped" if args.winding == "flip" else "winding as it was"
        tell(f"wrote {shown}: {count(faces, 'face')}, {done}{kept}", args.output)
    weld = weld_summary(mesh.vertices, args.weld)
    if weld is not None:
        tell(weld_line(weld), args.output)
    return EXIT_OK


def output_format(output: str, given: str | None) -> str:
    """The mesh format ``--format`` or the output's suffix names; a usage failure otherwise."""
    if output == STDOUT and given is None:
        raise Failure(
            f"writing the mesh to standard output (-) needs --format, one of "
            f"{', '.join(FIX_FORMATS)}",
            EXIT_USAGE,
        )
    chosen = given or Path(output).suffix.lower().lstrip(".")
    if chosen not in FIX_FORMATS:
        raise Failure(
            f"the output format must be one of {', '.join(FIX_FORMATS)} (from the "
            f"suffix or --format), not {chosen or 'none'}",
            EXIT_USAGE,
        )
    return chosen
