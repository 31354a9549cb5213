"""The mesh-normal command: analyze, normals, fix; exit codes and messages."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mesh_normal import face_normals, vertex_normals
from mesh_normal.cli import main
from mesh_normal.files import read_mesh, write_mesh
from tests.meshes import (
    CUBE_OBJ,
    CUBE_OBJ_FACES,
    CUBE_ONE_FLIPPED_OBJ,
    OPEN_BOX_OBJ,
    TETRA_OBJ,
    obj_as_solids,
    stepped_sides_cube,
)


@pytest.fixture
def cube(tmp_path: Path) -> Path:
    path = tmp_path / "cube.obj"
    path.write_text(CUBE_OBJ)
    return path


@pytest.fixture
def flipped(tmp_path: Path) -> Path:
    path = tmp_path / "flipped.obj"
    path.write_text(CUBE_ONE_FLIPPED_OBJ)
    return path


def test_analyze_clean_mesh(cube: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyze", str(cube)]) == 0
    out = capsys.readouterr().out
    assert "cube.obj: 8 vertices, 12 faces (OBJ)" in out
    assert "No problems found." in out


def test_analyze_lists_objects_one_line_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.mesh_normal.mesh.report.test_objects import many_triangles, two_cubes

    path = tmp_path / "two.obj"
    path.write_text(two_cubes([face[::-1] for face in CUBE_OBJ_FACES], "turned"))
    main(["analyze", str(path)])
    lines = capsys.readouterr().out.splitlines()
    start = lines.index("2 objects:")
    assert lines[start + 1 : start + 3] == [
        "  left: 12 faces, outward, closed, 0 flipped by the fix",
        "  turned: 12 faces, inward, closed, 12 flipped by the fix",
    ]
    path.write_text(many_triangles(103))
    main(["analyze", str(path)])
    assert "  and 3 more" in capsys.readouterr().out.splitlines()


def test_analyze_lists_stl_solids_as_objects(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    path = tmp_path / "two.stl"
    path.write_bytes(obj_as_solids(two_cubes([face[::-1] for face in CUBE_OBJ_FACES], "turned")))
    main(["analyze", str(path)])
    lines = capsys.readouterr().out.splitlines()
    start = lines.index("2 objects:")
    assert lines[start + 1 : start + 3] == [
        "  left: 12 faces, outward, closed, 0 flipped by the fix",
        "  turned: 12 faces, inward, closed, 12 flipped by the fix",
    ]


def test_stl_solids_written_again_say_the_objects_are_left_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    source, out = tmp_path / "two.stl", tmp_path / "again.stl"
    source.write_bytes(obj_as_solids(two_cubes()))
    assert main(["export", str(source), str(out)]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "leaves out" in line]
    assert lines == [
        f"mesh-normal: {out} leaves out the division into 2 objects (the STL written is one mesh)"
    ]
    assert len(read_mesh(out.read_bytes(), "again.stl").faces) == 24


def test_fix_with_nothing_to_flip_writes_the_input_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A script's ``fix IN OUT`` always finds OUT; with nothing to flip it is the input's own
    bytes, so the solids (and anything else the file holds) are kept."""
    from tests.mesh_normal.mesh.report.test_objects import two_cubes

    source, out = tmp_path / "two.stl", tmp_path / "fixed.stl"
    source.write_bytes(obj_as_solids(two_cubes()))
    assert main(["fix", str(source), str(out)]) == 0
    captured = capsys.readouterr()
    assert out.read_bytes() == source.read_bytes()
    assert captured.out == (
        f"wrote {out}: the input as it was, since none of the 24 faces needs flipping "
        "(orientation outward)\n"
    )
    assert "leaves out" not in captured.err


