"""Which files a batch finds: folders, globs, single files, memory:// URLs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import fsspec
import pytest

from mesh_normal.datasets.inputs import InputError, discover
from tests.mesh_normal.datasets.dataset import MESH_FILES, SKIPPED

Dataset = tuple[Path, dict[str, dict[str, Any]]]


def test_a_folder_gives_its_meshes_sorted(dataset: Dataset) -> None:
    root, expected = dataset
    found = discover([str(root)])
    paths = [task.path for task in found.tasks]
    assert paths == sorted(expected)
    assert len(paths) == MESH_FILES
    assert found.skipped == SKIPPED  # the point cloud and the notes
    first = found.tasks[0]
    assert Path(first.url).is_absolute()
    assert first.size == Path(first.url).stat().st_size


def test_a_file_given_twice_is_one_task(dataset: Dataset) -> None:
    root, _ = dataset
    cube = f"{root.as_posix()}/cubes/cube_01.obj"
    found = discover([cube, str(root / "cubes"), cube])
    assert [task.path for task in found.tasks].count(cube) == 1


def test_a_glob_matches_recursively(dataset: Dataset) -> None:
    root, expected = dataset
    found = discover([f"{root}/**/*.stl"])
    stl = sorted(path for path in expected if path.endswith(".stl"))
    assert [task.path for task in found.tasks] == stl


def test_a_file_named_alone_is_taken_whatever_its_suffix(dataset: Dataset) -> None:
    root, _ = dataset
    found = discover([str(root / "other" / "notes.txt")])
    assert [task.path for task in found.tasks] == [str(root / "other" / "notes.txt")]


def test_points_take_the_point_cloud_suffixes(dataset: Dataset) -> None:
    root, _ = dataset
    found = discover([str(root / "other")], points=True)
    assert [Path(task.path).name for task in found.tasks] == ["cloud.xyz", "notes.txt"]
    assert found.skipped == 0


def test_hidden_files_and_the_output_folder_are_not_inputs(tmp_path: Path) -> None:
    (tmp_path / "a.stl").write_bytes(b"solid a\nendsolid a\n")
    (tmp_path / ".hidden.stl").write_bytes(b"x")
    (tmp_path / ".git").mkdir()
    (tmp_path / ".git" / "b.stl").write_bytes(b"x")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "c.stl").write_bytes(b"x")
    found = discover([str(tmp_path)], exclude=str(tmp_path / "out"))
    assert [Path(task.path).name for task in found.tasks] == ["a.stl"]


@pytest.mark.parametrize("given", ["/no/such/folder", "/no/such/*.stl", "memory://nothing/here"])
def test_an_input_that_names_nothing_is_an_error(given: str) -> None:
    with pytest.raises(InputError, match=r"not a file|matches no file"):
        discover([given])


def test_memory_urls() -> None:
    fs = fsspec.filesystem("memory")
    fs.pipe("/inputs14/a/b.stl", b"0123456789")
    fs.pipe("/inputs14/c.obj", b"v 0 0 0\n")
    fs.pipe("/inputs14/read.me", b"x")
    found = discover(["memory://inputs14"])
    assert [(task.path, task.size) for task in found.tasks] == [
        ("memory://inputs14/a/b.stl", 10),
        ("memory://inputs14/c.obj", 8),
    ]
    assert found.skipped == 1
    globbed = discover(["memory://inputs14/**/*.stl"])
    assert [task.path for task in globbed.tasks] == ["memory://inputs14/a/b.stl"]
    fs.rm("/inputs14", recursive=True)
