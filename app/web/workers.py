"""The server's pool of worker processes (:mod:`mesh_normal.workers`) for the heavy work, one
job at a time in each, driven from the event loop.

Why processes, not threads: the heavy work holds the GIL for seconds (regular expressions over
an ASCII file, ``tolist``), which would stall every page; an allocation that fails inside a
native library aborts the whole process (pydantic-core: "memory allocation of N bytes
failed", exit 134); and a thread cannot be stopped when its client hangs up. A worker that
dies, or that is killed because its job did not stop, is replaced; the server process lives on.

The pool keeps :data:`SPARE` warm worker more than it has slots for jobs (the admission in
:mod:`app.web.jobs` runs at most ``count`` jobs at once), and hands out the worker that
finished last first: a worker killed with its job (a client that left while a native loop ran,
a crash) is replaced at once by the one to spare, so that the next job neither waits for a
worker's start (a Python start, the imports and the warm-up: about a second) nor gets a 503,
while a new spare starts in the background. Each worker imports ``preload`` (the jobs'
modules) and runs ``warm`` once as it starts (every job once, on small files). The first
worker warms alone, before the others start, so that it has the cores to itself and the first
jobs wait less. Starting a process and waiting for it block, so they happen in threads: the
event loop serves pages meanwhile, at start-up and while a worker is replaced.

Until the first worker is ready (a second or two after the server's first page), a job that
its module has marked as safe to run in the server (:func:`run_in_server_while_starting`: the
calculator's batch of a small body, which ends in milliseconds, with nothing to cancel and no
memory to run out of) runs in a thread of the server instead of waiting; any other job waits
for a worker.

A worker ends with the server however the server ends (:mod:`mesh_normal.workers`: each
watches a pipe only the server holds); :meth:`WorkerPool.close` kills them at once.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import suppress
from typing import Any

from app.web.errors import ApiError
from mesh_normal import allocator, workers
from mesh_normal.workers import (
    ALLOCATION_FAILED,
    GRACE_SECONDS,
    JobCancelled,
    JobTimedOut,
    WorkerCrashed,
    WorkerDied,
    WorkerNotStarted,
    WorkerOutOfMemory,
    ended,
    run,
)

__all__ = [
    "ALLOCATION_FAILED",
    "GRACE_SECONDS",
    "JobCancelled",
    "JobTimedOut",
    "ServerThread",
    "Worker",
    "WorkerCrashed",
    "WorkerDied",
    "WorkerOutOfMemory",
    "WorkerPool",
    "run_in_server_while_starting",
]

logger = logging.getLogger(__name__)

#: Warm workers beyond the job slots, to take a killed worker's place at once.
SPARE = 1

#: How much lower than the server's a worker's scheduling priority is: a job of seconds may
#: wait a moment for a core; a page waiting behind it is what a user sees.
WORKER_NICENESS = 5

#: What a refusal is in a job: an ApiError raised there is raised again in the server.
REFUSALS = (ApiError,)

#: How long the first jobs wait for the first worker to be ready: it takes a second or two
#: (its imports, then the warm-up), far longer only on a machine whose cores are busy with
#: other work.
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


def tune_allocator() -> None:
    """Give every block of 1 MB or more its own mapping (glibc's ``mallopt``), returned to the
    system when freed, in the server as in its workers (:data:`mesh_normal.workers.MAPPED_FROM`)."""
    allocator.map_from(workers.MAPPED_FROM)


class Worker(workers.Worker):
    """A worker process (:class:`mesh_normal.workers.Worker`) whose waits run in threads of
    ``executor``, so that the event loop goes on meanwhile."""

    def __init__(self, settings: workers.Settings, executor: ThreadPoolExecutor) -> None:
        super().__init__(settings)
        self.executor = executor

    async def started(self, called_off: threading.Event) -> None:
        """Wait until it is ready (WorkerNotStarted if it ends, or ``called_off`` is set)."""
        wait = functools.partial(self.wait_ready, workers.START_SECONDS, called_off)
        await asyncio.get_running_loop().run_in_executor(self.executor, wait)

    async def run(self, function: Callable[..., Any], args: Sequence[Any]) -> Any:
        """Run one job in this worker (:meth:`call`); cancelling the wait leaves the job
        running, for the caller to :meth:`interrupt` or :meth:`kill`."""
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self.executor, self.call, function, tuple(args))


class ServerThread:
    """Stands in for a worker while none is ready: the job runs in a thread of the server (see
    :func:`run_in_server_while_starting`); its endings come back as a worker's do. Its jobs
    are small: no time limit, no cap, and nothing to stop."""

    allowance: int | None = None

    async def run(self, function: Callable[..., Any], args: Sequence[Any]) -> Any:
        return ended(*await asyncio.to_thread(run, function, args, REFUSALS))

    def interrupt(self) -> None:
        """Its small job ends on its own, in milliseconds."""


class WorkerPool:
    """``count`` workers and :data:`SPARE` more (``spare``); :meth:`acquire` lends an idle one,
    :meth:`release` takes it back (replacing it when its job did not end cleanly)."""

    def __init__(
        self,
        count: int,
        *,
        spare: int = 0,
        warm: Callable[[], object] | None = None,
        preload: Sequence[str] = (),
        memory_limit: int | None = None,
        job_memory: int | None = None,
        job_seconds: float | None = None,
        expansion_most: int | None = None,
    ) -> None:
        """``memory_limit``, ``job_memory``, ``job_seconds`` and ``expansion_most``: each
        worker's limits (:class:`mesh_normal.workers.Settings`)."""
        self.count = count + spare
        self.settings = workers.Settings(
            imports=tuple(preload),
            warm=warm,
            memory_limit=memory_limit,
            job_memory=job_memory,
            job_seconds=job_seconds,
            expansion_most=expansion_most,
            niceness=WORKER_NICENESS,
            tune_memory=True,
            refusals=REFUSALS,
        )
        # Its own threads: a job's wait, or a start's, never waits for one of the loop's.
        self.executor = ThreadPoolExecutor(2 * self.count + 2, thread_name_prefix="worker")
        self.idle: list[Worker] = []  # the last one released is the first one lent
        self.busy: set[Worker] = set()
        self.replaced = 0  # workers replaced after a crash or a job that did not stop
        self.started = 0  # worker processes started
        self._changed: asyncio.Event | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._started = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._warmed: asyncio.Event | None = None
        # Workers started but not yet ready, and what calls their start off when the pool
        # closes (a worker whose start finishes in its thread after a close is killed there).
        self._lock = threading.Lock()
        self._starting: set[Worker] = set()
        self._closed = threading.Event()

    def start(self) -> None:
        """Start the workers in the background (from the event loop, which this does not
        block: each process starts in a thread); the first warms alone."""
        loop = asyncio.get_running_loop()
        if self._started and self._loop is loop:
            return
        if self._started:  # a new event loop (a test client's): its workers start afresh
            self.close()
        self._started = True
        self._closed = threading.Event()
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
        closed = self._closed
        if not first:
            await self._warmed.wait()
        loop = asyncio.get_running_loop()
        while True:
            try:
                worker = await loop.run_in_executor(self.executor, self._launch, closed)
                if worker is None:  # the pool was closed meanwhile
                    return
                try:
                    await worker.started(closed)
                finally:
                    with self._lock:
                        self._starting.discard(worker)
                break
            except (WorkerNotStarted, OSError) as error:  # e.g. a memory limit too low
                if closed.is_set():
                    return
                logger.error("a worker process could not start (%s); trying again", error)
                await asyncio.sleep(1)
        if closed.is_set():  # closed as it became ready
            worker.kill()
            return
        self._warmed.set()
        self.idle.append(worker)
        self._notify()

    def _launch(self, closed: threading.Event) -> Worker | None:
        """A new worker process (in a thread: starting one blocks), or None, that process
        killed again, if the pool was closed while it started."""
        worker = Worker(self.settings, self.executor)
        with self._lock:
            if not closed.is_set():
                self._starting.add(worker)
                self.started += 1
                return worker
        worker.kill()
        return None

    def _notify(self) -> None:
        assert self._changed is not None
        self._changed.set()
        self._changed = asyncio.Event()

    async def acquire(
        self, timeout: float, job: tuple[Callable[..., Any], Sequence[Any]] | None = None
    ) -> Worker | ServerThread | None:
        """An idle worker within ``timeout`` seconds, or ``None``. Before the first worker is
        ready (its imports, then the warm-up), up to STARTUP_SECONDS; or, for a small ``job``
        marked so (:func:`run_in_server_while_starting`), a thread of the server at once."""
        self.start()
        assert self._warmed is not None
        loop = asyncio.get_running_loop()
        started = self._warmed.is_set()
        if not started and not self.idle and _starting_job(job):
            return ServerThread()
        deadline = loop.time() + (timeout if started else max(timeout, STARTUP_SECONDS))
        while True:
            while not self.idle:
                assert self._changed is not None
                left = deadline - loop.time()
                if left <= 0 or not self._started:  # waited long enough, or closed
                    return None
                try:
                    await asyncio.wait_for(self._changed.wait(), left)
                except TimeoutError:
                    return None
            worker = self.idle.pop()
            if worker.alive():
                self.busy.add(worker)
                return worker
            self._replace(worker)  # it died idle (e.g. killed from outside)

    def release(self, worker: Worker | ServerThread, clean: bool) -> None:
        """Take a worker back: idle again after a clean job, else killed and replaced."""
        if isinstance(worker, ServerThread):
            return  # its thread ends with its small job
        self.busy.discard(worker)
        if clean and not worker.leaving and worker.alive():
            self.idle.append(worker)
            self._notify()
            return
        self._replace(worker)

    def _replace(self, worker: Worker) -> None:
        worker.kill()
        if self._started:  # not once the pool is closed
            self.replaced += 1
            self._spawn()

    def close(self) -> None:
        """Kill every worker, the ones still starting too."""
        for task in self._tasks:
            task.cancel()
        with self._lock:
            self._closed.set()
            starting, self._starting = self._starting, set()
        for worker in [*self.idle, *self.busy, *starting]:
            worker.kill()
        self.idle.clear()
        self.busy.clear()
        self._started = False
        if self._changed is not None:  # whoever waits for a worker learns of it
            with suppress(RuntimeError):  # unless its event loop is closed already
                self._notify()
