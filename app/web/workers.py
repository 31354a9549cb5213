"""A small pool of worker processes for the heavy work, one job at a time in each.

Why processes, not threads: the heavy work holds the GIL for seconds (regular expressions over
an ASCII file, ``tolist``), which would stall every page; an allocation that fails inside a
native library aborts the whole process (pydantic-core: "memory allocation of N bytes
failed", exit 134); and a thread cannot be stopped when its client hangs up. A worker that
dies, or that is killed because its client left, is replaced; the server process lives on.

The workers come from the ``forkserver`` context (a clean process, never a fork of the
server's threads) with ``preload`` imported once in the fork server, and each runs ``warm``
once as it starts (the numba kernels, loaded from their cache). The first worker warms alone,
before the others start, so that a cold cache is compiled once, not by every worker at once.
Starting a process blocks (the first start waits for the fork server to import ``preload``,
seconds), so it happens in a thread: the event loop serves pages meanwhile, at start-up and
while a worker is replaced.

Until the first worker is ready (seconds after the server's first page: the fork server imports
``preload``, the worker warms), a job that its module has marked as safe to run in the server
(:func:`run_in_server_while_starting`: the real mesh jobs, on a file of a few kilobytes, which
end in milliseconds in the kernels' Python path, with nothing to cancel and no memory to run
out of) runs in a thread of the server instead of waiting; any other job waits for a worker.

Jobs travel as pickles of protocol 5: large buffers (``pickle.PickleBuffer``, NumPy arrays)
go out of band, so a 200 MB upload is not copied into a pickle on its way; to a worker, those of
a megabyte or more go in shared memory (:func:`send`), and answers come back as raw bytes.
"""

from __future__ import annotations

import asyncio
import logging
import mmap
import multiprocessing
import os
import pickle
import resource
import threading
import traceback
from collections import deque
from collections.abc import Callable, Sequence
from multiprocessing import reduction
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from typing import Any

from app.web.errors import ApiError
from mesh_normal import allocator

#: How a worker's job ended: its value, a refusal (an ApiError's status, sentence and field),
#: memory exhausted, or a crash (the traceback, for the log).
OK, REFUSED, NO_MEMORY, CRASHED = "ok", "refused", "memory", "crashed"


logger = logging.getLogger(__name__)

#: How long the first jobs wait for the first worker to be ready: compiling the kernels into
#: an empty cache (every kernel for read-only and writable arrays, mesh_normal.precompile) took
#: 114 s on two cores shared with other work, 2.5 times the 46 s of the writable ones alone.
STARTUP_SECONDS = 120


#: Jobs that may run in the server while no worker is ready yet: each function, with its test
#: of the job's arguments (see :func:`run_in_server_while_starting`).
_STARTUP_JOBS: dict[Callable[..., Any], Callable[..., bool]] = {}


def run_in_server_while_starting(function: Callable[..., Any], small: Callable[..., bool]) -> None:
    """Let ``function`` run in a thread of the server, until the first worker is ready, when
    ``small(*args)`` says its arguments are small: for jobs that end in milliseconds there and
    can neither crash the process nor exhaust its memory (a worker is what stops a job whose
    client left, and what survives an abort)."""
    _STARTUP_JOBS[function] = small


def _starting_job(job: tuple[Callable[..., Any], Sequence[Any]] | None) -> bool:
    if job is None:
        return False
    small = _STARTUP_JOBS.get(job[0])
    return small is not None and small(*job[1])


class WorkerDied(Exception):
    """The worker ended before it answered (killed, or aborted: exit code ``exitcode``)."""

    def __init__(self, exitcode: int | None) -> None:
        super().__init__(f"the worker ended with exit code {exitcode}")
        self.exitcode = exitcode


class WorkerOutOfMemory(Exception):
    """The job raised ``MemoryError`` in its worker (the worker itself lives on)."""


class WorkerCrashed(Exception):
    """The job raised an unexpected exception in its worker; the message is its traceback."""


#: A job's buffers of this many bytes or more travel to the worker in shared memory (Linux).
SHARED_FROM = 2**20

#: Where a buffer's size is sent, -1: it follows as bytes through the pipe.
_THROUGH_PIPE = -1


