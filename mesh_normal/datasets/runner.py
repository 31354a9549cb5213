"""A persistent worker process that runs one file at a time, within a time and memory limit.

:class:`FileRunner` starts a child Python once (``python -m mesh_normal.datasets.runner``), which
imports the library and runs a report once (:func:`warm`), then runs
:func:`~mesh_normal.datasets.job.run_file` for each file sent to it over a pipe: no process
start per file, yet a file that hangs or eats the machine's memory costs only the child. A file
over ``timeout`` seconds kills the child (a ``timed_out`` row) and the next file gets a new
one; the child's address space is limited to its size after the warm-up plus
``options.memory_mb`` (``RLIMIT_AS``), so a file that needs more fails in it (a ``too_large``
row), and a child that dies any other way is a ``too_large`` row too.

The child is a plain subprocess (not :mod:`multiprocessing`), so a runner also works inside a
daemonic process such as a Dask worker: :func:`shared_runner` is the one of the process.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
import time
from multiprocessing.connection import Connection
from typing import Any

from mesh_normal.datasets.schema import failed_row
from mesh_normal.datasets.tasks import BatchOptions, FileTask

#: Seconds a new child may take to import the library and warm up (a second or two; far more
#: only on a machine whose cores are all busy).
START_SECONDS = 120.0


class RunnerError(RuntimeError):
    """The child could not be started (not a file's fault)."""


class FileRunner:
    """One child process, reused file after file; ``run`` is thread-safe (one file at a time).

    ``threads`` is the child's compiled core's thread count (``MESH_NORMAL_THREADS``): 1 by
    default, since a batch runs a child for every core.
    """

    def __init__(self, threads: int = 1) -> None:
        self.threads = threads
        self._lock = threading.Lock()
        self._child: _Child | None = None
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
                child.send((task, options))
                if child.wait(options.timeout):
                    row: dict[str, Any] = child.receive()
                    return row
            except (EOFError, OSError):  # the child died: out of memory, or killed
                code = self._stop()
                seconds = time.perf_counter() - start
                sentence = f"Its worker process died ({_exit_words(code)}): out of memory?"
                return failed_row(task, "too_large", sentence, kind=kind, seconds=seconds)
            self._stop()
            seconds = time.perf_counter() - start
            sentence = f"It took longer than the limit of {options.timeout:g} s (--timeout)."
            return failed_row(task, "timed_out", sentence, kind=kind, seconds=seconds)

    def close(self) -> None:
        """Stop the child (a new one starts on the next ``run``)."""
        with self._lock:
            self._stop()

    def kill(self) -> None:
        """Kill the child now, from any thread, even while it runs a file (which then has
        no row worth keeping): how an interrupted batch stops at once."""
        self._killed.set()  # a child starting now stops itself (see _Child.__init__)
        child = self._child
        if child is not None and child.process.poll() is None:
            child.process.kill()

    def _ensure(self) -> _Child:
        if self._child is None or self._child.process.poll() is not None:
            self._stop()
            self._child = _Child(self.threads, self._killed)
            self.started += 1
        return self._child

    def _stop(self) -> int | None:
        child, self._child = self._child, None
        return None if child is None else child.kill()

    def __del__(self) -> None:
        child = getattr(self, "_child", None)
        if child is not None:
            child.kill()


def _exit_words(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return f"signal {signal.Signals(-code).name}"
        except ValueError:
            return f"signal {-code}"
    return f"exit code {code}"


class _Child:
    """The child process and the two pipes to it."""

    def __init__(self, threads: int, killed: threading.Event | None = None) -> None:
        to_child_read, to_child_write = os.pipe()
        from_child_read, from_child_write = os.pipe()
        env = {**os.environ, "MESH_NORMAL_THREADS": str(threads)}
        command = [sys.executable, "-m", "mesh_normal.datasets.runner"]
        command += [str(to_child_read), str(from_child_write)]
        self.process = subprocess.Popen(
            command,
            pass_fds=(to_child_read, from_child_write),
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,  # the driver's stdout is the summary (--json: JSON)
            start_new_session=True,  # Ctrl-C goes to the driver, which stops the children
        )
        os.close(to_child_read)
        os.close(from_child_write)
        self.to_child = Connection(to_child_write, readable=False)
        self.from_child = Connection(from_child_read, writable=False)
        # Waited for in steps, so that a runner killed meanwhile (Ctrl-C while the child
        # starts) does not leave this child running on.
        deadline = time.monotonic() + START_SECONDS
        while not self.from_child.poll(min(0.2, max(0.0, deadline - time.monotonic()))):
            if (killed is not None and killed.is_set()) or time.monotonic() >= deadline:
                self.kill()
                raise RunnerError("The worker process did not start.")
        if self.from_child.recv() != "ready":
            self.kill()
            raise RunnerError("The worker process did not start.")

    def send(self, message: object) -> None:
        self.to_child.send(message)

    def wait(self, timeout: float | None) -> bool:
        return self.from_child.poll(timeout)

    def receive(self) -> Any:
        return self.from_child.recv()

    def kill(self) -> int | None:
        if self.process.poll() is None:
            self.process.kill()
        code = self.process.wait()
        for connection in (self.to_child, self.from_child):
            connection.close()
        return code


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


# --- the child ----------------------------------------------------------------------------


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


def serve(receive: Connection, send: Connection) -> None:
    """The child's loop: a (task, options) in, its row out, until the pipe closes."""
    from mesh_normal.datasets.job import run_file

    warm()
    baseline = _address_space()
    send.send("ready")
    while True:
        try:
            task, options = receive.recv()
        except EOFError:
            return
        _limit_memory(baseline, options.memory_mb)
        row = run_file(task, options)
        _limit_memory(baseline, None)
        send.send(row)


def _watch_parent(parent: int) -> None:
    """Exit when the driver is gone (killed: no one reads the rows), even while the main
    thread is blocked in a file that hangs."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os._exit(1)


def main(argv: list[str]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    watcher = threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True)
    watcher.start()
    receive = Connection(int(argv[0]), writable=False)
    send = Connection(int(argv[1]), readable=False)
    with contextlib.suppress(BrokenPipeError, EOFError):
        serve(receive, send)


if __name__ == "__main__":
    main(sys.argv[1:])
