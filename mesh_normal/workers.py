"""Worker processes: a persistent child Python that runs one job at a time, within a time and
a memory limit, which can be asked to stop its job, and is killed and replaced when it does not.

The server's heavy jobs (:mod:`app.web.workers`, an asyncio pool over this) and the local and
Dask batches (:mod:`mesh_normal.datasets.runner`) both run their jobs in a :class:`Worker`.

Why a plain child process (``python -m mesh_normal.workers``), not :mod:`multiprocessing`:

- it works everywhere a job runs, a daemonic process included (a Dask worker), where
  multiprocessing refuses to start children;
- nothing stands between the parent and its workers (a fork server imports for seconds
  before it looks at its parent again, and outlives a parent stopped meanwhile);
- a child watches a pipe whose other end only its parent holds, from its first line on
  (before its imports): when the parent ends, however it ends, the pipe closes and the child
  exits. (``PR_SET_PDEATHSIG`` is tied to the parent's *thread*, and the workers are started
  from threads that may end before their parent.)

A start costs a Python start, the imports and the warm-up (about a second); a replacement
need not wait for one: a pool keeps a warm worker to spare (:mod:`app.web.workers`), so that
the next job takes a ready worker at once while a new spare starts in the background.

Each job has a time limit (``job_seconds``: the child's own timer raises in its Python code,
so the warm worker lives on; a job that does not stop within :data:`GRACE_SECONDS` more, in
a native loop, costs its worker) and each worker a memory cap (``RLIMIT_DATA``: the memory it
writes, not the address space it merely reserves). A job whose client left is asked to stop
(:meth:`Worker.interrupt`, the same exception as its time limit raises).

Jobs travel as pickles of protocol 5: large buffers (``pickle.PickleBuffer``, NumPy arrays)
go out of band, so a 200 MB upload is not copied into a pickle on its way; to a worker, those
of a megabyte or more go in shared memory (:func:`send`).
"""

from __future__ import annotations

import mmap
import os
import pickle
import resource
import signal
import socket
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable, Sequence
from contextlib import suppress
from dataclasses import dataclass, field
from multiprocessing import reduction
from multiprocessing.connection import Connection
from types import FrameType
from typing import Any

#: How a job ended: its value, a refusal (an exception of the worker's ``refusals``), memory
#: exhausted, a crash (the traceback, for the log), its time up, or stopped on request.
OK, REFUSED, NO_MEMORY, CRASHED = "ok", "refused", "memory", "crashed"
TIMED_OUT, CANCELLED = "timed out", "cancelled"

#: Seconds a worker has to answer once its job is to stop (its time is up, or its client left)
#: before it is killed: a job sees the stop only between two steps of its Python code, not
#: inside a kernel or a NumPy call.
GRACE_SECONDS = 2.0

#: What a worker that ran out of memory while it received a job says with NO_MEMORY: it ends,
#: as what is left of the job in the pipe cannot be told from the next one.
LEAVING = "leaving"

#: The signal that asks a worker to stop its job (its time limit is SIGALRM, its own timer).
STOP_SIGNAL = signal.SIGUSR1

#: What a worker that died from these signals most likely met: an allocation its cap refused,
#: in native code that aborts or dereferences the null pointer instead of raising MemoryError.
ALLOCATION_FAILED = frozenset({-signal.SIGSEGV, -signal.SIGABRT, -signal.SIGBUS})

#: Seconds a new worker may take to import and warm up (a second or two; far more only on a
#: machine whose cores are all busy).
START_SECONDS = 120.0


class WorkerDied(Exception):
    """The worker ended before it answered (killed, or aborted: exit code ``exitcode``)."""

    def __init__(self, exitcode: int | None) -> None:
        super().__init__(f"the worker ended with exit code {exitcode}")
        self.exitcode = exitcode


class WorkerNotStarted(RuntimeError):
    """The worker did not get ready: it ended, took longer than START_SECONDS, or its start
    was called off."""


