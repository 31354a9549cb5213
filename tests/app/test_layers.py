"""The house's rules, read from the source with ``ast``: no import circle, each room apart.

Every import statement counts, including ones inside functions and under ``TYPE_CHECKING``
(an import hidden in a function is still a dependency, and hiding one is how circles creep
back). The rules:

- no cycle among the modules of ``app`` and ``mesh_normal``;
- ``app.calculator`` never imports ``app.mesh``, nor ``app.mesh`` ``app.calculator``;
- ``app.web`` (the plumbing) imports no feature;
- ``mesh_normal`` (the library) imports nothing from ``app``;
- in ``mesh_normal``, only the entry points (the command line, a worker process's main)
  import the command line and the process-wide settings (``mesh_normal.allocator``): the
  geometry, the readers and the reports change nothing in the process that imports them;
- the library's layers, bottom up: the shared words (``types``, ``choices``, ``tolerances``,
  ``record``) import no other module of the library; the geometry (``mesh_normal.triangle``,
  ``mesh_normal.mesh`` but its ``report``) imports only the shared words and itself; the files
  (``mesh_normal.files``) import neither the reports, the point clouds nor the datasets.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping
from pathlib import Path

from tests.paths import ROOT

PACKAGES = ("app", "mesh_normal")
FEATURES = ("app.calculator", "app.mesh", "app.points")
#: What only an entry point may import, and the library's entry points.
RUNTIME = ("mesh_normal.cli", "mesh_normal.allocator")
ENTRY_POINTS = ("mesh_normal.cli", "mesh_normal.__main__", "mesh_normal.workers")
SHARED = (
    "mesh_normal._lazy",
    "mesh_normal.choices",
    "mesh_normal.record",
    "mesh_normal.tolerances",
    "mesh_normal.types",
)
GEOMETRY = ("mesh_normal.triangle", "mesh_normal.mesh")
REPORTS = "mesh_normal.mesh.report"
#: What the files may not import: what is built on them.
ABOVE_FILES = (REPORTS, "mesh_normal.points", "mesh_normal.datasets")
Graph = Mapping[str, set[str]]


def module_name(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(tree: ast.AST, module: str, is_package: bool) -> set[str]:
    """Every module named by an import anywhere in ``tree`` (relative ones resolved)."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = module.split(".")
                anchor = anchor[: len(anchor) - node.level + (1 if is_package else 0)]
                base = ".".join([*anchor, *([base] if base else [])])
            names.add(base)
            # ``from app.mesh import view`` imports the module app.mesh.view.
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def build_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the project modules it imports."""
    sources = {
        module_name(path, root): path
        for package in PACKAGES
        for path in sorted((root / package).rglob("*.py"))
    }
    graph: dict[str, set[str]] = {}
    for module, path in sources.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        found = imported(tree, module, path.name == "__init__.py")
        graph[module] = {name for name in found if name in sources and name != module}
    return graph


def find_cycle(graph: Graph) -> list[str] | None:
    """One import cycle as ``[a, b, ..., a]``, or None (depth-first search, three colours)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == 1:
                return [*path[path.index(target) :], target]
            if target not in state and (cycle := visit(target)):
                return cycle
        path.pop()
        state[node] = 2
        return None

    for start in sorted(graph):
        if start not in state and (cycle := visit(start)):
            return cycle
    return None


