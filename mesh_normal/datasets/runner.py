"""A persistent worker process that runs one file at a time, within a time and memory limit.

:class:`FileRunner` keeps one :class:`mesh_normal.workers.Worker` (a child Python that imports
the library and runs a report once, :func:`warm`), and runs
:func:`~mesh_normal.datasets.job.run_file` in it for each file: no process start per file,
yet a file that hangs or eats the machine's memory costs only the child. A file over
``timeout`` seconds kills the child (a ``timed_out`` row) and the next file gets a new one;
the child's address space is limited to its size after the warm-up plus ``options.memory_mb``
(``RLIMIT_AS``), so a file that needs more fails in it (a ``too_large`` row), and a child that
dies any other way is a ``too_large`` row too.

The worker is a plain child process (not :mod:`multiprocessing`), so a runner also works
inside a daemonic process such as a Dask worker: :func:`shared_runner` is the one of the
process.
"""

from __future__ import annotations

import signal
import threading
import time
from typing import Any

from mesh_normal.datasets.schema import failed_row
from mesh_normal.datasets.tasks import BatchOptions, FileTask
from mesh_normal.workers import (
    JobTimedOut,
    Settings,
    Worker,
    WorkerDied,
    WorkerNotStarted,
    WorkerOutOfMemory,
)


class RunnerError(RuntimeError):
    """The child could not be started (not a file's fault)."""


class FileRunner:
    """One child process, reused file after file; ``run`` is thread-safe (one file at a time).

    ``threads`` is the child's compiled core's thread count (``MESH_NORMAL_THREADS``): 1 by
    default, since a batch runs a child for every core.
    """

    def __init__(self, threads: int = 1) -> None:
        self.settings = Settings(warm=warm, threads=threads)
        self._lock = threading.Lock()
        self._child: Worker | None = None
        self._killed = threading.Event()  # kill() was called: start no child from now on
        self.started = 0  # how many children it has started, for the tests

    def run(self, task: FileTask, options: BatchOptions) -> dict[str, Any]:
        """The row of ``task``, never an exception for the file's fault."""
        kind = "points" if options.points else "mesh"
        limit = options.max_file_mb
        if limit is not None and task.size > limit * 1e6:
            from mesh_normal.datasets.job import too_large_sentence

            return failed_row(task, "too_large", too_large_sentence(task.size, limit), kind=kind)
        with self._lock:
            if self._killed.is_set():
                raise RunnerError("The batch was stopped.")
            child = self._ensure()
            start = time.perf_counter()
            try:
                row: dict[str, Any] = child.call(run_limited, (task, options), options.timeout)
                return row
            except JobTimedOut:
                self._child = None  # killed by the call
                seconds = time.perf_counter() - start
                sentence = f"It took longer than the limit of {options.timeout:g} s (--timeout)."
                return failed_row(task, "timed_out", sentence, kind=kind, seconds=seconds)
            except WorkerOutOfMemory:  # beyond the cap outside the file's own work
                seconds = time.perf_counter() - start
                sentence = "It needs more memory than the limit allows."
                return failed_row(task, "too_large", sentence, kind=kind, seconds=seconds)
            except WorkerDied as died:  # out of memory, or killed
                self._child = None
                seconds = time.perf_counter() - start
                sentence = f"Its worker process died ({_exit_words(died.exitcode)}): out of memory?"
                return failed_row(task, "too_large", sentence, kind=kind, seconds=seconds)

    def close(self) -> None:
        """Stop the child (a new one starts on the next ``run``)."""
        with self._lock:
            self._stop()

    def kill(self) -> None:
        """Kill the child now, from any thread, even while it runs a file (which then has
        no row worth keeping): how an interrupted batch stops at once."""
        self._killed.set()  # a child starting now stops itself (Worker.wait_ready)
        child = self._child
        if child is not None:
            child.kill()

    def _ensure(self) -> Worker:
        if self._child is None or not self._child.alive():
            self._stop()
            child = Worker(self.settings)
            self.started += 1
            try:
                child.wait_ready(called_off=self._killed)
            except WorkerNotStarted:
                raise RunnerError("The worker process did not start.") from None
            self._child = child
        return self._child

    def _stop(self) -> None:
        child, self._child = self._child, None
        if child is not None:
            child.kill()


def _exit_words(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return f"signal {signal.Signals(-code).name}"
        except ValueError:
            return f"signal {-code}"
    return f"exit code {code}"


_shared: FileRunner | None = None
_shared_lock = threading.Lock()


def shared_runner() -> FileRunner:
    """The process's one runner, made on first use (a Dask task calls
    ``shared_runner().run(task, options)``)."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = FileRunner()
        return _shared


# --- in the child ---------------------------------------------------------------------------


def warm() -> None:
    """Run the mesh report once on a tetrahedron, so that no file pays for the first call's
    imports (the readers, the report's modules)."""
    import numpy as np

    from mesh_normal.files import read_mesh, write_mesh
    from mesh_normal.mesh.report.analysis import analyse_mesh, build_report

    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    data = write_mesh(vertices, faces, "stl")
    build_report(analyse_mesh(read_mesh(data, "warm.stl"), "warm.stl", len(data)))
    import mesh_normal.datasets.job  # noqa: F401  (what each file runs)

    global _baseline
    _baseline = _address_space()


def _address_space() -> int:
    """The process's virtual memory size in bytes (``VmSize``), or 0 when unknown."""
    try:
        with open("/proc/self/status", "rb") as status:
            for line in status:
                if line.startswith(b"VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _limit_memory(baseline: int, memory_mb: float | None) -> None:
    import resource

    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    soft = hard if memory_mb is None or not baseline else baseline + int(memory_mb * 1e6)
    if hard != resource.RLIM_INFINITY:
        soft = min(soft, hard)
    resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


#: The child's address space once warm (bytes; 0: unknown), which ``memory_mb`` is beyond.
_baseline = 0


def run_limited(task: FileTask, options: BatchOptions) -> dict[str, Any]:
    """In the child: ``task``'s row, its address space limited to ``options.memory_mb`` beyond
    the warm child's."""
    from mesh_normal.datasets.job import run_file

    _limit_memory(_baseline, options.memory_mb)
    try:
        return run_file(task, options)
    finally:
        _limit_memory(_baseline, None)
