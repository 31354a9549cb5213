"""mesh-normal fix and export: never over the input, nothing written for nothing to fix,
what is kept and dropped said."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

from mesh_normal.cli import main
from mesh_normal.cli.common import EXIT_OK, EXIT_USAGE
from mesh_normal.files import read_mesh, write_mesh
from mesh_normal.mesh.vertices import vertex_normals
from tests.meshes import TETRA_FACES, TETRA_VERTICES

FLIPPED = TETRA_FACES[:, [0, 2, 1]]


@pytest.fixture
def with_normals(tmp_path: Path) -> Path:
    """An OBJ with per-vertex vn and one face flipped."""
    faces = TETRA_FACES.copy()
    faces[0] = faces[0, [0, 2, 1]]
    normals = vertex_normals(TETRA_VERTICES, TETRA_FACES).normals
    path = tmp_path / "bunny.obj"
    path.write_bytes(
        write_mesh(TETRA_VERTICES, faces, "obj", normals=normals, normals_kind="vertex")
    )
    return path


def test_fix_refuses_to_overwrite_its_input(
    with_normals: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = with_normals.read_bytes()
    assert main(["fix", str(with_normals), str(with_normals)]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "is the input file" in err and "--force" in err and err.count("\n") == 1
    assert with_normals.read_bytes() == before


def test_fix_refuses_a_link_to_its_input(with_normals: Path) -> None:
    link = with_normals.with_name("link.obj")
    os.link(with_normals, link)
    assert main(["fix", str(with_normals), str(link)]) == EXIT_USAGE
    symlink = with_normals.with_name("sym.obj")
    symlink.symlink_to(with_normals)
    assert main(["fix", str(with_normals), str(symlink)]) == EXIT_USAGE


def test_fix_with_force_replaces_the_input_keeping_its_normals(
    with_normals: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["fix", "--force", str(with_normals), str(with_normals)]) == EXIT_OK
    out = capsys.readouterr().out
    assert "flipped 1 of 4 faces" in out and "kept vertex normals (recomputed)" in out
    fixed = read_mesh(with_normals.read_bytes(), "bunny.obj")
    assert fixed.file_vertex_normals is not None  # the vn lines are still there
    outward = vertex_normals(TETRA_VERTICES, TETRA_FACES).normals
    np.testing.assert_allclose(fixed.file_vertex_normals, outward, atol=1e-12)


def test_nothing_to_fix_still_writes_the_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source, out = tmp_path / "good.ply", tmp_path / "out.ply"
    source.write_bytes(write_mesh(TETRA_VERTICES, TETRA_FACES, "ply"))
    assert main(["fix", str(source), str(out)]) == EXIT_OK
    assert out.read_bytes() == source.read_bytes()
    assert "the input as it was" in capsys.readouterr().out
    out.unlink()  # the old option is still taken, and changes nothing
    assert main(["fix", "--write-unchanged", str(source), str(out)]) == EXIT_OK
    assert out.read_bytes() == source.read_bytes()


def test_nothing_to_fix_in_another_format_writes_the_same_faces(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source, out = tmp_path / "good.ply", tmp_path / "out.obj"
    source.write_bytes(write_mesh(TETRA_VERTICES, TETRA_FACES, "ply"))
    assert main(["fix", str(source), str(out)]) == EXIT_OK
    assert "the same faces, since none of the 4 faces needs flipping" in capsys.readouterr().out
    np.testing.assert_array_equal(read_mesh(out.read_bytes(), "out.obj").faces, TETRA_FACES)


def test_an_obj_with_nothing_to_fix_keeps_its_texture_coordinates_and_groups(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source, out = tmp_path / "good.obj", tmp_path / "out.obj"
    text = (
        "mtllib a.mtl\ng body\nvt 0 0\n" + write_mesh(TETRA_VERTICES, TETRA_FACES, "obj").decode()
    )
    source.write_text(text)
    assert main(["fix", str(source), str(out)]) == EXIT_OK
    assert out.read_text() == text
    assert "leaves out" not in capsys.readouterr().err


def test_fix_says_what_it_drops(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source, out = tmp_path / "t.obj", tmp_path / "t.stl"
    text = write_mesh(TETRA_VERTICES, FLIPPED, "obj").decode() + "vt 0 0\n"
    source.write_text(text)
    assert main(["fix", str(source), str(out)]) == EXIT_OK
    assert "leaves out texture coordinates (1 vt)" in capsys.readouterr().err


def test_export_writes_a_glb_with_corner_normals(
    with_normals: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out.glb"
    argv = ["export", str(with_normals), str(out), "--normals", "corner", "--winding", "fix"]
    assert main(argv) == EXIT_OK
    assert "flipped 1 of 4 faces" in capsys.readouterr().out
    scene = trimesh.load(io.BytesIO(out.read_bytes()), file_type="glb", process=False)
    (mesh,) = scene.geometry.values()
    assert len(mesh.faces) == 4 and len(mesh.vertices) == 12
    assert mesh.is_winding_consistent and mesh.volume > 0


def test_normals_to_an_obj_writes_the_mesh_with_them(with_normals: Path, tmp_path: Path) -> None:
    out = tmp_path / "corners.obj"
    assert main(["normals", str(with_normals), "--kind", "corner", "-o", str(out)]) == EXIT_OK
    mesh = read_mesh(out.read_bytes(), "corners.obj")
    assert mesh.file_corner_normals is not None
    loaded = trimesh.load(io.BytesIO(out.read_bytes()), file_type="obj", process=False)
    assert len(loaded.faces) == 4


def test_normals_refuses_a_kind_the_format_cannot_hold(
    with_normals: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "c.stl"
    assert main(["normals", str(with_normals), "--kind", "corner", "-o", str(out)]) == 2
    assert "STL file, which holds only face normals" in capsys.readouterr().err


def test_analyze_reads_as_a_person_would(
    with_normals: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    main(["analyze", str(with_normals)])
    out = capsys.readouterr().out
    assert "1 component\n" in out and "(s)" not in out and "Download" not in out
    assert "area 2.36603, volume -" in out  # six significant digits, not sixteen