class WorkerOutOfMemory(Exception):
    """The job raised ``MemoryError`` in its worker (the worker itself lives on)."""


class JobTimedOut(Exception):
    """The job ran past its time limit: its worker stopped it, or was killed when it did not."""


class JobCancelled(Exception):
    """The job stopped when asked to (:meth:`Worker.interrupt`); its worker lives on."""


class WorkerCrashed(Exception):
    """The job raised an unexpected exception in its worker; the message is its traceback."""


@dataclass(frozen=True)
class Settings:
    """What a worker is: sent to the child, pickled (functions and classes by name).

    ``imports``: modules the child imports as it starts; ``warm``: what it runs once then
    (every job once, on small files, so that no job pays for first calls). ``memory_limit``:
    its cap in bytes in all, or else ``job_memory`` bytes beyond what the warm worker holds
    (None: no cap). ``job_seconds``: each job's time limit, raised in the job (None: the
    caller's own, see :meth:`Worker.call`). ``expansion_most``: what an upload may expand into
    (:mod:`mesh_normal.files.expansion`). ``niceness``: added to the child's scheduling
    priority. ``threads``: the compiled core's thread count (``MESH_NORMAL_THREADS``).
    ``tune_memory``: blocks of 1 MB or more mapped on their own and freed memory given back
    after each job (:mod:`mesh_normal.allocator`). ``refusals``: exceptions a job raises on
    purpose, raised again as they are in the caller.
    """

    imports: tuple[str, ...] = ()
    warm: Callable[[], object] | None = None
    memory_limit: int | None = None
    job_memory: int | None = None
    job_seconds: float | None = None
    expansion_most: int | None = None
    niceness: int = 0
    threads: int | None = None
    tune_memory: bool = False
    refusals: tuple[type[BaseException], ...] = field(default=())


# --- the parent's side ---------------------------------------------------------------------


