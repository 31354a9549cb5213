"""A small pool of worker processes for the heavy work, one job at a time in each.

Why processes, not threads: the heavy work holds the GIL for seconds (regular expressions over
an ASCII file, ``tolist``), which would stall every page; an allocation that fails inside a
native library aborts the whole process (pydantic-core: "memory allocation of N bytes
failed", exit 134); and a thread cannot be stopped when its client hangs up. A worker that
dies, or that is killed because its client left, is replaced; the server process lives on.

The workers come from the ``forkserver`` context (a clean process, never a fork of the
server's threads) with ``preload`` imported once in the fork server, and each runs ``warm``
once as it starts (every job once, on small files). The first worker warms alone, before the
others start, so that it has the cores to itself and the first jobs wait less.
Starting a process blocks (the first start waits for the fork server to import ``preload``,
seconds), so it happens in a thread: the event loop serves pages meanwhile, at start-up and
while a worker is replaced.

Until the first worker is ready (a second or two after the server's first page: the fork server
imports ``preload``, the worker warms), a job that its module has marked as safe to run in the
server (:func:`run_in_server_while_starting`: the calculator's batch of a small body, which
ends in milliseconds, with nothing to cancel and no memory to run out of) runs in a thread of
the server instead of waiting; any other job waits for a worker.

Each job has a time limit, and each worker a memory cap (``RLIMIT_DATA``: the memory it
writes, not the address space it merely reserves, so that glibc's arenas, reserved but not
yet written, do not trip it). A job whose time is up, or whose client left, is stopped in the
worker (:func:`run_in_worker`: an exception raised in its Python code), so the warm worker
lives on; only a job that does not stop within ``GRACE_SECONDS`` (a native loop) costs its
worker. A worker ends with the server, and with its parent, the fork server, however they end.

Jobs travel as pickles of protocol 5: large buffers (``pickle.PickleBuffer``, NumPy arrays)
go out of band, so a 200 MB upload is not copied into a pickle on its way; to a worker, those of
a megabyte or more go in shared memory (:func:`send`), and answers come back as raw bytes.
"""

from __future__ import annotations

import asyncio
import ctypes
import logging
import mmap
import multiprocessing
import os
import pickle
import resource
import signal
import threading
import traceback
from collections import deque
from collections.abc import Callable, Sequence
from contextlib import suppress
from multiprocessing import reduction
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from types import FrameType
from typing import Any

from app.web.errors import ApiError
from mesh_normal import allocator
from mesh_normal.files import expansion

#: How a worker's job ended: its value, a refusal (an ApiError's status, sentence and field),
#: memory exhausted, a crash (the traceback, for the log), its time up, or stopped on request.
OK, REFUSED, NO_MEMORY, CRASHED = "ok", "refused", "memory", "crashed"
TIMED_OUT, CANCELLED = "timed out", "cancelled"

#: Seconds a worker has to answer once its job is to stop (its time is up, or its client left)
#: before it is killed and replaced: a job sees the stop only between two steps of its Python
#: code, not inside a kernel or a NumPy call.
GRACE_SECONDS = 2.0

#: What a worker that ran out of memory while it received a job says with NO_MEMORY: it ends,
#: as what is left of the job in the pipe cannot be told from the next one.
LEAVING = "leaving"

#: The signal that asks a worker to stop its job (its time limit is SIGALRM, its own timer).
STOP_SIGNAL = signal.SIGUSR1

#: What a worker that died from these signals most likely met: an allocation its cap refused,
#: in native code that aborts or dereferences the null pointer instead of raising MemoryError.
ALLOCATION_FAILED = frozenset({-signal.SIGSEGV, -signal.SIGABRT, -signal.SIGBUS})


logger = logging.getLogger(__name__)

#: How long the first jobs wait for the first worker to be ready: it takes a second or two
#: (the fork server's imports, then the warm-up), far longer only on a machine whose cores are
#: busy with other work.
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


class JobTimedOut(Exception):
    """The job ran past its time limit: its worker stopped it, or was killed when it did not."""


