"""The `mesh-normal` command line (being built)."""

from __future__ import annotations


def main(argv: list[str] | None = None) -> int:
    raise SystemExit("mesh-normal: not built yet")
