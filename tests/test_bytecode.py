"""The environments hold compiled bytecode: the one ``make env`` made (which runs these tests),
and, by their recipes, those of ``make run`` and the container image. Without it every start
compiles each module it imports (3.9 s to the server's first page instead of 1.4 s), and
PYTHONDONTWRITEBYTECODE, often set, keeps Python from saving the result."""

from __future__ import annotations

import importlib
import importlib.util
import re
import sysconfig
from pathlib import Path

import pytest

from tests.paths import ROOT

#: Modules every start imports: the library's and the app's heaviest dependencies, and ours.
MODULES = ("numpy", "pydantic", "fastapi", "uvicorn", "starlette")
# The checkout's own modules change between runs: the recipes compile them (tested below).


def cached(path: str | Path) -> Path:
    return Path(importlib.util.cache_from_source(str(path)))


@pytest.mark.parametrize("name", MODULES)
def test_a_module_started_with_has_its_bytecode(name: str) -> None:
    spec = importlib.util.find_spec(name)
    assert spec is not None and spec.origin is not None
    assert cached(spec.origin).is_file(), f"{name} has no .pyc beside {spec.origin}"


def test_nearly_every_module_of_site_packages_has_its_bytecode() -> None:
    sources = list(Path(sysconfig.get_paths()["purelib"]).rglob("*.py"))
    missing = [path for path in sources if not cached(path).is_file()]
    # uv leaves out the few files that do not compile (test data of some packages).
    assert len(sources) > 1000 and len(missing) < len(sources) / 100, missing[:10]


def test_the_recipes_compile_the_bytecode() -> None:
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r"^export UV_COMPILE_BYTECODE := 1$", makefile, re.MULTILINE)
    compile_sources = ".venv/bin/python -m compileall -q mesh_normal app"
    assert f"COMPILE_SOURCES = {compile_sources}" in makefile
    run = makefile.split("\nrun: ", 1)[1].split("\n\n", 1)[0]
    assert "$(COMPILE_SOURCES)" in run  # the checkout's own modules, before the server starts
    dockerfile = (ROOT / "Dockerfile").read_text()
    # The library is a wheel that uv installs (and compiles, UV_COMPILE_BYTECODE) in the builder
    # stage; the app's sources are copied into the runtime stage and compiled there.
    builder, runtime = dockerfile.split("\nFROM ")[1:]
    assert "UV_COMPILE_BYTECODE=1" in builder and "uv pip install" in builder
    assert "RUN python -m compileall -q app" in runtime
