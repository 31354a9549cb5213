"""Where the tests find the checkout and its sample files."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
TEMPLATES = ROOT / "templates"
STATIC = ROOT / "static"
