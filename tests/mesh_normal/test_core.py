"""The compiled core, ``mesh_normal._core``: its threads, and a new process that reports a mesh
at once, saying nothing about compiling and needing no JIT in its environment."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys

import pytest

from mesh_normal import _core
from tests.paths import ROOT


def run(script: str, **environment: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", script],
        cwd=ROOT,
        env={**os.environ, **environment},
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def test_a_new_process_reports_a_mesh_and_says_nothing_else() -> None:
    script = (
        "import mesh_normal as mn\n"
        f"report = mn.analyse({str(ROOT / 'tests' / 'data' / 'cow.obj')!r})\n"
        "print(report.faces, report.watertight)\n"
    )
    result = run(script)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout == "5804 True\n"
    assert result.stderr == ""


@pytest.mark.parametrize("name", ["numba", "llvmlite"])
def test_no_jit_is_in_the_environment(name: str) -> None:
    assert importlib.util.find_spec(name) is None


def test_the_threads_come_from_the_environment_and_can_be_set() -> None:
    result = run("from mesh_normal import _core\nprint(_core.threads())", MESH_NORMAL_THREADS="3")
    assert result.stdout == "3\n", result.stderr
    before = _core.threads()
    try:
        _core.set_threads(1)
        assert _core.threads() == 1
    finally:
        _core.set_threads(before)


@pytest.mark.parametrize("count", [0, -1, 1025])
def test_a_thread_count_out_of_range_is_one_sentence(count: int) -> None:
    with pytest.raises(ValueError, match=r"^the number of threads must be from 1 to 1024$"):
        _core.set_threads(count)


def test_a_bad_thread_count_in_the_environment_means_every_core() -> None:
    result = run(
        "import os\nfrom mesh_normal import _core\nprint(_core.threads() == os.cpu_count())",
        MESH_NORMAL_THREADS="many",
    )
    assert result.stdout == "True\n", result.stderr
