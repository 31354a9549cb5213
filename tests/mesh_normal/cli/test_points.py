"""``mesh-normal points``: a point cloud's normals as a file or a summary; errors and exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mesh_normal.cli import main
from mesh_normal.cli.points import component_lines, written_line
from mesh_normal.points import point_normals, read_points, write_points
from tests.mesh_normal.points._clouds import sphere
from tests.mesh_normal.points._pcd import pcd_header

N = 400
#: Two points far from the sphere: with --radius 0.5 each is alone in its neighbourhood.
LONERS = np.array([[10.0, 10.0, 10.0], [-20.0, 5.0, 0.0]])


@pytest.fixture
def cloud() -> tuple[np.ndarray, np.ndarray]:
    return sphere(N, seed=3)


@pytest.fixture
def ply(tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray]) -> Path:
    """The sphere with its true outward normals stored."""
    path = tmp_path / "ball.ply"
    path.write_bytes(write_points(*cloud))
    return path


@pytest.fixture
def xyz(tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray]) -> Path:
    """The sphere's points alone, no normals."""
    path = tmp_path / "ball.xyz"
    path.write_bytes(write_points(cloud[0], fmt="xyz"))
    return path


def plane_pcd(path: Path, viewpoint: str) -> Path:
    """A 10 x 10 grid on z = 0 as an ASCII PCD file with the given VIEWPOINT line."""
    x, y = np.meshgrid(np.arange(10.0), np.arange(10.0))
    rows = "".join(f"{a} {b} 0\n" for a, b in zip(x.ravel(), y.ravel(), strict=True))
    path.write_bytes(
        pcd_header("x y z", "4 4 4", "F F F", 100, viewpoint=viewpoint) + rows.encode()
    )
    return path


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


# --- the summary --------------------------------------------------------------------------------


