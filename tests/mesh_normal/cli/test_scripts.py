"""mesh-normal in scripts and pipes: ``-`` is standard output, the data alone goes there, and
every command that writes says what it wrote (on stderr when stdout carries the data)."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mesh_normal.cli import main
from mesh_normal.cli.common import EXIT_OK, EXIT_OUTPUT, EXIT_USAGE
from mesh_normal.cli.mesh import terminal_words
from mesh_normal.files import read_mesh, write_mesh
from mesh_normal.mesh.faces import face_normals
from mesh_normal.mesh.vertices import vertex_normals
from mesh_normal.points import write_points
from tests.mesh_normal.points._clouds import sphere
from tests.meshes import TETRA_FACES, TETRA_VERTICES


@pytest.fixture
def tetra(tmp_path: Path) -> Path:
    path = tmp_path / "tetra.ply"
    path.write_bytes(write_mesh(TETRA_VERTICES, TETRA_FACES, "ply"))
    return path


@pytest.fixture
def cloud(tmp_path: Path) -> Path:
    points, normals = sphere(200)
    path = tmp_path / "ball.ply"
    path.write_bytes(write_points(points, normals, "ply"))
    return path


def test_normals_to_a_file_say_what_was_written(
    tetra: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "n.npy"
    assert main(["normals", str(tetra), "-o", str(out)]) == EXIT_OK
    captured = capsys.readouterr()
    assert captured.out == f"wrote 4 vertex normals to {out}\n"
    assert captured.err == ""
    expected = vertex_normals(TETRA_VERTICES, TETRA_FACES, weighting="angle").normals
    np.testing.assert_array_equal(np.load(out), expected)


def test_normals_to_standard_output_are_npy_by_default(
    tetra: Path, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    assert main(["normals", str(tetra), "--kind", "face", "-o", "-"]) == EXIT_OK
    captured = capsysbinary.readouterr()
    np.testing.assert_array_equal(
        np.load(io.BytesIO(captured.out)), face_normals(TETRA_VERTICES, TETRA_FACES).normals
    )
    assert captured.err == b"wrote 4 face normals to standard output (npy)\n"


def test_normals_to_standard_output_in_a_text_format(
    tetra: Path, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    assert main(["normals", str(tetra), "-o", "-", "--format", "csv"]) == EXIT_OK
    captured = capsysbinary.readouterr()
    rows = captured.out.decode().splitlines()
    assert len(rows) == 1 + 4  # a header, then a row a vertex
    assert captured.err == b"wrote 4 vertex normals to standard output (csv)\n"


def test_a_format_that_contradicts_the_suffix_is_refused(
    tetra: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "n.npy"
    assert main(["normals", str(tetra), "-o", str(out), "--format", "csv"]) == EXIT_USAGE
    assert "names npy but --format is csv" in capsys.readouterr().err
    assert not out.exists()


def test_fix_to_standard_output_needs_a_format(
    tetra: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["fix", str(tetra), "-"]) == EXIT_USAGE
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "writing the mesh to standard output (-) needs --format" in captured.err


def test_fix_to_standard_output_writes_the_mesh_there(
    tmp_path: Path, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    source = tmp_path / "flipped.obj"
    source.write_bytes(write_mesh(TETRA_VERTICES, TETRA_FACES[:, [0, 2, 1]], "obj"))
    assert main(["fix", str(source), "-", "--format", "ply"]) == EXIT_OK
    captured = capsysbinary.readouterr()
    fixed = read_mesh(captured.out, "fixed.ply")
    assert fixed.format == "ply"
    assert sorted(map(tuple, np.sort(fixed.faces, axis=1))) == sorted(
        map(tuple, np.sort(TETRA_FACES, axis=1))
    )
    assert captured.err.decode().startswith("wrote standard output (ply): flipped 4 of 4 faces")


def test_point_normals_to_standard_output(
    cloud: Path, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    assert main(["points", str(cloud), "--k", "16", "-o", "-"]) == EXIT_OK
    captured = capsysbinary.readouterr()
    assert np.load(io.BytesIO(captured.out)).shape == (200, 3)
    assert captured.err == b"wrote 200 normals to standard output (npy)\n"
    assert main(["points", str(cloud), "--k", "16", "-o", "-", "--format", "xyz"]) == EXIT_OK
    rows = capsysbinary.readouterr().out.decode().splitlines()
    assert len([row for row in rows if not row.startswith("#")]) == 200


def test_point_summary_and_data_cannot_share_standard_output(
    cloud: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["points", str(cloud), "-o", "-", "--json"]) == EXIT_USAGE
    assert "--json and -o - would both write to standard output" in capsys.readouterr().err


def test_a_reader_that_has_gone_ends_the_command_without_a_traceback(tetra: Path) -> None:
    """``mesh-normal normals m.ply -o - | head -c 0``: the pipe's reader has closed it."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        command = [sys.executable, "-m", "mesh_normal", "normals", str(tetra), "-o", "-"]
        done = subprocess.run(command, stdout=write_end, stderr=subprocess.PIPE, timeout=60)
    finally:
        os.close(write_end)
    assert done.returncode == EXIT_OUTPUT
    assert done.stderr == b"mesh-normal: standard output was closed before the data was written\n"


@pytest.mark.parametrize(
    ("page", "terminal"),
    [
        (
            "Download the fixed mesh (every face reversed), or reverse each face's winding.",
            "Write the fixed mesh (every face reversed) with the command below, or reverse each "
            "face's winding.",
        ),
        (
            "Download the fixed mesh, or call orient() in your own code.",
            "Write the fixed mesh with the command below, or call orient() in your own code.",
        ),
        ("Nothing to download here.", "Nothing to download here."),
    ],
)
def test_the_page_s_advice_reads_as_a_sentence_in_a_terminal(page: str, terminal: str) -> None:
    assert terminal_words(page) == terminal
