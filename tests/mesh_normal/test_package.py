"""The wheel, as a newcomer gets it: built by ``uv build``, holding ``mesh_normal`` and its
metadata only, installed into a fresh virtual environment outside the checkout and used from
another folder (the library from a path, ``mesh-normal analyze``, ``--help``), where ``app``
does not exist.

Most of the time goes to building the wheel (the compiled core: CMake, Ninja and g++ in an
isolated build); ``uv`` comes from the test group (or PATH, or the checkout's ``.tools``) and
installs from its cache.
"""

from __future__ import annotations

import email.parser
import os
import shutil
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

import pytest
from packaging.requirements import Requirement

import mesh_normal
from tests.paths import DATA, ROOT

#: Nothing of the web app or the tests reaches the wheel's requirements, not even as an extra.
WEB_AND_TEST = frozenset(
    {"fastapi", "starlette", "uvicorn", "jinja2", "plotly", "pytest", "playwright", "httpx"}
)
#: The most the library's environment (the wheel and its dependencies, bytecode left out) may
#: take, in MB.
MOST_MB = 230


def find_uv() -> str:
    """uv: the test group's own, else on PATH, else the checkout's ``.tools`` (as the Makefile)."""
    found = (
        shutil.which("uv", path=str(Path(sys.executable).parent))
        or shutil.which("uv")
        or str(ROOT / ".tools" / "bin" / "uv")
    )
    if not Path(found).is_file():
        pytest.fail("uv is needed to build the wheel: `uv sync --group test` installs it")
    return found


def clean_environment(bin_dir: Path | None = None) -> dict[str, str]:
    """os.environ without PYTHONPATH or an active virtual environment; uv offline-friendly."""
    environment = {
        key: value
        for key, value in os.environ.items()
        if key not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME", "PYTHONSTARTUP")
    }
    environment.update(UV_NATIVE_TLS="1", UV_SYSTEM_CERTS="1", UV_PYTHON_DOWNLOADS="never")
    if bin_dir is not None:
        environment["PATH"] = f"{bin_dir}{os.pathsep}{environment.get('PATH', '')}"
    return environment


