"""The local engine: the same rows on one worker or two, each file once."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mesh_normal.datasets.inputs import discover
from mesh_normal.datasets.local import run_local
from mesh_normal.datasets.tasks import BatchOptions

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