def within(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def is_geometry(module: str) -> bool:
    return any(within(module, package) for package in GEOMETRY) and not within(module, REPORTS)


def violations(graph: Graph) -> list[str]:
    """Every import that crosses a wall between rooms, as ``importer -> imported``."""
    found = []
    for module, targets in graph.items():
        for target in targets:
            crossing = (
                any(
                    within(module, room) and within(target, other)
                    for room in FEATURES
                    for other in FEATURES
                    if room != other
                )
                or (within(module, "app.web") and any(within(target, f) for f in FEATURES))
                or (within(module, "mesh_normal") and within(target, "app"))
                or (
                    within(module, "mesh_normal")
                    and not any(within(module, entry) for entry in ENTRY_POINTS)
                    and any(within(target, runtime) for runtime in RUNTIME)
                )
                or (module in SHARED and target not in SHARED)
                or (is_geometry(module) and not (is_geometry(target) or target in SHARED))
                or (
                    within(module, "mesh_normal.files")
                    and any(within(target, above) for above in ABOVE_FILES)
                )
            )
            if crossing:
                found.append(f"{module} -> {target}")
    return sorted(found)


def edges(pairs: Iterable[tuple[str, str]]) -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for source, target in pairs:
        graph.setdefault(source, set()).add(target)
        graph.setdefault(target, set())
    return graph


# --- The rules, over the real code --------------------------------------------------------------

GRAPH = build_graph()


def test_the_graph_sees_every_module_and_late_imports() -> None:
    seen = {"app.main", "app.web.errors", "app.calculator.steps", "mesh_normal.triangle.normal"}
    assert seen <= set(GRAPH)
    assert "app.calculator.pages" in GRAPH["app.main"]  # ``from app.calculator import pages``
    assert "mesh_normal.triangle.normal" in GRAPH["app.calculator.steps"]


def test_no_import_cycle() -> None:
    cycle = find_cycle(GRAPH)
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_no_room_imports_another() -> None:
    assert violations(GRAPH) == []


# --- The checker, on tiny graphs it must judge right ------------------------------------------


def test_a_planted_cycle_is_found_and_reported() -> None:
    graph = edges([("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")])
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle(edges([("x", "x")])) == ["x", "x"]


def test_a_tree_and_a_diamond_have_no_cycle() -> None:
    assert find_cycle(edges([("a", "b"), ("a", "c"), ("b", "d"), ("c", "d")])) is None


def test_crossings_are_named() -> None:
    graph = edges(
        [
            ("app.mesh.view", "app.calculator.view3d"),
            ("app.web.errors", "app.calculator.pages"),
            ("mesh_normal.mesh.report.models", "app.web.formatting"),
            ("mesh_normal.mesh.faces", "mesh_normal.allocator"),
            ("mesh_normal.files.read", "mesh_normal.cli"),
            ("mesh_normal.cli.mesh", "mesh_normal.allocator"),  # allowed: an entry point
            ("mesh_normal.cli.points", "mesh_normal.cli.common"),  # allowed: within the CLI
            ("mesh_normal.mesh.topology", "mesh_normal.cli.common"),
            ("mesh_normal.mesh.faces", "mesh_normal.files.read"),
            ("mesh_normal.triangle.normal", "mesh_normal.mesh.report.models"),
            ("mesh_normal.mesh.faces", "mesh_normal.tolerances"),  # allowed: shared words
            ("mesh_normal.mesh.report.analysis", "mesh_normal.files"),  # allowed: reports read
            ("mesh_normal.files.loaded", "mesh_normal.mesh.report.models"),
            ("mesh_normal.files.write", "mesh_normal.mesh.faces"),  # allowed: files use geometry
            ("mesh_normal.choices", "mesh_normal.mesh.faces"),
            ("app.mesh.work", "mesh_normal.allocator"),  # allowed: a worker's job
            ("app.calculator.pages", "app.web.templating"),  # allowed: features use the plumbing
            ("app.main", "app.mesh.page"),  # allowed: the app builds every room
        ]
    )
    assert violations(graph) == [
        "app.mesh.view -> app.calculator.view3d",
        "app.web.errors -> app.calculator.pages",
        "mesh_normal.choices -> mesh_normal.mesh.faces",
        "mesh_normal.files.loaded -> mesh_normal.mesh.report.models",
        "mesh_normal.files.read -> mesh_normal.cli",
        "mesh_normal.mesh.faces -> mesh_normal.allocator",
        "mesh_normal.mesh.faces -> mesh_normal.files.read",
        "mesh_normal.mesh.report.models -> app.web.formatting",
        "mesh_normal.mesh.topology -> mesh_normal.cli.common",
        "mesh_normal.triangle.normal -> mesh_normal.mesh.report.models",
    ]


def test_imports_inside_functions_and_relative_ones_count() -> None:
    tree = ast.parse("def f():\n    from app.calculator.pages import x\nfrom . import view\n")
    assert imported(tree, "app.mesh.page", False) == {
        "app.calculator.pages",
        "app.calculator.pages.x",
        "app.mesh",
        "app.mesh.view",
    }