def send(connection: Connection, value: Any, shared_from: int | None = None) -> None:
    """Send ``value`` with its large buffers out of band (no copy into the pickle).

    Buffers of ``shared_from`` bytes or more (where the system has ``memfd_create``) are
    written into an anonymous shared-memory file whose descriptor is passed instead of the
    bytes: the receiver maps it read-only (:func:`receive`). For a 42 MB upload that took
    29-31 ms against 59-72 ms through the pipe (which copies it in pieces of the socket's
    buffer, twice, and once more into the bytes received). The file is gone once both
    processes have let go of it, a worker that dies included.
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
    return pickle.loads(header, buffers=buffers)


def serve(
    connection: Connection, warm: Callable[[], object] | None, memory_limit: int | None
) -> None:
    """A worker's life: warm up, say so, then run one job after another until the pipe closes."""
    if memory_limit is not None:
        resource.setrlimit(resource.RLIMIT_AS, (memory_limit, memory_limit))
    tune_allocator()
    allocator.enable_jobs()  # a job may keep freed memory while it runs (allocator.start_job)
    try:
        if warm is not None:
            warm()
        connection.send("ready")
        while True:
            function, args = receive(connection)
            outcome = run(function, args)
            send(connection, outcome)
            del function, args, outcome
            allocator.end_job(_MAPPED_FROM)  # the allocator as it was, and the memory back
    except (EOFError, OSError):  # the server closed the pipe: it no longer needs this worker
        return


#: Blocks of at least this many bytes get their own mapping, returned to the system when freed.
_MAPPED_FROM = 2**20


def tune_allocator() -> None:
    """Give every block of 1 MB or more its own mapping (glibc's ``mallopt``), returned to the
    system when freed. glibc otherwise raises that threshold (up to 32 MB) after large frees,
    and then keeps what a large upload once took resident for good. Nothing elsewhere."""
    allocator.map_from(_MAPPED_FROM)


def run(function: Callable[..., Any], args: Sequence[Any]) -> tuple[str, Any]:
    """One job, its ending as ``(OK, value)``, ``(REFUSED, ...)``, ``(NO_MEMORY, None)`` or
    ``(CRASHED, traceback)``."""
    try:
        return OK, function(*args)
    except ApiError as error:
        return REFUSED, (error.status_code, error.error, error.field)
    except MemoryError:
        return NO_MEMORY, None
    except Exception:
        return CRASHED, traceback.format_exc()


class Worker:
    """One worker process and the pipe to it."""

    def __init__(
        self,
        context: multiprocessing.context.BaseContext,
        warm: Callable[[], object] | None,
        memory_limit: int | None,
    ) -> None:
        self.connection, child = context.Pipe()
        self.process: BaseProcess = context.Process(  # type: ignore[attr-defined]
            target=serve, args=(child, warm, memory_limit), daemon=True, name="mesh-worker"
        )
        self.process.start()
        child.close()

    async def readable(self) -> None:
        """Wait until the worker has said something or has ended. The wait is a thread's
        (``connection.wait``; uvloop's ``add_reader`` on these descriptors did not wake
        reliably); cancelling it leaves that thread until the worker is stopped."""
        waited: list[Connection | int] = [self.connection, self.process.sentinel]
        await asyncio.get_running_loop().run_in_executor(None, wait, waited)

    async def answer(self) -> Any:
        """The worker's next message; WorkerDied if it ended instead."""
        await self.waited()
        try:
            # The message may be large: read it in a thread, not in the event loop.
            return await asyncio.get_running_loop().run_in_executor(None, receive, self.connection)
        except (EOFError, OSError):
            self.process.join()
            raise WorkerDied(self.process.exitcode) from None

    async def waited(self) -> None:
        """Wait until the worker's message can be read; WorkerDied if it ended instead. A wake
        without either (the loop may wake a reader early) waits again."""
        while True:
            await self.readable()
            if self.connection.poll():
                return
            if not self.process.is_alive():
                raise WorkerDied(self.process.exitcode)

    async def ready(self) -> None:
        """Wait for the worker's word that it has warmed up; WorkerDied if it ended instead."""
        await self.waited()
        try:
            self.connection.recv()
        except (EOFError, OSError):
            self.process.join()
            raise WorkerDied(self.process.exitcode) from None

    async def call(self, function: Callable[..., Any], args: Sequence[Any]) -> Any:
        """Run one job in this worker; cancelling the call is the caller's to follow with
        :meth:`stop`."""
        loop = asyncio.get_running_loop()
        try:
            await loop.run_in_executor(
                None, send, self.connection, (function, tuple(args)), SHARED_FROM
            )
        except (BrokenPipeError, OSError):
            self.process.join()
            raise WorkerDied(self.process.exitcode) from None
        ending, value = await self.answer()
        if ending == REFUSED:
            raise ApiError(*value)
        if ending == NO_MEMORY:
            raise WorkerOutOfMemory()
        if ending == CRASHED:
            raise WorkerCrashed(value)
        return value

    def stop(self) -> None:
        """End the worker now (SIGKILL: a job in a native loop does not look at signals)."""
        self.process.kill()
        self.process.join()
        self.connection.close()


class ServerThread:
    """Stands in for a worker while none is ready: the job runs in a thread of the server (see
    :func:`run_in_server_while_starting`); its endings come back as a worker's do."""

    async def call(self, function: Callable[..., Any], args: Sequence[Any]) -> Any:
        ending, value = await asyncio.to_thread(run, function, args)
        if ending == REFUSED:
            raise ApiError(*value)
        if ending == NO_MEMORY:
            raise WorkerOutOfMemory()
        if ending == CRASHED:
            raise WorkerCrashed(value)
        return value


