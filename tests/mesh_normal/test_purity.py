"""The library stays free of web imports: no fastapi, starlette, jinja2 or plotly (but in the
notebook package, whose ``mn.show`` imports Plotly when it is called: the ``show`` extra)."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import ROOT

CORE = ROOT / "mesh_normal"
FORBIDDEN = frozenset({"fastapi", "starlette", "jinja2", "plotly", "app"})
#: The one package that may import Plotly, inside the function that draws.
NOTEBOOK = CORE / "notebook"


def core_modules() -> list[str]:
    names = []
    for path in sorted(CORE.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names.append(".".join(parts))
    return names


def imported_top_level_names(source: str) -> set[str]:
    """Top-level package of every import statement, anywhere in the file."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute | ast.Name)
            and getattr(node.func, "attr", getattr(node.func, "id", None))
            in ("import_module", "__import__")
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            names.add(node.args[0].value.split(".")[0])
    return names


def test_the_core_modules_are_found() -> None:
    modules = core_modules()
    for expected in (
        "mesh_normal",
        "mesh_normal.triangle.exact",
        "mesh_normal.triangle.normal",
        "mesh_normal.triangle.batch",
        "mesh_normal.tolerances",
        "mesh_normal.files",
        "mesh_normal.mesh.report.models",
        "mesh_normal.mesh.report.analysis",
        "mesh_normal.cli",
    ):
        assert expected in modules


def test_importing_the_core_loads_no_web_package() -> None:
    modules = core_modules()
    script = (
        "import importlib, json, sys\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
        "print(json.dumps(sorted(sys.modules)))\n"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    loaded = set(json.loads(completed.stdout))
    assert set(modules) <= loaded  # every core module really was imported
    assert "numpy" in loaded
    leaked = {name for name in loaded if name.split(".")[0] in FORBIDDEN}
    assert not leaked, sorted(leaked)


@pytest.mark.parametrize("path", sorted(CORE.rglob("*.py")), ids=lambda p: p.name)
def test_no_core_file_imports_a_web_package(path: Path) -> None:
    names = imported_top_level_names(path.read_text(encoding="utf-8"))
    forbidden = FORBIDDEN - {"plotly"} if path.is_relative_to(NOTEBOOK) else FORBIDDEN
    assert not names & forbidden, (path, sorted(names & forbidden))


@pytest.mark.parametrize(
    "source",
    [
        "import fastapi",
        "import numpy, jinja2.ext",
        "from starlette.responses import Response",
        "from app.web.errors import ApiError",
        "def f():\n    import plotly.graph_objects as go\n",
        "import importlib\nimportlib.import_module('plotly')",
        "__import__('fastapi')",
    ],
)
def test_the_static_check_catches_web_imports(source: str) -> None:
    assert imported_top_level_names(source) & FORBIDDEN


def test_the_static_check_allows_the_standard_library_and_numpy() -> None:
    source = "import math\nfrom fractions import Fraction\nimport numpy as np\nfrom . import x\n"
    assert imported_top_level_names(source) == {"math", "fractions", "numpy"}