class Worker:
    """One child process and the pipes to it; its calls block (an asyncio caller runs them in
    a thread). One job at a time; :meth:`interrupt` and :meth:`kill` may come from any thread.

    The constructor starts the child and returns at once; :meth:`wait_ready` waits for it.
    """

    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        #: The memory a job may take in this worker (bytes; None: no cap), once it is ready.
        self.allowance: int | None = None
        self.leaving = False  # the worker said it ends after this job (LEAVING)
        ours, theirs = socket.socketpair()  # a socket: descriptors pass through it (send)
        watched, self._alive = os.pipe()  # its end closes when this process ends
        env = dict(os.environ)
        if settings.threads is not None:
            env["MESH_NORMAL_THREADS"] = str(settings.threads)
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "mesh_normal.workers", str(theirs.fileno()), str(watched)],
                pass_fds=(theirs.fileno(), watched),
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,  # a batch's stdout is its summary (--json: JSON)
                start_new_session=True,  # Ctrl-C goes to the parent, which stops its workers
            )
        except BaseException:
            ours.close()
            os.close(self._alive)
            raise
        finally:
            theirs.close()
            os.close(watched)
        self.pid = self.process.pid
        self.connection = Connection(ours.detach())
        self._lock = threading.Lock()  # kill() from another thread, while a call waits
        try:
            # This process's import path first (as multiprocessing's spawn does): the jobs'
            # functions travel by name, and are found where this process found them.
            self.connection.send(sys.path)
            self.connection.send(settings)
        except OSError:  # it ended at once; wait_ready says so
            pass

    def wait_ready(
        self, timeout: float = START_SECONDS, called_off: threading.Event | None = None
    ) -> None:
        """Wait for the worker's word that it has warmed up (checking ``called_off`` every
        0.2 s); WorkerNotStarted, the worker killed, if it ends, takes longer than ``timeout``
        or the start is called off."""
        deadline = time.monotonic() + timeout
        try:
            while True:
                if (called_off is not None and called_off.is_set()) or time.monotonic() > deadline:
                    raise WorkerNotStarted("The worker process did not start.")
                if self.connection.poll(min(0.2, max(0.0, deadline - time.monotonic()))):
                    break
            word, self.allowance = self.connection.recv()
            if word != "ready":
                raise WorkerNotStarted("The worker process did not start.")
        except (EOFError, OSError, WorkerNotStarted) as error:
            code = self.kill()
            if isinstance(error, WorkerNotStarted):
                raise
            raise WorkerNotStarted(f"The worker process ended as it started ({code}).") from None

    def call(
        self, function: Callable[..., Any], args: Sequence[Any], seconds: float | None = None
    ) -> Any:
        """``function(*args)`` in the worker: its value, or the exception that says how it
        ended (:func:`ended`). The job may run ``seconds`` (by default the worker's
        ``job_seconds`` and :data:`GRACE_SECONDS` more, its own timer having stopped it by
        then if it could), after which the worker is killed: JobTimedOut."""
        if seconds is None and self.settings.job_seconds is not None:
            seconds = self.settings.job_seconds + GRACE_SECONDS
        try:
            send(self.connection, (function, tuple(args)), SHARED_FROM)
        except OSError:  # it ended while the job was on its way: it may say why
            ending, value = self.last_word()
        else:
            try:
                if not self.connection.poll(seconds):
                    self.kill()
                    raise JobTimedOut()
                ending, value = receive(self.connection)
            except (EOFError, OSError):
                raise WorkerDied(self.kill()) from None
        self.leaving = ending == NO_MEMORY and value == LEAVING
        return ended(ending, value)

    def last_word(self) -> Any:
        """What an ended worker said before it ended (it may say why), else WorkerDied."""
        with suppress(EOFError, OSError):
            if self.connection.poll():
                return receive(self.connection)
        raise WorkerDied(self.kill())

    def alive(self) -> bool:
        return self.process.poll() is None

    def interrupt(self) -> None:
        """Ask the worker to stop its job: :meth:`call` then ends (JobCancelled, or however
        the job ended if it was ending anyway), within ``GRACE_SECONDS`` if the worker is fine.
        A worker without a job ignores it."""
        if self.alive():
            with suppress(ProcessLookupError):
                os.kill(self.pid, STOP_SIGNAL)

    def kill(self) -> int | None:
        """End the worker now (SIGKILL: a job in a native loop does not look at signals);
        its exit code."""
        with self._lock:
            if self.process.poll() is None:
                with suppress(ProcessLookupError):
                    self.process.kill()
            code = self.process.wait()
            if self._alive >= 0:
                os.close(self._alive)
                self._alive = -1
        # The connection is closed with this object: a call in another thread may be reading
        # it (it reads the end of the stream now).
        return code

    def __del__(self) -> None:
        with suppress(Exception):
            self.kill()
            self.connection.close()


def ended(ending: str, value: Any) -> Any:
    """A job's value, or the exception that says how it ended otherwise."""
    if ending == REFUSED:
        raise value
    if ending == NO_MEMORY:
        raise WorkerOutOfMemory()
    if ending == CRASHED:
        raise WorkerCrashed(value)
    if ending == TIMED_OUT:
        raise JobTimedOut()
    if ending == CANCELLED:
        raise JobCancelled()
    return value


def run(
    function: Callable[..., Any],
    args: Sequence[Any],
    refusals: tuple[type[BaseException], ...] = (),
) -> tuple[str, Any]:
    """One job, its ending as ``(OK, value)``, ``(REFUSED, the exception)``,
    ``(NO_MEMORY, None)`` or ``(CRASHED, traceback)``."""
    try:
        return OK, function(*args)
    except refusals as refusal:
        return REFUSED, refusal
    except MemoryError:
        return NO_MEMORY, None
    except Exception:
        return CRASHED, traceback.format_exc()


# --- a job's journey -----------------------------------------------------------------------

#: A job's buffers of this many bytes or more travel to the worker in shared memory (Linux).
SHARED_FROM = 2**20

