"""The ``points`` command: a point cloud's normals, as a file or a summary."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mesh_normal.choices import OrientMode
from mesh_normal.cli.common import (
    EXIT_OK,
    EXIT_USAGE,
    STDOUT,
    Failure,
    Progress,
    count,
    output_form,
    parsed,
    read_input,
    same_file,
    tell,
    where,
    write,
)

if TYPE_CHECKING:
    from mesh_normal.points import PointCloud, PointNormals

#: ``mesh-normal points -o``: the suffix and what it writes (``write_points``' format or npy).
POINT_OUTPUTS = {".ply": "ply", ".xyz": "xyz", ".csv": "csv", ".npy": "npy"}
#: Components listed by name in the text summary, and in the JSON one.
LISTED_COMPONENTS, JSON_COMPONENTS = 5, 100
#: ``--k all`` (every point within --radius); None, the default, is the adaptive scale.
ALL = 0
#: Why a point has no normal, or no side, in a few words (``PointStatus`` by name).
STATUS_WORDS = {
    "ok": "a unit normal, oriented as asked",
    "not_finite": "a coordinate is NaN or infinite",
    "too_few_neighbours": "fewer than three points in the neighbourhood, itself included",
    "duplicates": "the neighbourhood's points coincide",
    "collinear": "the neighbourhood's points lie on a line",
    "ambiguous": "two directions are equally flat (a symmetric corner)",
    "unoriented": "a unit normal whose side could not be decided",
    "sharp": "a unit normal near a sharp edge, of the side the point lies on",
}


def points(args: argparse.Namespace, progress: Progress) -> int:
    """Normals of a point cloud: a file of them with ``-o``, else a summary on stdout."""
    output_format = point_output(args.file, args.output, args.format)
    if args.json and args.output == STDOUT:
        raise Failure("--json and -o - would both write to standard output; give one", EXIT_USAGE)
    if args.k == ALL and args.radius is None:
        raise Failure("--k all needs --radius", EXIT_USAGE)
    k = None if args.k == ALL else args.k
    from mesh_normal.points import point_normals

    cloud = load_points(args.file, progress)
    orient, references = point_references(args, cloud)
    bar = PointsBar(progress, orient)
    try:
        result = point_normals(
            cloud.points,
            k=k,
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
        progress.step(f"writing {where(args.output)}")
        write(args.output, point_bytes(cloud, result, output_format))
    progress.done()
    if args.json:  # allow_nan=False: never NaN
        print(json.dumps(found, indent=2, allow_nan=False))
    elif args.output is not None:
        tell(written_line(found, args.output, output_format or "npy"), args.output)
    else:
        print(points_text(found))
    return EXIT_OK


def point_output(source: str, output: str | None, given: str | None) -> str | None:
    """What ``-o`` writes: ``--format``, else its suffix, else npy for standard output;
    refuses another suffix, a suffix and ``--format`` that disagree, and the input's own
    path."""
    if output is None:
        if given is not None:
            raise Failure("--format is only used with -o", EXIT_USAGE)
        return None
    chosen = output_form(output, given, POINT_OUTPUTS)
    if same_file(output, source):
        raise Failure(f"{output} is the input file; write the normals to another file", EXIT_USAGE)
    return chosen


def load_points(path: str, progress: Progress) -> PointCloud:
    from mesh_normal.points import read_points

    data = read_input(path, progress)
    return parsed(path, lambda: read_points(data, Path(path).name))


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

        from mesh_normal.files.normals import npy_bytes

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
        "neighbourhood": {"k": None if args.k == ALL else args.k, "radius": args.radius},
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

    from mesh_normal.mesh.report.stored_normals import unit_rows

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
    if k is None and radius is None:
        return "each point's own scale, chosen from the data"
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


def written_line(found: dict[str, Any], output: str, output_format: str) -> str:
    """What ``-o`` wrote, and what in it is not a normal oriented as asked."""
    npy = output_format == "npy"
    rows = found["file_points"] if npy else found["points"]
    line = f"wrote {count(rows, 'normal')} to {where(output, output_format)}"
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
    if left_out and npy:
        rows_left = (
            "row the file left out is a zero row"
            if left_out == 1
            else ("rows the file left out are zero rows")
        )
        line += f"; {left_out:,} {rows_left} too"
    return line + ("; see `mesh-normal points FILE`" if missing or unoriented else "")
