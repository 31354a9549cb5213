"""mesh-normal fix keeps vertex colours where the output holds them, and says what it drops."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mesh_normal.cli import main
from mesh_normal.files import read_mesh, write_mesh
from tests.meshes import TETRA_FACES, TETRA_OBJ, TETRA_VERTICES

UCHAR = np.array([[255, 0, 3], [4, 5, 6], [7, 128, 9], [0, 254, 1]], dtype=np.uint8)
FLIPPED = np.array([TETRA_FACES[0][::-1], *TETRA_FACES[1:]])


@pytest.fixture
def coloured(tmp_path: Path) -> Path:
    path = tmp_path / "coloured.ply"
    path.write_bytes(write_mesh(TETRA_VERTICES, FLIPPED, "ply", vertex_colors=UCHAR))
    return path


def test_fix_keeps_ply_colours(
    coloured: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "fixed.ply"
    assert main(["fix", str(coloured), str(out)]) == 0
    printed = capsys.readouterr()
    assert "leaves out" not in printed.err
    assert "flipped 1 of 4 faces" in printed.out
    fixed = read_mesh(out.read_bytes(), "fixed.ply")
    assert fixed.vertex_colors is not None
    assert fixed.vertex_colors.tobytes() == UCHAR.tobytes()


def test_fix_keeps_obj_colours(tmp_path: Path) -> None:
    colors = np.array([[0.1, 0.2, 0.3], [1.0, 0.0, 0.5], [1 / 3, 2 / 3, 1e-9], [0.0, 0.0, 0.0]])
    source = tmp_path / "coloured.obj"
    source.write_bytes(write_mesh(TETRA_VERTICES, FLIPPED, "obj", vertex_colors=colors))
    out = tmp_path / "fixed.obj"
    assert main(["fix", str(source), str(out)]) == 0
    fixed = read_mesh(out.read_bytes(), "fixed.obj")
    assert fixed.vertex_colors is not None
    assert fixed.vertex_colors.tobytes() == colors.tobytes()


def test_fix_to_stl_says_the_colours_are_dropped(
    coloured: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "fixed.stl"
    assert main(["fix", str(coloured), str(out)]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "leaves out" in line]
    assert lines == [f"mesh-normal: {out} leaves out vertex colours (STL holds none)"]


def test_fix_without_colours_says_nothing_of_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = tmp_path / "t.obj"
    source.write_text(TETRA_OBJ)
    assert main(["fix", str(source), str(tmp_path / "fixed.stl")]) == 0
    assert "leaves out" not in capsys.readouterr().err


def test_fix_to_obj_says_the_face_colours_are_dropped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = tmp_path / "faces.ply"
    source.write_bytes(write_mesh(TETRA_VERTICES, FLIPPED, "ply", face_colors=UCHAR))
    kept = tmp_path / "fixed.ply"
    assert main(["fix", str(source), str(kept)]) == 0
    fixed = read_mesh(kept.read_bytes(), "fixed.ply")
    assert fixed.face_colors is not None and fixed.face_colors.tobytes() == UCHAR.tobytes()
    out = tmp_path / "fixed.obj"
    capsys.readouterr()
    assert main(["fix", str(source), str(out)]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "leaves out" in line]
    assert lines == [f"mesh-normal: {out} leaves out face colours (OBJ holds none)"]