class JobCancelled(Exception):
    """The job stopped when asked to (:meth:`Worker.interrupt`); its worker lives on."""


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
    bytes: the receiver maps it read-only (:func:`receive`). For a large upload that takes
    half the time of the pipe (which copies it in pieces of the socket's
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


def serve(
    connection: Connection,
    warm: Callable[[], object] | None,
    memory_limit: int | None,
    job_memory: int | None = None,
    job_seconds: float | None = None,
    expansion_most: int | None = None,
) -> None:
    """A worker's life: warm up, cap its memory, say so, then run one job after another until
    the pipe closes.

    The cap is ``memory_limit`` bytes in all, or else ``job_memory`` bytes beyond what the warm
    worker holds; the word ``ready`` comes with what that leaves a job (None: no cap). Each job
    may run ``job_seconds``, and its upload may expand into at most ``expansion_most`` bytes
    (:mod:`mesh_normal.files.expansion`).
    """
    if expansion_most is not None:
        expansion.set_most(expansion_most)
    os.nice(WORKER_NICENESS)  # the server's pages come first when the cores are busy
    die_with_parent()
    end_with_server()
    tune_allocator()
    allocator.enable_jobs()  # a job may keep freed memory while it runs (allocator.start_job)
    signal.signal(signal.SIGALRM, _stop_job)
    signal.signal(STOP_SIGNAL, _stop_job)
    try:
        if warm is not None:
            warm()
        connection.send(("ready", cap_memory(memory_limit, job_memory)))
        while True:
            try:
                job = received(connection)
            except MemoryError:  # beyond the cap already: the rest of the message is unread
                send(connection, (NO_MEMORY, LEAVING))
                return
            # Unpickled in the job: a job too large for the memory cap fails as any other.
            outcome = run_in_worker(run_job, job, job_seconds)
            del job
            try:
                send(connection, outcome)
            except MemoryError:  # pickling the value failed: nothing was sent yet
                send(connection, (NO_MEMORY, None))
            del outcome
            allocator.end_job(_MAPPED_FROM)  # the allocator as it was, and the memory back
    except (EOFError, OSError):  # the server closed the pipe: it no longer needs this worker
        return


#: How much lower than the server's a worker's scheduling priority is: a job of seconds may
#: wait a moment for a core; a page waiting behind it is what a user sees.
WORKER_NICENESS = 5

#: Linux's ``prctl`` option: the signal this process gets when its parent ends.
_PR_SET_PDEATHSIG = 1


def die_with_parent() -> None:
    """Have the kernel kill this worker when its parent, the fork server, ends (Linux):
    without this, a busy worker of a killed fork server runs its job on, outside the server's
    tree. The server's own end is :func:`end_with_server`'s."""
    prctl = allocator.libc("prctl")
    if prctl is None:
        return
    parent = os.getppid()
    prctl(ctypes.c_int(_PR_SET_PDEATHSIG), ctypes.c_ulong(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != parent:  # the parent ended before the kernel was told
        os._exit(1)


def end_with_server() -> None:
    """End this worker as soon as the server that started it ends, even mid-job (a thread
    waits for the server's end of the pipe it was started through to close). The fork server
    alone would not: each worker holds the pipe that tells it the server ended, so it stays
    while a busy worker does."""
    server = multiprocessing.parent_process()
    if server is None or server.sentinel is None:
        return

    def watch(sentinel: int) -> None:
        wait([sentinel])
        os._exit(1)

    threading.Thread(target=watch, args=(server.sentinel,), name="server", daemon=True).start()


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
    function: Callable[..., Any], args: Sequence[Any], seconds: float | None
) -> tuple[str, Any]:
    """:func:`run` in a worker, stopped by its timer after ``seconds`` or by
    :data:`STOP_SIGNAL`: then ``(TIMED_OUT, None)`` or ``(CANCELLED, None)``."""
    global _job_running
    try:
        _job_running = True
        if seconds:
            signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            return run(function, args)
        finally:
            _job_running = False
            signal.setitimer(signal.ITIMER_REAL, 0)
    except _Stop as stop:
        signal.setitimer(signal.ITIMER_REAL, 0)  # the stop may have come before the finally
        return stop.ending, None


#: Blocks of at least this many bytes get their own mapping, returned to the system when freed.
_MAPPED_FROM = 2**20


def tune_allocator() -> None:
    """Give every block of 1 MB or more its own mapping (glibc's ``mallopt``), returned to the
    system when freed. glibc otherwise raises that threshold (up to 32 MB) after large frees,
    and then keeps what a large upload once took resident for good. Nothing elsewhere."""
    allocator.map_from(_MAPPED_FROM)


def run_job(header: bytes, buffers: list[bytes | mmap.mmap]) -> Any:
    """The job that :meth:`Worker.call` sent, pickled (:func:`send`): its function's value."""
    function, args = unpickled(header, buffers)
    return function(*args)


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
    """One worker process and the pipe to it (:func:`serve` says what the limits are)."""

    def __init__(
        self,
        context: multiprocessing.context.BaseContext,
        warm: Callable[[], object] | None,
        memory_limit: int | None,
        job_memory: int | None = None,
        job_seconds: float | None = None,
        expansion_most: int | None = None,
    ) -> None:
        self.job_seconds = job_seconds
        self.leaving = False  # the worker said it ends after this job (LEAVING)
        #: The memory a job may take in this worker (bytes; None: no cap), once it is ready.
        self.allowance: int | None = None
        self.connection, child = context.Pipe()
        self.process: BaseProcess = context.Process(  # type: ignore[attr-defined]
            target=serve,
            args=(child, warm, memory_limit, job_memory, job_seconds, expansion_most),
            daemon=True,
            name="mesh-worker",
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
        """The worker's next message; WorkerDied if it ended instead. A job that does not end
        within its time and ``GRACE_SECONDS`` more (stuck where its timer cannot stop it) is
        JobTimedOut, its worker killed."""
        seconds = None if self.job_seconds is None else self.job_seconds + GRACE_SECONDS
        try:
            await asyncio.wait_for(self.waited(), seconds)
        except TimeoutError:
            self.stop()
            raise JobTimedOut() from None
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
            try:
                await self.readable()
                if self.connection.poll():
                    return
            except OSError:  # the pipe was closed: the worker was stopped meanwhile
                self.process.join()
                raise WorkerDied(self.process.exitcode) from None
            if not self.process.is_alive():
                raise WorkerDied(self.process.exitcode)

    async def ready(self) -> None:
        """Wait for the worker's word that it has warmed up; WorkerDied if it ended instead."""
        await self.waited()
        try:
            _, self.allowance = self.connection.recv()
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
        except (BrokenPipeError, OSError):  # it ended while the job was on its way
            self.process.join()
            ending, value = self.last_word()
        else:
            ending, value = await self.answer()
        self.leaving = ending == NO_MEMORY and value == LEAVING
        return ended(ending, value)

    def last_word(self) -> Any:
        """What an ended worker said before it ended (it may say why), else WorkerDied."""
        with suppress(EOFError, OSError):
            if self.connection.poll():
                return receive(self.connection)
        raise WorkerDied(self.process.exitcode)

    def interrupt(self) -> None:
        """Ask the worker to stop its job: :meth:`call` then ends (JobCancelled, or however
        the job ended if it was ending anyway), within ``GRACE_SECONDS`` if the worker is fine."""
        with suppress(ProcessLookupError):
            if self.process.pid is not None and self.process.is_alive():
                os.kill(self.process.pid, STOP_SIGNAL)

    def stop(self) -> None:
        """End the worker now (SIGKILL: a job in a native loop does not look at signals)."""
        self.process.kill()
        self.process.join()
        self.connection.close()


def ended(ending: str, value: Any) -> Any:
    """A job's value, or the exception that says how it ended otherwise."""
    if ending == REFUSED:
        raise ApiError(*value)
    if ending == NO_MEMORY:
        raise WorkerOutOfMemory()
    if ending == CRASHED:
        raise WorkerCrashed(value)
    if ending == TIMED_OUT:
        raise JobTimedOut()
    if ending == CANCELLED:
        raise JobCancelled()
    return value


class ServerThread:
    """Stands in for a worker while none is ready: the job runs in a thread of the server (see
    :func:`run_in_server_while_starting`); its endings come back as a worker's do. Its jobs
    are small: no time limit, no cap, and nothing to stop."""

    allowance: int | None = None

    async def call(self, function: Callable[..., Any], args: Sequence[Any]) -> Any:
        return ended(*await asyncio.to_thread(run, function, args))

    def interrupt(self) -> None:
        """Its small job ends on its own, in milliseconds."""


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
        job_memory: int | None = None,
        job_seconds: float | None = None,
        expansion_most: int | None = None,
    ) -> None:
        """``memory_limit``, ``job_memory``, ``job_seconds`` and ``expansion_most``: each
        worker's limits (:func:`serve`)."""
        self.count = count
        self.warm = warm
        self.memory_limit = memory_limit
        self.job_memory = job_memory
        self.job_seconds = job_seconds
        self.expansion_most = expansion_most
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
        worker = Worker(
            self.context,
            self.warm,
            self.memory_limit,
            self.job_memory,
            self.job_seconds,
            self.expansion_most,
        )
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
        ready (the fork server's imports, then the warm-up), up to STARTUP_SECONDS; or,
        for a small ``job`` marked so (:func:`run_in_server_while_starting`), a thread of the
        server at once."""
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
            worker = self.idle.popleft()
            if worker.process.is_alive():
                self.busy.add(worker)
                return worker
            self._replace(worker)  # it died idle (e.g. its fork server was killed)

    def release(self, worker: Worker | ServerThread, clean: bool) -> None:
        """Take a worker back: idle again after a clean job, else stopped and replaced."""
        if isinstance(worker, ServerThread):
            return  # its thread ends with its small job
        self.busy.discard(worker)
        if clean and not worker.leaving and worker.process.is_alive():
            self.idle.append(worker)
            self._notify()
            return
        self._replace(worker)

    def _replace(self, worker: Worker) -> None:
        worker.stop()
        if self._started:  # not once the pool is closed
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
        if self._changed is not None:  # whoever waits for a worker learns of it
            with suppress(RuntimeError):  # unless its event loop is closed already
                self._notify()
