"""The persistent worker process: the time limit, the memory limit, a file too large."""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import mesh_normal as mn
from mesh_normal.datasets.runner import FileRunner, RunnerError, shared_runner
from mesh_normal.datasets.tasks import BatchOptions, FileTask
from tests.mesh_normal.datasets.dataset import cube


@pytest.fixture(scope="module")
def runner() -> Iterator[FileRunner]:
    found = FileRunner()
    yield found
    found.close()


def task_of(path: Path) -> FileTask:
    return FileTask(str(path), path.as_posix(), path.stat().st_size)


def grid(side: int) -> bytes:
    """A flat grid of side x side vertices as a binary PLY: 2 (side - 1)² faces."""
    x, y = np.meshgrid(np.arange(side, dtype=np.float64), np.arange(side, dtype=np.float64))
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(side * side)])
    index = np.arange(side * side).reshape(side, side)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[:-1, 1:].ravel(), index[1:, 1:].ravel()
    faces = np.vstack([np.column_stack([a, b, c]), np.column_stack([b, d, c])])
    return mn.write_mesh(vertices, faces, "ply")


def test_a_file_that_hangs_is_timed_out_and_the_next_one_runs(
    runner: FileRunner, tmp_path: Path
) -> None:
    hang = tmp_path / "hang.stl"
    os.mkfifo(hang)  # opening it for reading blocks until someone writes: forever here
    fine = tmp_path / "fine.stl"
    fine.write_bytes(cube(1, "stl"))
    options = BatchOptions(out=str(tmp_path / "out"), timeout=1.0)
    assert runner.run(task_of(fine), options)["status"] == "ok"  # a child is running
    before = runner.started
    row = runner.run(task_of(hang), options)
    assert row["status"] == "timed_out"
    assert row["error"] == "It took longer than the limit of 1 s (--timeout)."
    assert row["path"] == hang.as_posix() and row["hash"] is None
    after = runner.run(task_of(fine), options)
    assert after["status"] == "ok" and after["volume"] == 1.0
    assert runner.started == before + 1  # the hung child was replaced


def test_the_memory_limit_makes_a_too_large_row(runner: FileRunner, tmp_path: Path) -> None:
    big = tmp_path / "big.ply"
    big.write_bytes(grid(500))  # 498,002 faces, 12 MB: some 200 MB to analyse
    fine = tmp_path / "fine.obj"
    fine.write_bytes(cube(2, "obj"))
    limited = BatchOptions(out=str(tmp_path / "out"), memory_mb=20)
    row = runner.run(task_of(big), limited)
    assert row["status"] == "too_large"
    assert "memory" in row["error"]
    assert runner.run(task_of(fine), limited)["status"] == "ok"  # the same child goes on
    unlimited = runner.run(task_of(big), BatchOptions(out=str(tmp_path / "out")))
    assert unlimited["status"] == "problems"  # open: every edge of the border
    assert unlimited["faces"] == 498_002


def test_max_file_mb_needs_no_worker(tmp_path: Path) -> None:
    fresh = FileRunner()
    task = FileTask(str(tmp_path / "nowhere.stl"), "nowhere.stl", 5_000_000)
    row = fresh.run(task, BatchOptions(out=str(tmp_path), max_file_mb=1))
    assert row["status"] == "too_large"
    assert "--max-file-mb" in row["error"]
    assert fresh.started == 0


def test_a_worker_that_dies_is_a_too_large_row(runner: FileRunner, tmp_path: Path) -> None:
    hang = tmp_path / "hang.stl"
    os.mkfifo(hang)
    import threading

    killer = threading.Timer(0.5, runner.kill)  # as the kernel's OOM killer would
    killer.start()
    row = runner.run(task_of(hang), BatchOptions(out=str(tmp_path), timeout=120))
    killer.join()
    assert row["status"] == "too_large"
    assert row["error"] == "Its worker process died (signal SIGKILL): out of memory?"


def test_the_shared_runner_is_one_per_process() -> None:
    assert shared_runner() is shared_runner()


def test_a_runner_killed_while_its_child_starts_leaves_no_child(tmp_path: Path) -> None:
    # Ctrl-C in the first second of a batch: the child is still loading the kernels, and is
    # not yet the runner's, when kill() comes.
    path = tmp_path / "cube.stl"
    path.write_bytes(cube(1, "stl"))
    fresh = FileRunner()
    errors: list[BaseException] = []

    def run() -> None:
        try:
            fresh.run(task_of(path), BatchOptions(out=str(tmp_path / "out")))
        except BaseException as error:
            errors.append(error)

    thread = threading.Thread(target=run)
    thread.start()
    fresh.kill()
    thread.join(timeout=120)  # a guard: the child stops itself at its next step
    assert not thread.is_alive()
    assert [str(error) for error in errors] in (
        ["The worker process did not start."],
        ["The batch was stopped."],
    )
    assert fresh._child is None
    with pytest.raises(RunnerError, match="stopped"):
        fresh.run(task_of(path), BatchOptions(out=str(tmp_path / "out")))
