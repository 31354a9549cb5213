"""``mesh-normal batch``: the command's options, its progress bar and its summary.

Kept apart from :mod:`mesh_normal.cli`, which imports this module only to add the command's
options (standard library only here, so ``--help`` stays quick).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from mesh_normal.datasets.driver import BatchProgress, BatchResult

EXIT_OK, EXIT_USAGE, EXIT_INTERRUPTED = 0, 2, 130
#: The slowest files the summary names.
SLOWEST = 5
#: Without a terminal, a progress line every this many seconds at most.
LINE_SECONDS = 10.0

DESCRIPTION = (
    "Report on every mesh (or, with --points, point cloud) of the inputs, one row a file in "
    "DIR/report.parquet: status (ok, problems, unreadable, too_large, timed_out), figures and "
    "problems. Runs on every core, or on a Dask cluster with --scheduler. Run it again to "
    "finish an interrupted batch: files already in the table (same path, size and hash) are "
    "not run again."
)


def add_batch(commands: Any) -> None:
    """The ``batch`` command and its options, on the ``mesh-normal`` parser's subparsers."""
    command = commands.add_parser(
        "batch",
        help="report on every file of folders, globs or URLs, as a Parquet table",
        description=DESCRIPTION,
        epilog="Exit codes: 0 the batch ran (even with problem files), 2 usage, 130 "
        "interrupted (the finished rows are kept).",
    )
    command.add_argument(
        "inputs",
        nargs="+",
        metavar="INPUT",
        help="files, folders (recursive), glob patterns ('**/*.stl', quoted) or fsspec URLs "
        "(s3://, gs://, memory://, with the fsspec package for them)",
    )
    command.add_argument("--out", required=True, metavar="DIR", help="the table and outputs")
    command.add_argument(
        "--normals",
        choices=("face", "vertex", "corner"),
        help="write each mesh's normals to DIR/normals/ (with --points: the points' normals)",
    )
    command.add_argument(
        "--format",
        dest="normals_format",
        choices=("npy", "ply"),
        default="npy",
        help="of the normals: npy ((n, 3) float64; corner (m, 3, 3)) or ply (the mesh with "
        "them; face or vertex) (default: %(default)s)",
    )
    command.add_argument(
        "--fix",
        action="store_true",
        help="write the meshes the fix changes (consistent, outward winding) to DIR/fixed/",
    )
    command.add_argument("--points", action="store_true", help="read the inputs as point clouds")
    command.add_argument(
        "--timeout",
        type=_positive_or_none,
        default=60.0,
        metavar="S",
        help="seconds one file may take before it is a timed_out row; 0: none "
        "(default: %(default)s)",
    )
    command.add_argument(
        "--max-file-mb",
        type=_positive_or_none,
        metavar="N",
        help="files larger are too_large rows, never read (default: no limit)",
    )
    command.add_argument(
        "--memory-mb",
        type=_positive_or_none,
        metavar="N",
        help="memory a worker may take for one file beyond its start; a file that needs "
        "more is a too_large row (default: no limit)",
    )
    command.add_argument(
        "--workers",
        type=_workers,
        metavar="N",
        help="local worker processes (default: one a core)",
    )
    command.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="run on a Dask cluster, e.g. tcp://HOST:8786 (default: $DASK_SCHEDULER_ADDRESS, "
        "else this machine)",
    )
    command.add_argument(
        "--flush-rows",
        type=_workers,
        default=200,
        metavar="N",
        help="keep the finished rows (DIR/.parts/) every N files, or every 5 s "
        "(default: %(default)s)",
    )
    command.add_argument("--json", action="store_true", help="the summary as JSON")
    command.set_defaults(run=run)


