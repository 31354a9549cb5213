"""The Dask engine on a ``distributed.LocalCluster`` of two worker processes started here:
the same rows as the local engine, a worker killed mid-way, a file that hangs."""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import distributed
import pytest

import mesh_normal as mn
from mesh_normal.datasets import cluster
from mesh_normal.datasets.cluster import memory_estimate, run_dask, task_key
from mesh_normal.datasets.inputs import discover
from mesh_normal.datasets.local import run_local
from mesh_normal.datasets.tasks import BatchOptions, FileTask

Dataset = tuple[Path, dict[str, dict[str, Any]]]

#: Seconds the file that hangs is given: long enough to kill its worker while it waits.
TIMEOUT = 4.0


def start_cluster() -> Any:
    return distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",
        silence_logs=50,
    )


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    with start_cluster() as local_cluster, distributed.Client(local_cluster) as found:
        yield found


def rows_by_path(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    return {row["path"]: {**row, "wall_seconds": None} for row in rows}


@pytest.fixture(scope="module")
def batch(
    dataset: Dataset, tmp_path_factory: pytest.TempPathFactory
) -> tuple[list[FileTask], BatchOptions, dict[str, dict[str, Any]]]:
    """The dataset's files and one that hangs (a named pipe), with the local engine's rows."""
    root, _ = dataset
    hang = tmp_path_factory.mktemp("hang") / "hang.stl"
    os.mkfifo(hang)  # reading it blocks until someone writes: forever here
    tasks = [*discover([str(root)]).tasks, FileTask(str(hang), hang.as_posix(), 0)]
    options = BatchOptions(out=str(tmp_path_factory.mktemp("out")), timeout=TIMEOUT)
    local = rows_by_path(list(run_local(tasks, options, workers=2)))
    assert len(local) == len(tasks) >= 51
    assert local[hang.as_posix()]["status"] == "timed_out"
    return tasks, options, local


def test_the_cluster_gives_the_local_engines_rows(client: Any, batch: Any) -> None:
    tasks, options, local = batch
    rows = list(run_dask(tasks, options, client))
    assert len(rows) == len(tasks)  # each file once
    assert rows_by_path(rows) == local
    statuses = {row["status"] for row in rows}
    assert {"ok", "problems", "unreadable", "timed_out"} <= statuses


def test_an_address_makes_its_own_client(client: Any, batch: Any) -> None:
    tasks, options, local = batch
    address = client.scheduler.address
    few = [task for task in tasks if task.path.endswith(("cube_01.stl", "inside_out.stl"))]
    rows = rows_by_path(list(run_dask(few, options, address)))
    assert rows == {task.path: local[task.path] for task in few}


def test_a_worker_killed_mid_way_loses_no_file_and_repeats_none(batch: Any) -> None:
    tasks, options, local = batch
    hang = next(task for task in tasks if task.path.endswith("hang.stl"))
    key = task_key(hang, options)
    with start_cluster() as local_cluster, distributed.Client(local_cluster) as own:
        rows = run_dask(tasks, options, own)
        found = [next(rows)]
        holder = _worker_holding(own, key)  # the worker waiting on the pipe, for 4 s
        pids = own.run(os.getpid, workers=[holder])
        os.kill(pids[holder], signal.SIGKILL)
        found += list(rows)
        assert holder not in own.scheduler_info()["workers"]  # it died (the nanny may restart it)
    assert len(found) == len(tasks)
    assert len({row["path"] for row in found}) == len(tasks)
    assert rows_by_path(found) == local  # the hung file was run again and timed out again


def _worker_holding(client: Any, key: str) -> str:
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        for worker, keys in client.processing().items():
            if key in keys:
                return str(worker)
        time.sleep(0.05)
    raise AssertionError("no worker took the file that hangs")


def test_workers_with_a_memory_resource_get_the_estimate(batch: Any) -> None:
    tasks, options, local = batch
    few = [task for task in tasks if task.path.endswith((".stl", ".ply"))][:6]
    with (
        distributed.LocalCluster(
            n_workers=1,
            threads_per_worker=2,
            processes=True,
            host="127.0.0.1",
            dashboard_address=":0",
            silence_logs=50,
            resources={cluster.MEMORY: 200 * 2**20},
        ) as local_cluster,
        distributed.Client(local_cluster) as own,
    ):
        assert cluster._memory_resource(own) == 200 * 2**20
        rows = rows_by_path(list(run_dask(few, options, own)))
    assert rows == {task.path: local[task.path] for task in few}


def test_the_estimate_follows_the_format_and_never_exceeds_what_a_worker_declares() -> None:
    stl = FileTask("a.stl", "a.stl", 100 * 2**20)
    gltf = FileTask("a.gltf", "a.gltf", 100 * 2**20)
    assert memory_estimate(stl) == 600 * 2**20
    assert memory_estimate(gltf) == 2600 * 2**20
    assert memory_estimate(FileTask("t.obj", "t.obj", 10)) == cluster.MEMORY_FLOOR


def test_memory_urls_are_refused_with_a_sentence(client: Any) -> None:
    task = FileTask("memory://a.stl", "memory://a.stl", 10)
    with pytest.raises(ValueError, match=r"^memory://a.stl is in this process's memory"):
        list(run_dask([task], BatchOptions(out="/tmp/unused"), client))


def test_the_command_runs_on_the_cluster_and_writes_the_same_table(
    client: Any, dataset: Dataset, tmp_path: Path
) -> None:
    import pyarrow.parquet as pq

    from mesh_normal.cli import main

    root, _ = dataset
    cubes = str(root / "cubes" / "deeper")
    local = mn.batch(cubes, out=tmp_path / "local", workers=1)
    address = client.scheduler.address
    code = main(["batch", cubes, "--out", str(tmp_path / "dask"), "--scheduler", address, "--json"])
    assert code == 0
    table = pq.read_table(tmp_path / "dask" / "report.parquet")
    assert table.num_rows == local.num_rows == 10
    drop = ["wall_seconds"]
    assert table.drop_columns(drop).to_pylist() == local.drop_columns(drop).to_pylist()