def test_summary_in_words(ply: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(["points", str(ply)], capsys)
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == f"ball.ply: {N} points (PLY), {N} with a normal, 0 without"
    assert lines[1].startswith("neighbourhood: each point's own scale, chosen from the data; ")
    assert "oriented by mst (max angle 60 degrees)" in lines[1]
    assert f"  ok: {N} (a unit normal, oriented as asked)" in lines
    assert lines[3].startswith("orientation: 1 part; ")
    assert lines[4].startswith(f"  part 1: {N} points, ")
    # A closed sphere points out, as its stored normals do.
    assert lines[-1].startswith(f"the file's normals: {N} compared, median angle between the")
    assert lines[-1].endswith(f"{N} point the same way, 0 the opposite way")


def test_summary_counts_points_without_a_normal_with_reasons(
    tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray], capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "lonely.xyz"
    path.write_bytes(write_points(np.vstack([cloud[0], LONERS]), fmt="xyz"))
    code, out, _ = run(["points", str(path), "--radius", "0.5"], capsys)
    assert code == 0
    assert f"{N + 2} points (XYZ), {N} with a normal, 2 without" in out
    assert "every point within 0.5" in out
    assert "  too_few_neighbours: 2 (fewer than three points in the neighbourhood" in out
    assert "the file's normals" not in out  # the file has none


def test_json_summary(ply: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(["points", str(ply), "--json", "--k", "12"], capsys)
    assert code == 0
    found = json.loads(out)
    assert (found["file"], found["format"], found["points"]) == ("ball.ply", "ply", N)
    assert found["neighbourhood"] == {"k": 12, "radius": None}
    assert found["counts"]["ok"] == N and sum(found["counts"].values()) == N
    assert found["with_normal"] == N and found["without_normal"] == 0
    assert found["component_count"] == 1 == len(found["components"])
    part = found["components"][0]
    assert part["points"] == N and found["flipped"] == part["flipped"]
    stored = found["stored_normals"]
    assert stored["compared"] == stored["same_way"] == N and stored["opposite"] == 0
    assert 0 <= stored["median_line_degrees"] < 5
    assert found["output"] is None


def test_agreement_counts_opposite_normals(
    tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray], capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "inside_out.ply"
    path.write_bytes(write_points(cloud[0], -cloud[1]))
    found = json.loads(run(["points", str(path), "--json"], capsys)[1])
    assert found["stored_normals"]["opposite"] == N and found["stored_normals"]["same_way"] == 0
    # Oriented by the file instead, every one agrees.
    found = json.loads(run(["points", str(path), "--json", "--orient", "file"], capsys)[1])
    assert found["orient"] == "file" and found["stored_normals"]["same_way"] == N


def test_a_mesh_file_is_read_as_its_vertices(
    tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray], capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "ball.obj"
    path.write_text(
        "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in cloud[0].tolist()) + "f 1 2 3\n"
    )
    code, out, _ = run(["points", str(path)], capsys)
    assert code == 0 and out.startswith(f"ball.obj: {N} points (OBJ vertices)")


# --- output files -------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".ply", ".xyz", ".csv"])
def test_each_point_file_holds_the_points_and_their_normals(
    ply: Path, tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / f"out{suffix}"
    code, stdout, _ = run(["points", str(ply), "-o", str(out), "--k", "16"], capsys)
    assert (code, stdout) == (0, f"wrote {N} normals to {out}\n")
    written, source = read_points(out), read_points(ply)
    expected = point_normals(source.points, k=16).normals
    np.testing.assert_array_equal(written.points, source.points)
    assert written.normals is not None
    np.testing.assert_array_equal(written.normals, expected)  # repr and doubles: exact
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(["ball.ply", out.name])


def test_npy_holds_the_normals_in_input_order(
    xyz: Path, tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray]
) -> None:
    out = tmp_path / "normals.NPY"  # the suffix in any case
    assert main(["points", str(xyz), "-o", str(out), "--orient", "none"]) == 0
    normals = np.load(out)
    assert normals.dtype == np.float64 and normals.shape == (N, 3)
    np.testing.assert_array_equal(normals, point_normals(cloud[0], orient="none").normals)


def test_points_without_a_normal_are_zero_rows_and_said(
    tmp_path: Path, cloud: tuple[np.ndarray, np.ndarray], capsys: pytest.CaptureFixture[str]
) -> None:
    path, out = tmp_path / "lonely.ply", tmp_path / "n.npy"
    path.write_bytes(write_points(np.vstack([cloud[0], LONERS])))
    code, stdout, _ = run(["points", str(path), "--radius", "0.5", "-o", str(out)], capsys)
    assert code == 0
    assert stdout == (
        f"wrote {N + 2} normals to {out}; 2 points without a normal are zero rows "
        "(2 too_few_neighbours); see `mesh-normal points FILE`\n"
    )
    normals = np.load(out)
    assert not normals[N:].any() and np.allclose(np.linalg.norm(normals[:N], axis=1), 1)


def test_unoriented_normals_are_said_when_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, out = plane_pcd(tmp_path / "plane.pcd", "0 0 0 1 0 0 0"), tmp_path / "n.csv"
    # The plane's normals are at right angles to +x: no side.
    code, stdout, _ = run(["points", str(path), "--direction=1,0,0", "-o", str(out)], capsys)
    assert (code, stdout) == (
        0,
        f"wrote 100 normals to {out}; 100 normals unoriented (their side could not be "
        "decided); see `mesh-normal points FILE`\n",
    )


def test_npy_rows_are_the_file_rows_when_it_left_some_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A PCD's NaN points are left out when read; the .npy keeps a (zero) row for each, so
    that row i is the file's point i. The point files hold the points read."""
    x, y = np.meshgrid(np.arange(10.0), np.arange(10.0))
    rows = [f"{a} {b} 0" for a, b in zip(x.ravel(), y.ravel(), strict=True)]
    rows[7] = rows[50] = "nan nan nan"
    path, out = tmp_path / "holes.pcd", tmp_path / "n.npy"
    path.write_bytes(pcd_header("x y z", "4 4 4", "F F F", 100) + "\n".join(rows).encode() + b"\n")
    code, stdout, _ = run(["points", str(path), "--direction=0,0,1", "-o", str(out)], capsys)
    assert code == 0
    assert stdout == (f"wrote 100 normals to {out}; 2 rows the file left out are zero rows too\n")
    expected = np.tile([0.0, 0.0, 1.0], (100, 1))
    expected[[7, 50]] = 0.0
    np.testing.assert_array_equal(np.load(out), expected)
    ply = tmp_path / "n.ply"
    assert run(["points", str(path), "--direction=0,0,1", "-o", str(ply)], capsys)[1] == (
        f"wrote 98 normals to {ply}\n"
    )
    summary = run(["points", str(path)], capsys)[1].splitlines()
    assert summary[:2] == [
        "holes.pcd: 98 points (PCD), 98 with a normal, 0 without",
        "the file holds 100 rows: 2 left out",
    ]
    assert summary[2].startswith("note: 2 ")


def test_json_with_an_output_names_it(
    ply: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o.csv"
    found = json.loads(run(["points", str(ply), "-o", str(out), "--json"], capsys)[1])
    assert found["output"] == str(out) and out.read_text().startswith("x,y,z,nx,ny,nz\n")


def test_the_input_is_never_overwritten(ply: Path, capsys: pytest.CaptureFixture[str]) -> None:
    before = ply.read_bytes()
    spelled = ply.parent / "." / ply.name  # another spelling of the same path
    for target in (ply, spelled):
        code, out, err = run(["points", str(ply), "-o", str(target)], capsys)
        assert code == 2 and not out
        assert (
            err == f"mesh-normal: {target} is the input file; write the normals to another file\n"
        )
    assert ply.read_bytes() == before
    assert [path.name for path in ply.parent.iterdir()] == ["ball.ply"]
    link = ply.with_name("link.ply")
    link.hardlink_to(ply)
    assert run(["points", str(ply), "-o", str(link)], capsys)[0] == 2
    assert ply.read_bytes() == before


def test_an_output_is_replaced_whole(ply: Path, tmp_path: Path) -> None:
    out = tmp_path / "out.xyz"
    out.write_text("old\n" * 10_000)
    assert main(["points", str(ply), "-o", str(out)]) == 0
    assert read_points(out).normals is not None and "old" not in out.read_text()


# --- orientation options ------------------------------------------------------------------------


@pytest.mark.parametrize(("viewpoint", "sign"), [("0 0 5 1 0 0 0", 1.0), ("0 0 -5 1 0 0 0", -1.0)])
def test_viewpoint_comes_from_the_pcd_file(
    tmp_path: Path, viewpoint: str, sign: float, capsys: pytest.CaptureFixture[str]
) -> None:
    path, out = plane_pcd(tmp_path / "plane.pcd", viewpoint), tmp_path / "n.npy"
    code, _, _ = run(["points", str(path), "--orient", "viewpoint", "-o", str(out)], capsys)
    assert code == 0
    np.testing.assert_array_equal(np.load(out), np.tile([0.0, 0.0, sign], (100, 1)))
    summary = run(["points", str(path), "--orient", "viewpoint"], capsys)[1]
    assert f"oriented towards the viewpoint (0, 0, {sign * 5:g})" in summary


def test_a_given_viewpoint_or_direction_chooses_the_orientation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, out = plane_pcd(tmp_path / "plane.pcd", "0 0 5 1 0 0 0"), tmp_path / "n.npy"
    assert main(["points", str(path), "--viewpoint=0,0,-3", "-o", str(out)]) == 0
    assert (np.load(out)[:, 2] == -1).all()  # the option wins over the file's
    assert main(["points", str(path), "--direction", "0, 0, 1", "-o", str(out)]) == 0
    assert (np.load(out)[:, 2] == 1).all()
    capsys.readouterr()  # the two lines that say what was written
    found = json.loads(run(["points", str(path), "--direction=1,0,-1", "--json"], capsys)[1])
    assert found["orient"] == "direction" and found["direction"] == [1.0, 0.0, -1.0]
    assert found["component_count"] == 1 and found["flipped"] == 100


def test_k_all_within_a_radius(xyz: Path, capsys: pytest.CaptureFixture[str]) -> None:
    found = json.loads(
        run(["points", str(xyz), "--k", "all", "--radius", "0.4", "--json"], capsys)[1]
    )
    assert found["neighbourhood"] == {"k": None, "radius": 0.4}
    assert (
        "every point within 0.4" in run(["points", str(xyz), "--k=all", "--radius=0.4"], capsys)[1]
    )


# --- progress and errors ------------------------------------------------------------------------


def test_progress_over_the_points_on_stderr(
    ply: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(["--progress", "points", str(ply), "-o", str(tmp_path / "n.ply")], capsys)
    assert code == 0
    assert "reading" in err and f"estimating normals [{'#' * 24}] {N} of {N} points" in err
    assert "orienting them (mst)" in err and "writing" in err and err.endswith("done\n")


def test_point_normals_reports_the_finite_points_done(
    cloud: tuple[np.ndarray, np.ndarray],
) -> None:
    calls: list[tuple[int, int]] = []
    points = np.vstack([cloud[0], [[np.nan, 0.0, 0.0]]])
    point_normals(points, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(N, N)]  # one chunk; the NaN row is not counted


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        (["-o", "{dir}/out.obj"], 2, "the output must end in .ply, .xyz, .csv, .npy, not .obj"),
        (["-o", "{dir}/out"], 2, "the output must end in .ply, .xyz, .csv, .npy, not no suffix"),
        (["--orient", "file"], 2, "--orient file needs normals, and {file} stores none"),
        (["--orient", "viewpoint"], 2, "--orient viewpoint needs --viewpoint X,Y,Z: the file"),
        (["--orient", "direction"], 2, "--orient direction needs --direction X,Y,Z"),
        (["--orient", "mst", "--direction=0,0,1"], 2, "--direction is only used with --orient"),
        (["--viewpoint=0,0,1", "--direction=0,0,1"], 2, "--direction is only used with"),
        (["--direction=0,0,0"], 2, "direction must not be zero"),
        (["--k", "all"], 2, "--k all needs --radius"),
        (["-o", "/nonexistent-dir/out.ply"], 4, "cannot write /nonexistent-dir/out.ply"),
    ],
)
def test_errors_are_one_sentence_with_an_exit_code(
    xyz: Path, argv: list[str], code: int, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [arg.replace("{dir}", str(xyz.parent)) for arg in argv]
    exit_code, out, err = run(["points", str(xyz), *argv], capsys)
    assert exit_code == code and not out
    assert err.startswith("mesh-normal: ") and err.count("\n") == 1
    assert message.replace("{file}", str(xyz)) in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--viewpoint=-1,0,x"], "argument --viewpoint: must be three finite numbers"),
        (["--viewpoint", "1,2"], "like 0,0,1, not '1,2'"),
        (["--direction", "nan,0,1"], "argument --direction: must be three finite numbers"),
        (["--k", "2"], "argument --k: must be a whole number of at least 3"),
        (["--k", "3.5"], "argument --k: must be a whole number"),
        (["--radius", "-1"], "argument --radius: must be a positive number, not '-1'"),
        (["--radius", "inf"], "argument --radius: must be a positive number"),
        (["--max-angle", "100"], "argument --max-angle: must be in degrees, over 0 and at most 90"),
        (["--orient", "up"], "argument --orient: invalid choice: 'up'"),
    ],
)
def test_bad_numbers_are_usage_errors_naming_the_option(
    xyz: Path, argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["points", str(xyz), *argv])
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


def test_unreadable_files_exit_3(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "missing.ply"
    code, _, err = run(["points", str(missing)], capsys)
    assert code == 3 and err == f"mesh-normal: cannot read {missing}: No such file or directory\n"
    broken = tmp_path / "broken.ply"
    broken.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nend_header\n")
    code, _, err = run(["points", str(broken)], capsys)
    assert code == 3 and err.startswith(f"mesh-normal: {broken}: ") and err.count("\n") == 1
    empty = tmp_path / "empty.xyz"
    empty.write_bytes(b"")
    code, _, err = run(["points", str(empty)], capsys)
    assert (code, err) == (3, f"mesh-normal: {empty}: The file is empty (0 bytes).\n")


@pytest.mark.parametrize("argv", [["points"], ["points", "a.ply", "--k", "2"]])
def test_usage_errors_answer_before_the_library_loads(argv: list[str]) -> None:
    from tests.mesh_normal.cli.test_start import HEAVY, modules_after

    loaded, code = modules_after(argv)
    assert code == 2
    assert not sorted(name for name in loaded if name.split(".")[0] in HEAVY)


def test_counts_in_words_are_singular_or_plural() -> None:
    found = {
        "component_count": 1,
        "components": [{"points": 1, "flipped": 1, "unoriented": 0, "reason": "", "seed": 0}],
        "flipped": 1,
        "unoriented": 0,
        "orient": "mst",
    }
    assert component_lines(found) == [
        "orientation: 1 part; 1 normal flipped, 0 unoriented",
        "  part 1: 1 point, 1 flipped, 0 unoriented, seed point 0",
    ]
    found.update(component_count=2, flipped=2)
    assert component_lines(found)[0] == "orientation: 2 parts; 2 normals flipped, 0 unoriented"
    written = {
        "file_points": 3,
        "points": 2,
        "without_normal": 1,
        "counts": {"ok": 1, "too_few_neighbours": 1, "unoriented": 1},
    }
    assert written_line(written, "n.npy", "npy") == (
        "wrote 3 normals to n.npy; 1 point without a normal is a zero row (1 too_few_neighbours); "
        "1 normal unoriented (its side could not be decided); 1 row the file left out is a zero "
        "row too; see `mesh-normal points FILE`"
    )
