"""The embedded engine: every core of this machine, one persistent worker process each."""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Iterator, Sequence
from typing import Any

from mesh_normal.datasets.runner import FileRunner
from mesh_normal.datasets.tasks import BatchOptions, FileTask


def default_workers() -> int:
    """Every core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


#: fsspec protocols whose files live in one process: a worker process would see none of them.
IN_PROCESS_PROTOCOLS = ("memory://",)


#: Seconds to wait for a worker thread to stop once its child is killed.
JOIN_SECONDS = 5.0
#: How often the waiting main thread wakes up. A Ctrl-C that the system hands to a worker's
#: thread is only a note for the main thread, read when it next runs Python: a wait without
#: a timeout would never read it (seen as a batch that ignored Ctrl-C).
WAKE_SECONDS = 0.25


def in_process(tasks: Sequence[FileTask], options: BatchOptions) -> bool:
    """Whether the batch must run here, in this process: its inputs or outputs are in
    ``memory://`` (then one file at a time, without the time and memory limits)."""
    urls = [options.out, *(task.url for task in tasks)]
    return any(url.startswith(IN_PROCESS_PROTOCOLS) for url in urls)


def run_local(
    tasks: Sequence[FileTask], options: BatchOptions, workers: int | None = None
) -> Iterator[dict[str, Any]]:
    """The rows of ``tasks`` as their files finish, on ``workers`` processes (every core).

    Each worker is a thread here driving its own :class:`~mesh_normal.datasets.runner.FileRunner`
    (a child process, so the files' Python work runs in parallel, each child on one thread);
    closing the iterator early (Ctrl-C, ``break``) stops the children, and the files not
    finished have no row. A batch in ``memory://`` runs in this process instead (see
    :func:`in_process`).
    """
    if in_process(tasks, options):
        from mesh_normal.datasets.job import run_file

        for task in tasks:
            yield run_file(task, options)
        return
    count = min(workers or default_workers(), max(1, len(tasks)))
    todo: queue.SimpleQueue[FileTask | None] = queue.SimpleQueue()
    for task in tasks:
        todo.put(task)
    done: queue.SimpleQueue[dict[str, Any] | BaseException] = queue.SimpleQueue()
    stop = threading.Event()
    runners = [FileRunner() for _ in range(count)]

    def work(runner: FileRunner) -> None:
        try:
            while not stop.is_set():
                try:
                    task = todo.get_nowait()
                except queue.Empty:
                    return
                if task is None:
                    return
                done.put(runner.run(task, options))
        except BaseException as error:
            done.put(error)
        finally:
            runner.close()

    threads = [threading.Thread(target=work, args=(runner,), daemon=True) for runner in runners]
    try:
        for thread in threads:  # inside: a Ctrl-C between two starts stops the first too
            thread.start()
        for _ in range(len(tasks)):
            found = _next(done)
            if isinstance(found, BaseException):
                raise found
            yield found
    finally:
        stop.set()
        for runner in runners:
            runner.kill()
        for thread in threads:  # each reaps its child (a killed one returns at once)
            if thread.is_alive():
                thread.join(JOIN_SECONDS)


def _next(done: queue.SimpleQueue[Any]) -> Any:
    """The next item of ``done``, waking every ``WAKE_SECONDS`` so that a signal is seen."""
    while True:
        try:
            return done.get(timeout=WAKE_SECONDS)
        except queue.Empty:
            continue
