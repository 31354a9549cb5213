"""``mesh-normal batch``: the summary, usage errors, and a run killed and interrupted."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest

from mesh_normal.cli import main
from tests.mesh_normal.datasets.dataset import MESH_FILES, cube, hear_ctrl_c, make_dataset
from tests.paths import ROOT

Dataset = tuple[Path, dict[str, dict[str, Any]]]
#: How long the test waits for a subprocess's rows at most (a guard, not a timing).
PATIENCE = 300.0


def test_the_json_summary(
    dataset: Dataset, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root, _ = dataset
    code = main(["batch", str(root), "--out", str(tmp_path), "--workers", "2", "--json"])
    assert code == 0
    captured = capsys.readouterr()
    found = json.loads(captured.out)
    assert found["files"] == MESH_FILES
    assert found["by_status"] == {
        "ok": 42,
        "problems": 6,
        "unreadable": 4,
        "too_large": 0,
        "timed_out": 0,
    }
    assert found["by_problem"]["inward"] == 1
    assert found["by_problem"]["open"] >= 2  # the open box, the teapot
    assert found["skipped"] == 2 and found["reused"] == 0 and found["run"] == MESH_FILES
    assert len(found["slowest"]) == 5
    assert found["report"] == f"{tmp_path}/report.parquet"
    # Without a terminal the progress is plain lines; the last one at the end.
    assert f"{MESH_FILES}/{MESH_FILES} files (100%)" in captured.err.splitlines()[-1]


def test_the_text_summary(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "a.obj").write_bytes(cube(1, "obj"))
    (tmp_path / "in" / "b.stl").write_bytes(b"")
    code = main(["batch", str(tmp_path / "in"), "--out", str(tmp_path / "out"), "--timeout", "0"])
    assert code == 0  # a batch with an unreadable file ran
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("2 files: 2 run in ")
    assert lines[1] == "by status: ok 1, problems 0, unreadable 1, too_large 0, timed_out 0"
    assert lines[-1] == f"wrote {tmp_path}/out/report.parquet"


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["/no/such/folder"], "is not a file, a folder or a pattern"),
        (["x", "--normals", "corner", "--format", "ply"], "corner normals do not fit"),
        (["x", "--workers", "0"], "must be a whole number of 1 or more"),
        (["x", "--timeout", "soon"], "must be a number"),
    ],
)
def test_usage_errors_exit_2(
    argv: list[str], words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    try:
        code = main(["batch", *argv, "--out", str(tmp_path)])
    except SystemExit as stop:  # argparse's own errors
        code = int(stop.code or 0)
    assert code == 2
    assert words in capsys.readouterr().err


def start(root: Path, out: Path) -> subprocess.Popen[str]:
    command = [sys.executable, "-m", "mesh_normal", "batch", str(root), "--out", str(out)]
    command += ["--workers", "1", "--flush-rows", "5", "--timeout", "600", "--fix"]
    return subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip


class Watched:
    """A batch with its progress bar forced on, its stderr read as it comes."""

    def __init__(self, root: Path, out: Path) -> None:
        command = [sys.executable, "-m", "mesh_normal", "--progress", "batch", str(root)]
        command += ["--out", str(out), "--workers", "1", "--flush-rows", "5", "--fix"]
        command += ["--timeout", "600"]
        # A run that does not end is aborted: faulthandler then writes every thread's stack.
        env = {**os.environ, "PYTHONFAULTHANDLER": "1"}
        self.process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE,
                                        stderr=subprocess.PIPE, text=True, env=env,
                                        preexec_fn=hear_ctrl_c)  # fmt: skip
        self.err: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        while chunk := self.process.stderr.read(1):
            self.err.append(chunk)

    def wait_for(self, text: str) -> None:
        deadline = time.monotonic() + PATIENCE
        while text not in "".join(self.err):
            assert self.process.poll() is None, "".join(self.err)
            assert time.monotonic() < deadline, "".join(self.err)
            time.sleep(0.1)

    def finish(self) -> str:
        try:
            self.process.wait(timeout=PATIENCE)
        except subprocess.TimeoutExpired:
            self.process.send_signal(signal.SIGABRT)  # its threads' stacks, on stderr
            self.process.wait(timeout=PATIENCE)
            self.reader.join(timeout=PATIENCE)
            pytest.fail("the batch did not end:\n" + "".join(self.err)[-6000:])
        self.reader.join()
        assert self.process.stdout is not None
        self.process.stdout.close()
        self.process.stderr.close()  # type: ignore[union-attr]
        return "".join(self.err)


def kept_rows(out: Path) -> int:
    parts = out / ".parts"
    names = list(parts.glob("part-*.parquet")) if parts.exists() else []
    return sum(pq.read_metadata(path).num_rows for path in names)


def wait_for_rows(out: Path, count: int, process: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + PATIENCE
    while kept_rows(out) < count:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no rows came"
        time.sleep(0.2)


def test_killed_and_interrupted_runs_end_with_the_same_table(tmp_path: Path) -> None:
    root = tmp_path / "dataset"
    make_dataset(root)
    # A named pipe sorted last: reading it blocks, so each run below stops there, its other
    # files done, until the test stops it.
    hang = root / "zz" / "hang.stl"
    hang.parent.mkdir()
    os.mkfifo(hang)
    out = tmp_path / "out"

    killed = Watched(root, out)
    wait_for_rows(out, 20, killed.process)
    killed.process.send_signal(signal.SIGKILL)  # a killed machine: rows not in a part are lost
    killed.finish()
    after_kill = kept_rows(out)
    assert 20 <= after_kill <= MESH_FILES

    interrupted = Watched(root, out)
    interrupted.wait_for(f"{MESH_FILES}/{MESH_FILES + 1} files")  # all but the pipe
    interrupted.process.send_signal(signal.SIGINT)  # Ctrl-C
    err = interrupted.finish()
    assert interrupted.process.returncode == 130, err
    assert "the finished rows are kept: run the same command again to finish" in err
    paths = pq.read_table(out / ".parts").column("path").to_pylist()
    assert len(paths) == len(set(paths)) == MESH_FILES  # each file once; the pipe has none

    hang.unlink()
    hang.write_bytes(cube(7, "stl"))
    finished = start(root, out)
    stdout, err = finished.communicate(timeout=PATIENCE)
    assert finished.returncode == 0, err
    assert stdout.startswith(f"{MESH_FILES + 1} files: 1 run in ")

    whole = tmp_path / "whole"
    uninterrupted = start(root, whole)
    assert uninterrupted.communicate(timeout=PATIENCE)[0].startswith(f"{MESH_FILES + 1} files")
    mine = pq.read_table(out / "report.parquet").drop_columns(["wall_seconds"]).to_pylist()
    theirs = pq.read_table(whole / "report.parquet").drop_columns(["wall_seconds"]).to_pylist()
    for row in theirs:
        row["outputs"] = [path.replace(str(whole), str(out)) for path in row["outputs"]]
    assert mine == theirs
    assert mine[-1]["path"].endswith("zz/hang.stl") and mine[-1]["volume"] == 343.0


def test_points(dataset: Dataset, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root, _ = dataset
    argv = ["batch", str(root / "other"), "--out", str(tmp_path), "--points", "--json"]
    assert main([*argv, "--normals", "vertex", "--format", "ply"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert found["by_status"]["ok"] == 1 and found["by_status"]["unreadable"] == 1
    table = pq.read_table(tmp_path / "report.parquet").to_pylist()
    cloud, notes = table
    assert cloud["kind"] == "points" and cloud["points"] == 200
    assert cloud["outputs"] == [
        f"{tmp_path}/normals/{root.as_posix()[1:]}/other/cloud.xyz.points.ply"
    ]
    assert notes["path"].endswith("notes.txt") and notes["status"] == "unreadable"


def test_the_progress_line() -> None:
    from mesh_normal.datasets.command import duration, progress_line
    from mesh_normal.datasets.driver import BatchProgress

    # 100 kept from before, 20 run in 4 s: 5 files/s, 880 left at 5 a second is 176 s.
    state = BatchProgress(done=120, total=1_000, failures=3, reused=100, elapsed=4.0, row={})
    assert progress_line(state) == "120/1,000 files (12%) · 5.0 files/s · 3 failed · 2 m 56 s left"
    done = BatchProgress(done=1_000, total=1_000, failures=0, reused=0, elapsed=50.0, row={})
    assert progress_line(done) == "1,000/1,000 files (100%) · 20.0 files/s · 0 failed"
    assert [duration(s) for s in (42.4, 185, 7_800)] == ["42 s", "3 m 05 s", "2 h 10 m"]