#: Where a buffer's size is sent, -1: it follows as bytes through the pipe.
_THROUGH_PIPE = -1


def send(connection: Connection, value: Any, shared_from: int | None = None) -> None:
    """Send ``value`` with its large buffers out of band (no copy into the pickle).

    Buffers of ``shared_from`` bytes or more (where the system has ``memfd_create``) are
    written into an anonymous shared-memory file whose descriptor is passed instead of the
    bytes: the receiver maps it read-only (:func:`receive`). For a large upload that takes
    half the time of the pipe (which copies it in pieces of the pipe's buffer, twice, and once
    more into the bytes received). The file is gone once both processes have let go of it, a
    worker that dies included. Descriptors pass over a Unix socket only: through a pipe,
    every buffer goes as bytes.
    """
    buffers: list[pickle.PickleBuffer] = []
    header = pickle.dumps(value, protocol=5, buffer_callback=buffers.append)
    views = [buffer.raw() for buffer in buffers]
    if not hasattr(os, "memfd_create"):
        shared_from = None
    sizes = [
        len(view) if shared_from is not None and len(view) >= shared_from else _THROUGH_PIPE
        for view in views
    ]
    connection.send((header, sizes))
    for view, size in zip(views, sizes, strict=True):
        if size == _THROUGH_PIPE:
            connection.send_bytes(view)
            continue
        descriptor = os.memfd_create("mesh-job", os.MFD_CLOEXEC)
        try:
            written = 0
            while written < size:
                written += os.write(descriptor, view[written:])
            reduction.send_handle(connection, descriptor, 0)
        finally:
            os.close(descriptor)


def receive(connection: Connection) -> Any:
    """What :func:`send` sent: a buffer that came in shared memory is a read-only map of it
    (``mmap``), which the value's own unpickling keeps or copies."""
    return unpickled(*received(connection))


def unpickled(header: bytes, buffers: list[bytes | mmap.mmap]) -> Any:
    return pickle.loads(header, buffers=buffers)


def received(connection: Connection) -> tuple[bytes, list[bytes | mmap.mmap]]:
    """What :func:`send` sent, still pickled: its header and its buffers."""
    header, sizes = connection.recv()
    buffers: list[bytes | mmap.mmap] = []
    for size in sizes:
        if size == _THROUGH_PIPE:
            buffers.append(connection.recv_bytes())
            continue
        descriptor = reduction.recv_handle(connection)
        try:
            buffers.append(mmap.mmap(descriptor, size, access=mmap.ACCESS_READ) if size else b"")
        finally:
            os.close(descriptor)
    return header, buffers


# --- the child's side ----------------------------------------------------------------------


def serve(connection: Connection, settings: Settings) -> None:
    """A worker's life: set its limits, import, warm up, cap its memory, say so, then run one
    job after another until the pipe closes."""
    import mesh_normal.allocator as allocator
    from mesh_normal.files import expansion

    if settings.expansion_most is not None:
        expansion.set_most(settings.expansion_most)
    if settings.niceness:
        os.nice(settings.niceness)
    if settings.tune_memory:
        allocator.map_from(MAPPED_FROM)
        allocator.enable_jobs()  # a job may keep freed memory while it runs (allocator.start_job)
    signal.signal(signal.SIGALRM, _stop_job)
    signal.signal(STOP_SIGNAL, _stop_job)
    _load(settings.imports)
    if settings.warm is not None:
        settings.warm()
    connection.send(("ready", cap_memory(settings.memory_limit, settings.job_memory)))
    while True:
        try:
            job = received(connection)
        except MemoryError:  # beyond the cap already: the rest of the message is unread
            send(connection, (NO_MEMORY, LEAVING))
            return
        # Unpickled in the job: a job too large for the memory cap fails as any other.
        outcome = run_in_worker(run_job, job, settings)
        del job
        try:
            send(connection, outcome)
        except MemoryError:  # pickling the value failed: nothing was sent yet
            send(connection, (NO_MEMORY, None))
        except pickle.PicklingError:
            send(connection, (CRASHED, traceback.format_exc()))
        del outcome
        if settings.tune_memory:
            allocator.end_job(MAPPED_FROM)  # the allocator as it was, and the memory back