def test_analyze_one_object_lists_none(cube: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cube.write_text("o only\n" + CUBE_OBJ)
    main(["analyze", str(cube)])
    assert "objects:" not in capsys.readouterr().out


def test_analyze_json_and_exit_code_for_errors(
    flipped: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["analyze", str(flipped), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["winding_consistent"] is False
    assert report["fix"]["faces_flipped"] == 1


def test_analyze_warnings_only_exit_zero(tmp_path: Path) -> None:
    path = tmp_path / "box.obj"
    path.write_text(OPEN_BOX_OBJ)
    assert main(["analyze", str(path)]) == 0


@pytest.mark.parametrize("suffix", [".npy", ".csv", ".json", ".ply"])
def test_normals_each_output(cube: Path, tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"normals{suffix}"
    assert main(["normals", str(cube), "--kind", "vertex", "-o", str(out)]) == 0
    mesh = read_mesh(CUBE_OBJ.encode(), "cube.obj")
    expected = vertex_normals(mesh.vertices, mesh.faces).normals
    if suffix == ".npy":
        np.testing.assert_array_equal(np.load(out), expected)
    elif suffix == ".csv":
        rows = np.loadtxt(out, delimiter=",", skiprows=1)
        np.testing.assert_array_equal(rows[:, 1:], expected)
    elif suffix == ".json":
        assert json.loads(out.read_text())["normals"] == expected.tolist()
    else:
        trimesh = pytest.importorskip("trimesh")
        loaded = trimesh.load(out, process=False)
        np.testing.assert_array_equal(loaded.vertices, mesh.vertices)
        np.testing.assert_allclose(
            loaded.metadata["_ply_raw"]["vertex"]["data"]["nx"], expected[:, 0]
        )


def test_face_normals_npy(tmp_path: Path) -> None:
    path = tmp_path / "t.obj"
    path.write_text(TETRA_OBJ)
    out = tmp_path / "faces.npy"
    assert main(["normals", str(path), "--kind", "face", "-o", str(out)]) == 0
    mesh = read_mesh(TETRA_OBJ.encode(), "t.obj")
    np.testing.assert_array_equal(np.load(out), face_normals(mesh.vertices, mesh.faces).normals)


def test_fix_writes_the_fixed_mesh(
    flipped: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "fixed.ply"
    assert main(["fix", str(flipped), str(out)]) == 0
    assert "flipped 1 of 12 faces" in capsys.readouterr().out
    assert main(["analyze", str(out)]) == 0


@pytest.mark.parametrize(
    ("argv", "code", "words"),
    [
        (["analyze", "missing.obj"], 3, "cannot read missing.obj"),
        (["normals", "{cube}", "-o", "out.txt"], 2, "must end in"),
        (["normals", "{cube}", "--kind", "corner", "-o", "out.ply"], 2, "corner normals"),
        (["normals", "{cube}", "--crease-angle", "200", "-o", "o.npy"], 2, "between 0 and 180"),
        (["fix", "{cube}", "out.fbx"], 2, "output format"),
        (["fix", "--force", "{cube}", "/nonexistent-dir/out.ply"], 4, "cannot write"),
    ],
)
def test_failures_have_exit_codes_and_messages(
    cube: Path, capsys: pytest.CaptureFixture[str], argv: list[str], code: int, words: str
) -> None:
    argv = [arg.replace("{cube}", str(cube)) for arg in argv]
    assert main(argv) == code
    err = capsys.readouterr().err
    assert err.startswith("mesh-normal: ") and words in err


def test_broken_file_exit_code(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "broken.stl"
    path.write_bytes(b"\0" * 80 + (1000).to_bytes(4, "little"))
    assert main(["analyze", str(path)]) == 3
    assert "broken.stl" in capsys.readouterr().err


def test_usage_error_exit_code() -> None:
    with pytest.raises(SystemExit) as stop:
        main(["normals"])
    assert stop.value.code == 2


def test_progress_goes_to_stderr(
    cube: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "n.npy"
    assert main(["--progress", "normals", str(cube), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "reading" in err and "computing vertex normals" in err and err.endswith("done\n")


def test_installed_entry_point(cube: Path) -> None:
    command = shutil.which("mesh-normal", path=str(Path(sys.executable).parent))
    assert command is not None, "the mesh-normal script is not installed in the venv"
    result = subprocess.run(
        [command, "analyze", str(cube)], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    assert "No problems found." in result.stdout


def test_fix_in_place_writes_through_a_temporary_file(flipped: Path) -> None:
    assert main(["fix", "--force", str(flipped), str(flipped.with_suffix(".obj"))]) == 0
    assert main(["analyze", str(flipped)]) == 0  # the same path, now fixed
    assert sorted(path.name for path in flipped.parent.iterdir()) == ["flipped.obj"]


def test_fix_to_stl_beyond_float32_fails_cleanly(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "big.obj"
    path.write_text("v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nf 1 2 3\n")
    assert main(["fix", str(path), str(tmp_path / "big.stl")]) == 4
    assert "PLY or OBJ" in capsys.readouterr().err
    assert not (tmp_path / "big.stl").exists()


def test_face_normals_ply_carries_them_per_face(cube: Path, tmp_path: Path) -> None:
    out = tmp_path / "faces.ply"
    assert main(["normals", str(cube), "--kind", "face", "-o", str(out)]) == 0
    written = read_mesh(out.read_bytes(), "faces.ply")
    mesh = read_mesh(CUBE_OBJ.encode(), "cube.obj")
    np.testing.assert_array_equal(written.vertices, mesh.vertices)
    np.testing.assert_array_equal(written.faces, mesh.faces)
    np.testing.assert_array_equal(
        written.file_face_normals, face_normals(mesh.vertices, mesh.faces).normals
    )


# --- --weld -----------------------------------------------------------------------------------


@pytest.fixture
def stepped(tmp_path: Path) -> Path:
    """The cube of six sides a float32 step apart, wound inward, as a float64 PLY."""
    vertices, faces = stepped_sides_cube()
    path = tmp_path / "stepped.ply"
    path.write_bytes(write_mesh(vertices, faces[:, ::-1], "ply"))
    return path


def test_analyze_with_a_weld_says_so(stepped: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Six open sides, each seen from outside to face inward: a problem even without the weld.
    assert main(["analyze", str(stepped)]) == 1
    plain = capsys.readouterr().out
    assert "6 components" in plain and "open" in plain
    assert not any(line.startswith("weld ") for line in plain.splitlines())
    assert "--weld 1e-6 on the command line" in plain  # the open mesh suggests it
    assert main(["analyze", "--weld", "1e-6", str(stepped)]) == 1  # one closed shell, inward
    out = capsys.readouterr().out.splitlines()
    assert "1 component\n" in out[0] + "\n" and "orientation inward, watertight" in out[1]
    assert out[2].startswith("weld 1e-06 of the diagonal (") and out[2].endswith(
        "): 40 vertices joined beyond exact equality"
    )
    assert out[-1].startswith("To fix the winding: mesh-normal fix --weld 1e-06 stepped.ply")
    assert main(["analyze", "--json", "--weld", "1e-6", str(stepped)]) == 1
    assert json.loads(capsys.readouterr().out)["weld"]["joined_vertices"] == 40


def test_fix_with_the_weld_writes_what_the_report_described(
    stepped: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "fixed.ply"
    assert main(["fix", "--weld", "1e-6", str(stepped), str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert (
        lines[0].startswith(f"wrote {out}: flipped 108 of 108 faces") and "weld 1e-06" in lines[1]
    )
    before, after = read_mesh(stepped.read_bytes(), "s.ply"), read_mesh(out.read_bytes(), "f.ply")
    np.testing.assert_array_equal(after.vertices, before.vertices)  # kept, in their order
    np.testing.assert_array_equal(after.faces, before.faces[:, [0, 2, 1]])
    assert main(["analyze", "--weld", "1e-6", str(out)]) == 0
    assert "No problems found." in capsys.readouterr().out
    # Without it: six open sides, decided one by one by visibility, turned all the same.
    assert main(["fix", str(stepped), str(out)]) == 0
    assert capsys.readouterr().out.startswith(f"wrote {out}: flipped 108 of 108 faces")


@pytest.mark.parametrize("command", ["analyze", "fix"])
@pytest.mark.parametrize("value", ["-1e-6", "0.02", "nan", "inf", "abc"])
def test_a_bad_weld_is_a_usage_error_naming_it(
    command: str, value: str, cube: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [command, f"--weld={value}", str(cube)] + (
        [str(tmp_path / "o.ply")] * (command == "fix")
    )
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "argument --weld: must be a number from 0 to 0.01" in err and repr(value) in err


def test_the_weld_option_is_explained(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["fix", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "--weld FRACTION" in help_text and "of the bounding-box diagonal" in help_text


def test_a_large_binary_stl_is_mapped_and_reported_as_from_its_bytes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from mesh_normal.files import read as read_module
    from tests.paths import DATA

    path = tmp_path / "teapot.stl"
    shutil.copy(DATA / "teapot.stl", path)
    assert main(["analyze", "--json", str(path)]) == 0
    from_bytes = capsys.readouterr().out
    mapped: list[int] = []
    real = read_module.read_mapped
    monkeypatch.setattr(read_module, "MAPPED_BYTES", 1)
    monkeypatch.setattr(read_module, "read_mapped", lambda *a: mapped.append(1) or real(*a))
    assert main(["analyze", "--json", str(path)]) == 0
    assert capsys.readouterr().out == from_bytes and mapped == [1]
