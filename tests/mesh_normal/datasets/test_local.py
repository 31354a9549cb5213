"""The local engine: the same rows on one worker or two, each file once."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

from mesh_normal.datasets.inputs import discover
from mesh_normal.datasets.local import run_local
from mesh_normal.datasets.tasks import BatchOptions
from tests.mesh_normal.datasets.dataset import hear_ctrl_c
from tests.paths import ROOT

Dataset = tuple[Path, dict[str, dict[str, Any]]]


def rows_by_path(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    return {row["path"]: {**row, "wall_seconds": None} for row in rows}


def test_one_and_two_workers_give_the_same_rows(dataset: Dataset, tmp_path: Path) -> None:
    root, expected = dataset
    tasks = discover([str(root)]).tasks
    options = BatchOptions(out=str(tmp_path / "out"))
    one = list(run_local(tasks, options, workers=1))
    two = list(run_local(tasks, options, workers=2))
    assert len(one) == len(two) == len(tasks) == len(expected)
    assert rows_by_path(one) == rows_by_path(two)
    found = rows_by_path(two)
    for path, figures in expected.items():
        for name, value in figures.items():
            assert found[path][name] == value, (path, name)


def test_stopping_early_stops_the_workers(dataset: Dataset, tmp_path: Path) -> None:
    root, _ = dataset
    tasks = discover([str(root / "cubes")]).tasks
    rows = run_local(tasks, BatchOptions(out=str(tmp_path)), workers=2)
    first = next(rows)
    assert first["status"] == "ok"
    rows.close()  # as Ctrl-C does: no exception, no worker left behind


#: In its own process (a regression would hang the waiting thread for good, not fail).
_CTRL_C_ON_A_WORKER = """
import os, signal, sys, threading, time
from mesh_normal.datasets.local import run_local
from mesh_normal.datasets.tasks import BatchOptions, FileTask

folder = sys.argv[1]
hang = os.path.join(folder, "hang.stl")
os.mkfifo(hang)  # reading it blocks: the worker waits on its child meanwhile
rows = run_local([FileTask(hang, hang, 0)], BatchOptions(out=folder, timeout=600), workers=1)
before = set(threading.enumerate())

def interrupt():
    time.sleep(2.0)
    workers = [t for t in threading.enumerate() if t not in before and t.name != "ctrl-c"]
    signal.pthread_kill(workers[0].ident, signal.SIGINT)

threading.Thread(target=interrupt, name="ctrl-c", daemon=True).start()
try:
    next(rows)
except KeyboardInterrupt:
    print("stopped")
"""


def test_a_ctrl_c_that_lands_on_a_worker_thread_still_stops_the_batch(tmp_path: Path) -> None:
    # The system may hand SIGINT to any thread; Python's handler runs in the main thread only
    # when it next runs Python, so the main thread must not wait without a timeout.
    result = subprocess.run(
        [sys.executable, "-c", _CTRL_C_ON_A_WORKER, str(tmp_path)],
        cwd=ROOT, capture_output=True, text=True, timeout=60, preexec_fn=hear_ctrl_c,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == "stopped"
