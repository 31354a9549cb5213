"""The Dask engine: the same files, rows and limits on an existing ``distributed`` cluster.

:func:`run_dask` submits one Dask task per file. Each task runs on a worker as it does here:
in a :class:`~mesh_normal.datasets.runner.FileRunner` (a child process of the worker, one per
worker thread), so the per-file time and memory limits hold on the cluster too, and a file
that hangs or eats its memory costs that child, never the Dask worker. Everything else is
Dask's own:

- a worker that dies (killed, its machine lost) has its files rescheduled on another by the
  scheduler; ``retries`` covers a task that failed with an exception (a storage hiccup);
- ``as_completed`` gives each file's row as it finishes, and each file is one task with a key
  of its own, so each file ends up in the table exactly once;
- workers that declare a ``MEMORY`` resource (``dask worker ... --resources MEMORY=8e9``)
  get no more files at once than their memory holds: each task asks for its estimate.

Inputs and outputs are URLs that every worker can open (fsspec: ``s3://``, ``gs://``, a shared
file system): a local path must be visible to every worker under the same name.
"""

from __future__ import annotations

import importlib
import threading
from collections.abc import Iterator, Sequence
from pathlib import PurePosixPath
from typing import Any

from mesh_normal.datasets.schema import failed_row
from mesh_normal.datasets.tasks import BatchOptions, FileTask

#: How many times a task that raised (not a file's fault: run_file never raises for that) is
#: tried again. A worker's death is not counted here: the scheduler reschedules its tasks, up
#: to Dask's ``distributed.scheduler.allowed-failures`` deaths (3 by default).
RETRIES = 2

#: The worker resource a task asks for (bytes of memory), when the workers declare it.
MEMORY = "MEMORY"

#: Peak memory of a file's report per byte of the file, by format (``make bench-memory``; the
#: web app's admission control uses the same measurements); formats not measured take 26.
MEMORY_PER_BYTE = {"stl": 6, "obj": 6, "ply": 7, "off": 7, "glb": 9}
UNMEASURED_PER_BYTE = 26
#: A file's report never needs less than this (the worker's child and its arrays).
MEMORY_FLOOR = 64 * 2**20

#: fsspec protocols whose files live in one process, which no worker sees.
LOCAL_ONLY = ("memory://",)


def dask_missing() -> str:
    return "The Dask engine needs dask's distributed scheduler: pip install 'mesh-normal[dask]'."


def memory_estimate(task: FileTask) -> int:
    """Bytes of memory ``task``'s report may take, from its size and suffix."""
    suffix = PurePosixPath(task.path).suffix.lower().lstrip(".")
    factor = MEMORY_PER_BYTE.get(suffix, UNMEASURED_PER_BYTE)
    return max(MEMORY_FLOOR, int(task.size * factor))


def task_key(task: FileTask, options: BatchOptions) -> str:
    """The Dask key of ``task``'s file: one per file and options, so a file submitted twice
    (two clients, a resubmission) is one task, computed once."""
    from dask.base import tokenize

    return f"mesh-normal-{tokenize(task.url, task.path, task.size, repr(options))}"


def run_dask(
    tasks: Sequence[FileTask], options: BatchOptions, client_or_address: object
) -> Iterator[dict[str, Any]]:
    """The rows of ``tasks`` as their files finish on a Dask cluster.

    ``client_or_address`` is a ``distributed.Client`` (left open) or a scheduler's address such
    as ``"tcp://10.0.0.5:8786"`` (a client made and closed here). Closing the iterator early
    (Ctrl-C) cancels the files not yet finished.

    Raises
    ------
    ValueError
        When distributed is not installed, or an input or the output is in ``memory://``.
    """
    try:
        distributed: Any = importlib.import_module("distributed")  # untyped: Any
    except ImportError:
        raise ValueError(dask_missing()) from None
    local = [
        url for url in (options.out, *(task.url for task in tasks)) if url.startswith(LOCAL_ONLY)
    ]
    if local:
        raise ValueError(
            f"{local[0]} is in this process's memory (memory://), where no Dask worker can "
            "read or write it; use a folder or storage every worker sees."
        )
    if isinstance(client_or_address, str):
        with distributed.Client(client_or_address) as client:
            yield from _run(distributed, client, tasks, options)
    else:
        yield from _run(distributed, client_or_address, tasks, options)


def _run(
    distributed: Any, client: Any, tasks: Sequence[FileTask], options: BatchOptions
) -> Iterator[dict[str, Any]]:
    budget = _memory_resource(client)
    futures = []
    for task in tasks:
        extra: dict[str, Any] = {}
        if budget is not None:
            extra["resources"] = {MEMORY: min(memory_estimate(task), budget)}
        key = task_key(task, options)
        futures.append(
            client.submit(run_on_worker, task, options, key=key, retries=RETRIES, **extra)
        )
    by_key = {future.key: task for future, task in zip(futures, tasks, strict=True)}
    seen: set[str] = set()
    try:
        for future in distributed.as_completed(futures):
            task = by_key[future.key]
            row = _row(future, task, options)
            future.release()
            if task.path not in seen:
                seen.add(task.path)
                yield row
    finally:
        pending = [future for future in futures if not future.done()]
        if pending:
            client.cancel(pending)


def _row(future: Any, task: FileTask, options: BatchOptions) -> dict[str, Any]:
    """The file's row, or a row saying why the cluster could not give one.

    ``result()``, not the future's status: a finished file whose worker dies before its row is
    fetched is ``lost`` for a moment, and the scheduler computes it again (the future is still
    held), so waiting for it is right.
    """
    kind = "points" if options.points else "mesh"
    try:
        row: dict[str, Any] = future.result()
    except Exception as error:
        if type(error).__name__ == "KilledWorker":
            sentence = "The Dask workers running it died each time (out of memory?)."
            return failed_row(task, "too_large", sentence, kind=kind)
        sentence = f"The Dask task failed ({type(error).__name__}: {error})."
        return failed_row(task, "unreadable", sentence, kind=kind)
    return row


def _memory_resource(client: Any) -> int | None:
    """The largest ``MEMORY`` any worker declares, when every worker declares one (a task
    that asks for a resource runs only where it is declared); else ``None``."""
    workers = client.scheduler_info().get("workers", {}).values()
    declared = [worker.get("resources", {}).get(MEMORY) for worker in workers]
    if not declared or any(value is None for value in declared):
        return None
    return int(max(declared))


_runners = threading.local()


def run_on_worker(task: FileTask, options: BatchOptions) -> dict[str, Any]:
    """The Dask task: ``task``'s row, from this worker thread's own runner (a child process
    reused file after file, with the batch's time and memory limits)."""
    runner = getattr(_runners, "runner", None)
    if runner is None:
        from mesh_normal.datasets.runner import FileRunner

        runner = _runners.runner = FileRunner()
    row: dict[str, Any] = runner.run(task, options)
    return row