def run(
    command: list[str], cwd: Path, bin_dir: Path | None = None, timeout: float = 300
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        command,
        cwd=cwd,
        env=clean_environment(bin_dir),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


@dataclass(frozen=True)
class Installed:
    wheel: Path
    bin_dir: Path
    site_packages: Path
    work: Path  #: an empty folder outside the checkout, holding a copy of cow.obj

    def run(self, *command: str) -> subprocess.CompletedProcess[str]:
        return run([str(self.bin_dir / command[0]), *command[1:]], self.work, self.bin_dir)


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Installed:
    base = tmp_path_factory.mktemp("package")
    assert not base.resolve().is_relative_to(ROOT)
    uv = find_uv()
    # --no-config: an isolated build, as a newcomer's; the checkout's [tool.uv] builds without
    # isolation for the editable install.
    command = [uv, "build", "--no-config", "--wheel", "--out-dir", str(base / "dist"), str(ROOT)]
    built = run(command, ROOT)
    assert built.returncode == 0, built.stderr
    (wheel,) = (base / "dist").glob("*.whl")
    venv = run([uv, "venv", "--quiet", "--python", sys.executable, str(base / "env")], base)
    assert venv.returncode == 0, venv.stderr
    python = base / "env" / "bin" / "python"
    install = run([uv, "pip", "install", "--quiet", "--python", str(python), str(wheel)], base)
    assert install.returncode == 0, install.stderr
    (site_packages,) = (base / "env" / "lib").glob("python*/site-packages")
    work = base / "work"
    work.mkdir()
    shutil.copy(DATA / "cow.obj", work / "cow.obj")
    return Installed(wheel, python.parent, site_packages, work)


def test_the_wheel_holds_mesh_normal_and_its_metadata_only(installed: Installed) -> None:
    with zipfile.ZipFile(installed.wheel) as archive:
        names = archive.namelist()
    version = mesh_normal.__version__
    tag = f"cp{sys.version_info.major}{sys.version_info.minor}"
    assert installed.wheel.name.startswith(f"mesh_normal-{version}-{tag}-{tag}-")
    assert {name.split("/")[0] for name in names} == {
        "mesh_normal",
        f"mesh_normal-{version}.dist-info",
    }
    assert "mesh_normal/py.typed" in names
    sources = {path.relative_to(ROOT).as_posix() for path in (ROOT / "mesh_normal").rglob("*.py")}
    assert sources <= set(names)  # every module, files/formats.py and __main__.py too
    assert not [name for name in names if name.endswith((".pyc", ".html", ".js", ".css"))]
    # The compiled core and its stubs.
    core = sorted(name for name in names if name.startswith("mesh_normal/_core"))
    assert len(core) == 2 and core[0].endswith(".so") and core[1] == "mesh_normal/_core.pyi", core


def test_the_wheel_requires_no_web_or_test_package(installed: Installed) -> None:
    with zipfile.ZipFile(installed.wheel) as archive:
        text = archive.read(f"mesh_normal-{mesh_normal.__version__}.dist-info/METADATA")
    metadata = email.parser.BytesParser().parsebytes(text)
    assert metadata["Name"] == "mesh-normal"
    assert metadata["Version"] == mesh_normal.__version__
    # The extras are the batch's (pyarrow), the batch on a Dask cluster and mn.show's Plotly;
    # nothing of the web is required.
    assert sorted(metadata.get_all("Provides-Extra") or []) == ["batch", "dask", "show"]
    required = [Requirement(text) for text in metadata.get_all("Requires-Dist") or []]
    extras = [item for item in required if item.marker and "extra" in str(item.marker)]
    names = {requirement.name.lower() for requirement in required if requirement not in extras}
    assert "numpy" in names
    assert not names & {"numba", "llvmlite"}  # the kernels are the compiled core's
    assert not names & WEB_AND_TEST
    assert sorted(item.name.lower() for item in extras) == ["dask", "plotly", "pyarrow", "pyarrow"]
    assert "pyarrow" not in {item.name for item in required if item not in extras}


def test_the_library_from_another_folder(installed: Installed) -> None:
    script = (
        "import importlib.metadata, pathlib, sys\n"
        "import mesh_normal as mn\n"
        "mesh = mn.read_mesh('cow.obj')\n"
        "print(mesh.format, mesh.vertices.shape, mesh.faces.shape)\n"
        "print(mn.__version__ == importlib.metadata.version('mesh-normal'))\n"
        "print(pathlib.Path(mn.__file__).parent)\n"
    )
    completed = installed.run("python", "-c", script)
    assert completed.returncode == 0, completed.stderr
    lines = completed.stdout.splitlines()
    assert lines[0] == "obj (2904, 3) (5804, 3)"
    assert lines[1] == "True"
    assert Path(lines[2]) == installed.site_packages / "mesh_normal"  # not the checkout's


def test_there_is_no_app_package(installed: Installed) -> None:
    for name in ("app", "templates", "static", "tests"):
        completed = installed.run("python", "-c", f"import {name}")
        assert completed.returncode == 1
        assert f"No module named '{name}'" in completed.stderr
        assert not (installed.site_packages / name).exists()


def test_no_web_or_test_package_is_installed(installed: Installed) -> None:
    script = "import importlib.metadata as m\nfor d in m.distributions(): print(d.metadata['Name'])"
    completed = installed.run("python", "-c", script)
    assert completed.returncode == 0, completed.stderr
    distributions = {name.lower() for name in completed.stdout.split()}
    assert "mesh-normal" in distributions
    assert not distributions & WEB_AND_TEST


def test_mesh_normal_analyze(installed: Installed) -> None:
    completed = installed.run("mesh-normal", "analyze", "cow.obj")
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout.startswith("cow.obj: 2,904 vertices, 5,804 faces (OBJ), 1 component\n")
    assert "No problems found." in completed.stdout
    missing = installed.run("mesh-normal", "analyze", "missing.obj")
    assert missing.returncode == 3
    assert "mesh-normal: cannot read missing.obj" in missing.stderr


def test_mesh_normal_help_version_and_serve(installed: Installed) -> None:
    help_run = installed.run("mesh-normal", "--help")
    assert help_run.returncode == 0, help_run.stderr
    assert help_run.stdout.startswith("usage: mesh-normal ")
    version = installed.run("mesh-normal", "--version")
    assert version.stdout == f"mesh-normal {mesh_normal.__version__}\n"
    serve = installed.run("mesh-normal", "serve", "--port", "8001")
    assert serve.returncode == 2
    assert "make run" in serve.stderr and "Traceback" not in serve.stderr


def test_the_environment_holds_no_numba_or_llvmlite(installed: Installed) -> None:
    script = "import importlib.metadata as m\nfor d in m.distributions(): print(d.metadata['Name'])"
    completed = installed.run("python", "-c", script)
    assert completed.returncode == 0, completed.stderr
    distributions = {name.lower() for name in completed.stdout.split()}
    assert "numpy" in distributions
    assert not distributions & {"numba", "llvmlite"}
    folders = {path.name.split("-")[0] for path in installed.site_packages.iterdir()}
    assert not folders & {"numba", "llvmlite"}


def test_python_dash_m_help_imports_no_numpy_there(installed: Installed) -> None:
    completed = installed.run("python", "-X", "importtime", "-m", "mesh_normal", "--help")
    assert completed.returncode == 0, completed.stderr
    imported = {line.split("|")[-1].strip() for line in completed.stderr.splitlines()}
    assert "mesh_normal.cli" in imported
    assert "numpy" not in imported and "mesh_normal._core" not in imported


def test_a_report_and_its_json_load_no_pydantic(installed: Installed) -> None:
    # The reports are dataclasses: a new process's first answer does not pay for pydantic, and
    # the library does not install it.
    script = (
        "import json, sys, mesh_normal as mn\n"
        "report = mn.analyse('cow.obj')\n"
        "print(report.faces, json.loads(report.to_json())['faces'], 'pydantic' in sys.modules)\n"
    )
    completed = installed.run("python", "-c", script)
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout == "5804 5804 False\n"


def test_sizes(installed: Installed, record_property: pytest.RecordProperty) -> None:
    wheel_kb = installed.wheel.stat().st_size / 1024
    installed_mb = (
        sum(
            path.stat().st_size
            for path in installed.site_packages.rglob("*")
            # Bytecode left out: UV_COMPILE_BYTECODE adds it, Python writes it on first use.
            if path.is_file() and "__pycache__" not in path.parts
        )
        / 1e6
    )
    record_property("wheel_kb", round(wheel_kb))
    record_property("site_packages_mb", round(installed_mb))
    print(f"wheel {wheel_kb:.0f} KB, site-packages {installed_mb:.0f} MB (at most {MOST_MB} MB)")
    assert wheel_kb < 1024
    assert installed_mb <= MOST_MB
