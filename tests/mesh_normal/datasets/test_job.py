"""One file's job, run in this process: its row, its hash, its outputs."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import fsspec
import numpy as np
import pytest

import mesh_normal as mn
from mesh_normal.datasets.job import output_name, relative_key, run_file
from mesh_normal.datasets.schema import NAMES
from mesh_normal.datasets.tasks import BatchOptions, FileTask
from tests.mesh_normal.datasets.dataset import CUBE_FACES, CUBE_VERTICES, cube, cube_row

Dataset = tuple[Path, dict[str, dict[str, Any]]]


def task_of(path: Path) -> FileTask:
    return FileTask(str(path), path.as_posix(), path.stat().st_size)


def test_a_cube_row(tmp_path: Path) -> None:
    path = tmp_path / "cube.ply"
    path.write_bytes(cube(3, "ply"))
    row = run_file(task_of(path), BatchOptions(out=str(tmp_path / "out")))
    assert set(row) == set(NAMES)
    for name, value in cube_row(3).items():
        assert row[name] == value, name
    assert row["area"] == 54.0 and row["volume"] == 27.0
    assert row["hash"] == hashlib.blake2b(path.read_bytes(), digest_size=16).hexdigest()
    assert row["format"] == "ply"
    assert row["kind"] == "mesh"
    assert row["outputs"] == []
    assert row["wall_seconds"] > 0


def test_face_normals_are_written_as_npy(tmp_path: Path) -> None:
    path = tmp_path / "in" / "cube.stl"
    path.parent.mkdir()
    path.write_bytes(cube(2, "stl"))
    task = FileTask(str(path), "in/cube.stl", path.stat().st_size)
    row = run_file(task, BatchOptions(out=str(tmp_path / "out"), normals="face"))
    assert row["outputs"] == [f"{tmp_path}/out/normals/in/cube.stl.face.npy"]
    normals = np.load(row["outputs"][0])
    # The first two faces lie in z = 0 and face down, the next two in z = 2 and face up.
    assert normals.shape == (12, 3)
    np.testing.assert_array_equal(normals[:4], [[0, 0, -1], [0, 0, -1], [0, 0, 1], [0, 0, 1]])
    assert not list((tmp_path / "out" / "normals" / "in").glob(".*"))  # no temporary left


def test_vertex_normals_as_ply_are_the_mesh_with_them(tmp_path: Path) -> None:
    path = tmp_path / "cube.obj"
    path.write_bytes(cube(1, "obj"))
    options = BatchOptions(out=str(tmp_path / "out"), normals="vertex", normals_format="ply")
    row = run_file(task_of(path), options)
    written = mn.read_mesh(row["outputs"][0])
    assert len(written.vertices) == 8 and len(written.faces) == 12
    # A cube's corner (0, 0, 0): the three faces around it weigh alike, so (-1, -1, -1) / √3.
    assert written.file_vertex_normals is not None
    corner = written.file_vertex_normals[0]
    np.testing.assert_allclose(corner, -np.ones(3) / np.sqrt(3), atol=1e-6)


def test_fix_writes_the_fixed_mesh_only_when_it_changes(tmp_path: Path) -> None:
    inside_out = tmp_path / "inside_out.stl"
    inside_out.write_bytes(mn.write_mesh(CUBE_VERTICES, CUBE_FACES[:, ::-1], "stl"))
    fine = tmp_path / "fine.stl"
    fine.write_bytes(cube(1, "stl"))
    options = BatchOptions(out=str(tmp_path / "out"), fix=True)
    row = run_file(task_of(inside_out), options)
    assert row["orientation"] == "inward" and row["faces_flipped"] == 12
    fixed = row["outputs"][0]
    assert fixed.endswith("/fixed" + str(tmp_path) + "/inside_out.stl")
    report = mn.analyse(fixed)
    assert report.orientation == "outward" and report.volume == 1.0
    assert run_file(task_of(fine), options)["outputs"] == []


def test_an_unreadable_file_is_a_row_with_its_reason(tmp_path: Path) -> None:
    missing = FileTask(str(tmp_path / "gone.stl"), "gone.stl", 10)
    row = run_file(missing, BatchOptions(out=str(tmp_path)))
    assert row["status"] == "unreadable"
    assert row["error"].startswith("It cannot be read: ")
    assert row["hash"] is None
    broken = tmp_path / "broken.off"
    broken.write_bytes(b"OFF\n3 1 0\n0 0 0\n")
    row = run_file(task_of(broken), BatchOptions(out=str(tmp_path)))
    assert row["status"] == "unreadable" and row["error"].endswith(".")
    assert row["hash"] == hashlib.blake2b(b"OFF\n3 1 0\n0 0 0\n", digest_size=16).hexdigest()


def test_max_file_mb_refuses_before_reading(tmp_path: Path) -> None:
    # The file does not exist: had it been read, the row would say unreadable.
    task = FileTask(str(tmp_path / "absent.stl"), "absent.stl", 3_000_000)
    row = run_file(task, BatchOptions(out=str(tmp_path), max_file_mb=2))
    assert row["status"] == "too_large"
    assert row["error"] == "It is 3.0 MB, over the limit of 2 MB (--max-file-mb)."


def test_a_point_cloud_row(dataset: Dataset, tmp_path: Path) -> None:
    root, _ = dataset
    options = BatchOptions(out=str(tmp_path), points=True, normals="vertex")
    row = run_file(task_of(root / "other" / "cloud.xyz"), options)
    assert row["kind"] == "points" and row["format"] == "xyz"
    assert row["points"] == 200 and row["points_with_normal"] == 200
    assert row["status"] == "ok" and row["faces"] is None
    normals = np.load(row["outputs"][0])
    points = np.loadtxt(root / "other" / "cloud.xyz")
    # On the unit sphere each normal is its point, outward; a plane fitted to 30 of 200
    # points (a cap some 45 degrees wide) tilts it a little where the cap is lopsided.
    assert np.einsum("ij,ij->i", normals, points).min() > 0.9


def test_memory_urls_in_and_out() -> None:
    fs = fsspec.filesystem("memory")
    fs.pipe("/job14/in/cube.off", cube(2, "off"))
    task = FileTask("memory://job14/in/cube.off", "memory://job14/in/cube.off", 0)
    row = run_file(task, BatchOptions(out="memory://job14/out", normals="face"))
    assert row["status"] == "ok" and row["volume"] == 8.0
    assert row["outputs"] == ["memory://job14/out/normals/job14/in/cube.off.face.npy"]
    assert fs.exists("/job14/out/normals/job14/in/cube.off.face.npy")
    fs.rm("/job14", recursive=True)


@pytest.mark.parametrize(
    ("path", "key"),
    [
        ("a/b.stl", "a/b.stl"),
        ("/data/b.stl", "data/b.stl"),
        ("../../up/b.stl", "up/b.stl"),
        ("s3://bucket/x/b.stl", "bucket/x/b.stl"),
        ("C:\\data\\b.stl", "C:/data/b.stl"),
    ],
)
def test_outputs_stay_under_the_output_folder(path: str, key: str) -> None:
    assert relative_key(path) == key
    options = BatchOptions(out="o", normals="corner")
    assert output_name(FileTask(path, path, 0), options) == f"normals/{key}.corner.npy"
