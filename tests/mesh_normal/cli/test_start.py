"""The mesh-normal command starts fast: --help, --version and usage errors load neither the
compiled core nor numpy, pydantic or trimesh; ``python -m mesh_normal``; ``serve`` says how
to start the app."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import mesh_normal
from mesh_normal.cli import main
from mesh_normal.cli.commands import SERVE_HINT
from tests.paths import ROOT

HEAVY = ("numpy", "pydantic", "pydantic_core", "trimesh", "scipy")


def modules_after(argv: list[str]) -> tuple[set[str], int]:
    """The modules a fresh interpreter has loaded after ``main(argv)``, and its exit code."""
    script = (
        "import json, sys\n"
        "from mesh_normal.cli import main\n"
        "try:\n"
        f"    code = main({argv!r})\n"
        "except SystemExit as exit:\n"
        "    code = exit.code\n"
        "sys.stdout = sys.__stdout__\n"
        "print(json.dumps({'modules': sorted(sys.modules), 'code': code}))\n"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True
    )
    last = json.loads(completed.stdout.splitlines()[-1])
    return set(last["modules"]), last["code"]


@pytest.mark.parametrize(
    ("argv", "code"),
    [
        (["--help"], 0),
        (["--version"], 0),
        (["serve", "--port", "9000"], 2),
        (["analyze"], 2),  # a missing argument
        (["fix", "a.obj", "b.obj", "--format", "xyz"], 2),  # not a format it writes
    ],
)
def test_no_heavy_import_before_a_command_runs(argv: list[str], code: int) -> None:
    loaded, exit_code = modules_after(argv)
    assert exit_code == code
    heavy = sorted(name for name in loaded if name.split(".")[0] in HEAVY)
    assert not heavy, heavy
    assert "mesh_normal._core" not in loaded
    assert "mesh_normal.cli" in loaded


def test_the_check_sees_a_heavy_import() -> None:
    loaded, _ = modules_after(["normals", "missing.obj", "--kind", "face", "-o", "x.npy"])
    assert "numpy" in loaded


def test_analyze_of_a_tiny_mesh_imports_neither_trimesh_nor_scipy(tmp_path: Path) -> None:
    path = tmp_path / "tetra.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    loaded, code = modules_after(["analyze", str(path)])
    assert code == 0
    assert {"numpy", "mesh_normal.mesh.report.analysis"} <= loaded
    assert not {name for name in loaded if name.split(".")[0] in ("trimesh", "scipy")}


def test_python_dash_m_mesh_normal() -> None:
    completed = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "mesh_normal", "--help"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert completed.returncode == 0
    assert completed.stdout.startswith("usage: mesh-normal ")
    imported = {line.split("|")[-1].strip() for line in completed.stderr.splitlines()}
    assert "mesh_normal.cli" in imported
    assert not {name for name in imported if name.split(".")[0] in HEAVY}


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out == f"mesh-normal {mesh_normal.__version__}\n"


@pytest.mark.parametrize(
    "argv",
    [
        ["serve"],
        ["serve", "--host", "0.0.0.0", "--port", "9000", "--upload-limit-mb", "5"],
        ["serve", "--port=not-a-number"],  # ignored, like the others
    ],
)
def test_serve_says_in_one_sentence_how_to_start_the_app(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == f"mesh-normal: {SERVE_HINT}\n"
    assert SERVE_HINT.count(". ") == 0 and "make run" in SERVE_HINT


def test_serve_rejects_an_unknown_option(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["serve", "--reload"])
    assert exit_info.value.code == 2
    assert "unrecognized arguments: --reload" in capsys.readouterr().err


def test_a_bad_choice_names_the_choices(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["normals", "a.obj", "--weighting", "median", "-o", "x.npy"])
    assert exit_info.value.code == 2
    assert "(choose from 'uniform', 'area', 'angle', 'max')" in capsys.readouterr().err


def test_normals_help_lists_the_choices(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["normals", "--help"])
    out = " ".join(capsys.readouterr().out.split())  # argparse wraps lines
    assert "face, vertex, corner (default: vertex)" in out
    assert "uniform, area, angle, max (default: angle)" in out