class WorkerPool:
    """``count`` workers; :meth:`acquire` lends an idle one, :meth:`release` takes it back
    (replacing it when its job did not end cleanly)."""

    def __init__(
        self,
        count: int,
        *,
        warm: Callable[[], object] | None = None,
        preload: Sequence[str] = (),
        memory_limit: int | None = None,
    ) -> None:
        self.count = count
        self.warm = warm
        self.memory_limit = memory_limit
        self.context = multiprocessing.get_context("forkserver")
        self.context.set_forkserver_preload(list(preload))
        self.idle: deque[Worker] = deque()
        self.busy: set[Worker] = set()
        self.replaced = 0  # workers replaced after a crash or a cancelled job
        self._changed: asyncio.Event | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._started = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._warmed: asyncio.Event | None = None
        # Workers started but not yet ready, and the pool's generation (one more at each
        # close): a worker whose start finishes in its thread after a close is stopped there.
        self._lock = threading.Lock()
        self._starting: set[Worker] = set()
        self._generation = 0

    def start(self) -> None:
        """Start the workers in the background (from the event loop, which this does not
        block: each process starts in a thread); the first warms alone."""
        loop = asyncio.get_running_loop()
        if self._started and self._loop is loop:
            return
        if self._started:  # a new event loop (a test client's): its workers start afresh
            self.close()
        self._started = True
        self._loop = loop
        self._changed = asyncio.Event()
        self._warmed = asyncio.Event()
        for place in range(self.count):
            self._spawn(first=place == 0)

    def _spawn(self, first: bool = False) -> None:
        task = asyncio.get_running_loop().create_task(self._bring_up(first))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _bring_up(self, first: bool) -> None:
        assert self._warmed is not None
        generation = self._generation
        if not first:
            await self._warmed.wait()
        while True:
            try:
                worker = await asyncio.to_thread(self._launch, generation)
                if worker is None:  # the pool was closed meanwhile
                    return
                try:
                    await worker.ready()
                except WorkerDied:
                    self._drop(worker)
                    raise
                break
            except (WorkerDied, OSError, RuntimeError) as error:  # e.g. a memory limit too low
                logger.error("a worker process could not start (%s); trying again", error)
                await asyncio.sleep(1)
        with self._lock:
            self._starting.discard(worker)
        self._warmed.set()
        self.idle.append(worker)
        self._notify()

    def _launch(self, generation: int) -> Worker | None:
        """A new worker process (in a thread: starting one blocks), or None, that process
        stopped again, if the pool was closed (a new generation) while it started."""
        worker = Worker(self.context, self.warm, self.memory_limit)
        with self._lock:
            if generation == self._generation:
                self._starting.add(worker)
                return worker
        worker.stop()
        return None

    def _drop(self, worker: Worker) -> None:
        with self._lock:
            self._starting.discard(worker)
        worker.stop()

    def _notify(self) -> None:
        assert self._changed is not None
        self._changed.set()
        self._changed = asyncio.Event()

    async def acquire(
        self, timeout: float, job: tuple[Callable[..., Any], Sequence[Any]] | None = None
    ) -> Worker | ServerThread | None:
        """An idle worker within ``timeout`` seconds, or ``None``. Before the first worker is
        ready (the kernels load, or compile into an empty cache), up to STARTUP_SECONDS; or,
        for a small ``job`` marked so (:func:`run_in_server_while_starting`), a thread of the
        server at once."""
        self.start()
        assert self._warmed is not None
        loop = asyncio.get_running_loop()
        started = self._warmed.is_set()
        if not started and not self.idle and _starting_job(job):
            return ServerThread()
        deadline = loop.time() + (timeout if started else max(timeout, STARTUP_SECONDS))
        while not self.idle:
            assert self._changed is not None
            left = deadline - loop.time()
            if left <= 0:
                return None
            try:
                await asyncio.wait_for(self._changed.wait(), left)
            except TimeoutError:
                return None
        worker = self.idle.popleft()
        self.busy.add(worker)
        return worker

    def release(self, worker: Worker | ServerThread, clean: bool) -> None:
        """Take a worker back: idle again after a clean job, else stopped and replaced."""
        if isinstance(worker, ServerThread):
            return  # its thread ends with its small job
        self.busy.discard(worker)
        if clean and worker.process.is_alive():
            self.idle.append(worker)
            self._notify()
            return
        worker.stop()
        self.replaced += 1
        self._spawn()

    def close(self) -> None:
        """Stop every worker, the ones still starting too."""
        for task in self._tasks:
            task.cancel()
        with self._lock:
            self._generation += 1
            starting, self._starting = self._starting, set()
        for worker in [*self.idle, *self.busy, *starting]:
            worker.stop()
        self.idle.clear()
        self.busy.clear()
        self._started = False
