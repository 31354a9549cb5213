"""Tests for mesh_normal.kernels: the first compile says so once; reading files needs no numba."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.paths import ROOT

MESSAGE = "mesh-normal: compiling the mesh kernels (each once"
#: A call this small runs the kernels' Python source until numba is loaded: load it first.
COMPILED = "from mesh_normal.kernels import load_numba\nload_numba()\n"


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
    first = said_once_then_not(script, tmp_path)
    assert "about 20 s for all of them; later runs load them from the cache)" in first.stderr
    assert any(tmp_path.rglob("*.nbi"))  # the cache is where NUMBA_CACHE_DIR says


def said_once_then_not(script: str, cache: Path) -> subprocess.CompletedProcess[str]:
    """Run ``script`` twice on one cache: the first run says it compiles, once; the second,
    loading the cache, says nothing and prints the same. Returns the first run."""
    first = run(script, cache)
    assert first.returncode == 0, first.stderr[-2000:]
    assert first.stderr.count(MESSAGE) == 1
    second = run(script, cache)
    assert second.returncode == 0, second.stderr[-2000:]
    assert MESSAGE not in second.stderr
    assert second.stdout == first.stdout
    return first


def test_one_kernel_alone_is_announced_when_not_cached(tmp_path: Path) -> None:
    # A first use that compiles only the point-cloud kernels still says so.
    script = (
        COMPILED + "import numpy as np\n"
        "import mesh_normal as mn\n"
        "mn.point_normals(np.random.default_rng(0).normal(size=(50, 3)), k=8)\n"
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
        "mn.face_normals(mesh.vertices, mesh.faces)\n"  # 12 faces: in Python
        "assert 'numba' not in sys.modules, 'numba was imported for 12 faces'\n"
        "mn.face_normals(mesh.vertices, mesh.faces[[0] * 3000])\n"  # compiled core: no numba
        "assert 'numba' not in sys.modules, 'numba was imported for face normals'\n"
    )
    result = run(script, tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]


#: numba's writable locators refuse a folder they cannot write (each tests it by writing a
#: temporary file there): made to refuse here, as on a read-only root filesystem.
READ_ONLY = (
    "from numba.core import caching\n"
    "def refuse(self):\n"
    "    raise PermissionError(30, 'Read-only file system', self.get_cache_path())\n"
    "for name in ('UserProvidedCacheLocator', 'InTreeCacheLocator', 'UserWideCacheLocator'):\n"
    "    getattr(caching, name).ensure_cache_path = refuse\n"
)


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    return {
        str(path): (path.stat().st_size, path.stat().st_mtime_ns)
        for path in folder.rglob("*")
        if path.is_file()
    }


def test_a_read_only_cache_is_read_and_never_written(tmp_path: Path) -> None:
    compile_all = (
        "from mesh_normal.precompile import compile_kernels\n"
        "compile_kernels()\n"
        "import mesh_normal as mn\n"
        "print(mn.orient([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).orientation)\n"
    )
    built = run(compile_all, tmp_path)  # the image build: the cache is written
    assert built.returncode == 0, built.stderr[-2000:]
    before = _snapshot(tmp_path)
    check = (
        "from mesh_normal.kernels import _KERNELS\n"
        "assert all(kernel._cache.read_only for kernel in _KERNELS)\n"
    )
    served = run(READ_ONLY + compile_all + check, tmp_path)  # run time: read only
    assert served.returncode == 0, served.stderr[-2000:]
    assert "cannot cache" not in served.stderr
    assert MESSAGE not in served.stderr, "every kernel came from the read-only cache"
    assert served.stdout == built.stdout
    assert _snapshot(tmp_path) == before, "nothing was written"


def test_without_a_usable_cache_the_kernels_are_compiled_in_memory(tmp_path: Path) -> None:
    empty = tmp_path / "empty"
    script = (
        READ_ONLY + COMPILED + "import mesh_normal as mn\n"
        "print(mn.orient([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).orientation)\n"
    )
    result = run(script, empty)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == "undetermined"
    assert MESSAGE in result.stderr
    assert not empty.exists() or not any(empty.rglob("*.nbi")), "nothing was saved"


def test_a_point_cloud_run_is_not_told_of_mesh_kernels_it_never_runs(tmp_path: Path) -> None:
    # Reading the cloud imports mesh kernels (the readers'); the estimate runs its own alone.
    script = (
        "import numpy as np\n"
        "import mesh_normal as mn\n"
        "import mesh_normal.faces, mesh_normal.topology\n"
        "points = np.random.default_rng(0).normal(size=(50, 3))\n"
        "print(mn.point_normals(points, k=8).counts()['ok'])\n"
    )
    said_once_then_not(script, tmp_path)
