"""The benchmarks' tables: printed, and with ``--markdown PATH`` also written for the docs.

Each benchmark prints its Markdown tables through a :class:`Report`. Given ``--markdown PATH``
(``make bench`` passes ``docs/benchmarks/NAME.md``, which ``docs/benchmarks.md`` includes), it
writes them to that file after one line that states the date, the machine, its load and the
command, so that a table is never read without them.
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
from datetime import UTC, datetime
from pathlib import Path


def add_option(parser: argparse.ArgumentParser) -> None:
    """``--markdown PATH``: also write the tables there, the machine and the date first."""
    parser.add_argument(
        "--markdown",
        metavar="PATH",
        help="also write the tables to this file, after a line naming the machine and the date",
    )


def machine() -> str:
    """The cores, the processor and the memory: "2 cores (AMD EPYC) with 7.8 GiB"."""
    model = platform.processor() or platform.machine()
    memory = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
        total = Path("/proc/meminfo").read_text().split()[1]  # "MemTotal: N kB"
        memory = f" with {int(total) / 2**20:.1f} GiB"
    except (OSError, IndexError, ValueError):
        pass
    return f"{os.cpu_count()} cores ({model}){memory}"


def command() -> str:
    """The command that ran this benchmark, without its ``--markdown PATH``."""
    words, skip = [], False
    for word in sys.argv[1:]:
        if skip or word == "--markdown":
            skip = not skip
            continue
        if not word.startswith("--markdown="):
            words.append(word)
    module = f"benchmarks.{Path(sys.argv[0]).stem}"
    return shlex.join(["python", "-m", module, *words])


class Report:
    """The Markdown a benchmark prints, kept to be written to ``path`` (when given) at the end."""

    def __init__(self, path: str | None) -> None:
        self.path = Path(path) if path else None
        self.lines: list[str] = []
        self.started = datetime.now(UTC)
        self.load = os.getloadavg()[0]

    def print(self, text: str = "") -> None:
        """Print ``text`` (one or more lines of Markdown) and keep it for the file."""
        print(text, flush=True)
        self.lines.append(text)

    def heading(self) -> str:
        day = self.started
        return (
            f"Measured on {day.day} {day:%B %Y} ({day:%H:%M} UTC) on {machine()}, load average "
            f"{self.load:.2f} before and {os.getloadavg()[0]:.2f} after, by `{command()}`."
        )

    def write(self) -> None:
        """Write the kept Markdown to the file, after the line naming the machine and date."""
        if self.path is None:
            return
        body = "\n".join(self.lines).strip("\n")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text(f"{self.heading()}\n\n{body}\n")
        print(f"wrote {self.path}", file=sys.stderr)