#: Blocks of at least this many bytes get their own mapping, returned to the system when freed
#: (with ``tune_memory``): glibc otherwise raises that threshold (up to 32 MB) after large
#: frees, and then keeps what a large upload once took resident for good.
MAPPED_FROM = 2**20


def _load(modules: Sequence[str]) -> None:
    import importlib

    for name in modules:
        importlib.import_module(name)


def written_memory() -> int:
    """The bytes this process has written or may write (its data: heap and private maps, what
    ``RLIMIT_DATA`` counts), or 0 where ``/proc`` does not say."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmData:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def cap_memory(memory_limit: int | None, job_memory: int | None) -> int | None:
    """Cap this process's data at ``memory_limit`` bytes, or at ``job_memory`` beyond what it
    holds now; return what that leaves a job (None: no cap). Beyond it an allocation fails:
    ``MemoryError`` in Python and NumPy, an abort or a crash in some native code."""
    held = written_memory()
    limit = memory_limit if memory_limit is not None else job_memory and held + job_memory
    if not limit:
        return None
    resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))
    return max(limit - held, 0)


class _Stop(BaseException):
    """Raised in a job to stop it: a BaseException, as KeyboardInterrupt is, so that the job's
    own ``except Exception`` does not take it for a failure of its own."""

    def __init__(self, ending: str) -> None:
        super().__init__(ending)
        self.ending = ending


#: Whether a job is running in this worker, to be stopped: a stop signal that comes after it
#: ended (an answer and a stop that crossed), or a second one, is ignored.
_job_running = False


def _stop_job(signum: int, _frame: FrameType | None) -> None:
    global _job_running
    if _job_running:
        _job_running = False  # one stop a job: its cleanup is not interrupted again
        raise _Stop(TIMED_OUT if signum == signal.SIGALRM else CANCELLED)


def run_in_worker(
    function: Callable[..., Any], args: Sequence[Any], settings: Settings
) -> tuple[str, Any]:
    """:func:`run` in a worker, stopped by its timer after ``settings.job_seconds`` or by
    :data:`STOP_SIGNAL`: then ``(TIMED_OUT, None)`` or ``(CANCELLED, None)``."""
    global _job_running
    try:
        _job_running = True
        if settings.job_seconds:
            signal.setitimer(signal.ITIMER_REAL, settings.job_seconds)
        try:
            return run(function, args, settings.refusals)
        finally:
            _job_running = False
            signal.setitimer(signal.ITIMER_REAL, 0)
    except _Stop as stop:
        signal.setitimer(signal.ITIMER_REAL, 0)  # the stop may have come before the finally
        return stop.ending, None


def run_job(header: bytes, buffers: list[bytes | mmap.mmap]) -> Any:
    """The job that :meth:`Worker.call` sent, pickled (:func:`send`): its function's value."""
    function, args = unpickled(header, buffers)
    return function(*args)


def _exit_with_parent(watched: int) -> None:
    """Exit as soon as the parent ends (its end of ``watched`` closes), even mid-job."""

    def watch() -> None:
        with suppress(OSError):
            while os.read(watched, 1):
                pass
        os._exit(1)

    threading.Thread(target=watch, name="parent", daemon=True).start()


def main(argv: Sequence[str]) -> None:
    """``python -m mesh_normal.workers CONNECTION WATCHED`` (descriptors): a worker."""
    descriptor, watched = (int(arg) for arg in argv)
    _exit_with_parent(watched)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops its workers itself
    connection = Connection(descriptor)
    try:
        sys.path[:] = connection.recv()
        serve(connection, connection.recv())
    except (EOFError, OSError):  # the parent closed the pipe: it no longer needs this worker
        return


if __name__ == "__main__":
    main(sys.argv[1:])
