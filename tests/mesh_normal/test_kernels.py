"""Tests for mesh_normal.kernels: the first compile says so once; reading files needs no numba."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.paths import ROOT

MESSAGE = "mesh-normal: compiling the mesh kernels (each once"


def run(script: str, cache: Path) -> subprocess.CompletedProcess[str]:
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run(
        [sys.executable, "-c", script],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_the_first_compile_says_so_once_and_a_cached_run_does_not(tmp_path: Path) -> None:
    script = (
        "from mesh_normal.precompile import compile_kernels\n"
        "compile_kernels()\n"
        "compile_kernels()\n"
        "import mesh_normal as mn\n"
        "print(mn.orient([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).orientation)\n"
    )
    first = run(script, tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    assert first.stderr.count(MESSAGE) == 1
    assert "about 10 s for all of them; later runs load them from the cache)" in first.stderr
    assert any(tmp_path.rglob("*.nbi"))  # the cache is where NUMBA_CACHE_DIR says
    second = run(script, tmp_path)
    assert second.returncode == 0, second.stderr[-2000:]
    assert MESSAGE not in second.stderr
    assert second.stdout == first.stdout


def test_one_kernel_alone_is_announced_when_not_cached(tmp_path: Path) -> None:
    # A first use that compiles only the face kernels still says so.
    script = (
        "import mesh_normal as mn\n"
        "mn.face_normals([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])\n"
    )
    first = run(script, tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    assert first.stderr.count(MESSAGE) == 1
    assert MESSAGE not in run(script, tmp_path).stderr


def test_reading_and_checking_a_mesh_do_not_import_numba(tmp_path: Path) -> None:
    script = (
        "import sys\n"
        "import mesh_normal as mn\n"
        "from mesh_normal.checks import checked_mesh\n"
        f"mesh = mn.read_mesh(open({str(ROOT / 'tests' / 'data' / 'cube.obj')!r}, 'rb').read())\n"
        "checked_mesh(mesh.vertices, mesh.faces.astype('int32'))\n"
        "assert 'numba' not in sys.modules, 'numba was imported'\n"
        "mn.face_normals(mesh.vertices, mesh.faces)\n"
        "assert 'numba' in sys.modules\n"
    )
    result = run(script, tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