def _positive_or_none(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, not {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a number of 0 or more, not {text!r}")
    return value or None


def _workers(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number of 1 or more, not {text!r}")
    return int(text)


def run(args: argparse.Namespace, progress: Any) -> int:
    """Run the batch; print the summary on stdout (``--json``: as JSON)."""
    from mesh_normal.datasets.driver import batch_options, run_batch
    from mesh_normal.datasets.inputs import InputError

    bar = Bar(sys.stderr, terminal=bool(progress.enabled))
    try:
        options = batch_options(
            out=args.out,
            normals=args.normals,
            normals_format=args.normals_format,
            fix=args.fix,
            points=args.points,
            timeout=args.timeout,
            max_file_mb=args.max_file_mb,
            memory_mb=args.memory_mb,
        )
        result = run_batch(
            args.inputs,
            options,
            scheduler=args.scheduler,
            workers=args.workers,
            progress=bar,
            flush_rows=args.flush_rows,
        )
    except (InputError, ValueError) as error:
        bar.end()
        print(f"mesh-normal batch: {error}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        bar.end()
        print(
            f"mesh-normal batch: interrupted after {bar.done} of {bar.total} files; the "
            "finished rows are kept: run the same command again to finish.",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    bar.end()
    found = summary(result)
    if args.json:
        print(json.dumps(found, indent=2, allow_nan=False))
    else:
        print(summary_text(found))
    return EXIT_OK


class Bar:
    """The progress: a bar redrawn on a terminal, else a line now and then (on stderr)."""

    def __init__(self, stream: TextIO, terminal: bool) -> None:
        self.stream, self.terminal = stream, terminal
        self.done = self.total = 0
        self.last_line = time.monotonic()
        self.drawn = False

    def __call__(self, state: BatchProgress) -> None:
        self.done, self.total = state.done, state.total
        if self.terminal:
            self.stream.write(f"\r\033[K{progress_line(state)}")
            self.stream.flush()
            self.drawn = True
        elif state.row is not None and (
            time.monotonic() - self.last_line >= LINE_SECONDS or state.done == state.total
        ):
            self.last_line = time.monotonic()
            print(progress_line(state), file=self.stream, flush=True)

    def end(self) -> None:
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
            self.drawn = False


def progress_line(state: BatchProgress) -> str:
    """``120/1,000 files (12%) · 9.8 files/s · 3 failed · 1 m 30 s left``."""
    run = state.done - state.reused
    rate = run / state.elapsed if state.elapsed > 0 else 0.0
    share = 100 * state.done // state.total if state.total else 100
    left = (state.total - state.done) / rate if rate else None
    parts = [
        f"{state.done:,}/{state.total:,} files ({share}%)",
        f"{rate:.1f} files/s",
        f"{state.failures:,} failed",
    ]
    if left is not None and state.done < state.total:
        parts.append(f"{duration(left)} left")
    return " · ".join(parts)


def duration(seconds: float) -> str:
    """``42 s``, ``3 m 05 s``, ``2 h 10 m``."""
    whole = round(seconds)
    if whole < 60:
        return f"{whole} s"
    if whole < 3600:
        return f"{whole // 60} m {whole % 60:02d} s"
    return f"{whole // 3600} h {whole % 3600 // 60:02d} m"


def summary(result: BatchResult) -> dict[str, Any]:
    """The summary a script reads (``--json``): counts by status and by problem, the slowest
    files, what was skipped or kept, where the table is."""
    from mesh_normal.datasets.schema import STATUSES

    rows = result.table.select(["path", "status", "problems_found", "wall_seconds"]).to_pylist()
    statuses = Counter(row["status"] for row in rows)
    problems = Counter(code for row in rows for code in row["problems_found"])
    slowest = sorted(rows, key=lambda row: -row["wall_seconds"])[:SLOWEST]
    run = len(rows) - result.reused
    return {
        "files": len(rows),
        "by_status": {status: statuses.get(status, 0) for status in STATUSES},
        "by_problem": dict(sorted(problems.items(), key=lambda item: (-item[1], item[0]))),
        "slowest": [
            {"path": row["path"], "seconds": round(row["wall_seconds"], 4), "status": row["status"]}
            for row in slowest
        ],
        "run": run,
        "reused": result.reused,
        "skipped": result.skipped,
        "seconds": round(result.seconds, 3),
        "files_per_second": round(run / result.seconds, 2) if result.seconds > 0 else None,
        "engine": result.engine,
        "report": result.report,
    }


def summary_text(found: dict[str, Any]) -> str:
    """The summary for a person."""
    kept = f"; {found['reused']:,} kept from an earlier run" if found["reused"] else ""
    skipped = f"; {found['skipped']:,} other files skipped" if found["skipped"] else ""
    rate = found["files_per_second"]
    speed = f", {rate:,} files/s" if rate and found["run"] else ""
    lines = [
        f"{found['files']:,} files: {found['run']:,} run in {duration(found['seconds'])}"
        f"{speed} ({found['engine']}){kept}{skipped}",
        "by status: " + ", ".join(f"{name} {n:,}" for name, n in found["by_status"].items()),
    ]
    if found["by_problem"]:
        counts = ", ".join(f"{code} {n:,}" for code, n in found["by_problem"].items())
        lines.append(f"by problem: {counts}")
    if found["slowest"]:
        slow = ", ".join(f"{item['path']} {item['seconds']:.2f} s" for item in found["slowest"])
        lines.append(f"slowest: {slow}")
    lines.append(f"wrote {found['report']}")
    return "\n".join(lines)
