"""Heavy jobs: admitted against a slot count and a memory budget, then run in a worker.

A job says up front how much memory it may take (its estimate). It runs when a slot is free
and its estimate fits in what the running jobs leave of the budget; otherwise it waits, at
most ``queue_seconds`` and behind at most ``queue_length`` others, and then the answer is a
503 with ``Retry-After``. A job whose estimate alone exceeds the whole budget is a 413: no
wait would help. Pages, static files and the calculator's single triangles never come here,
so they never wait; a large calculator batch does (:mod:`app.calculator.batch`).

The jobs run in :class:`app.web.workers.WorkerPool` processes (or, with ``in_process``, in
threads of the server, for tests and debugging, without the limits below). Each job may run
``job_seconds`` and take the memory a worker's cap leaves it: ``worker_memory_mb`` in all, or
by default the whole ``memory_budget_mb`` beyond what the warm worker itself holds. Beyond
either, the answer blames the file (a 422 for the time, a 413 for the memory: the same file
would fail again), and the worker lives on. A client that hangs up stops its job, its worker
kept if the job stops within :data:`app.web.workers.GRACE_SECONDS`. A worker killed from
outside (the system out of memory) is a 503 saying that the server ran out of memory. When the
server is asked to stop (:meth:`Jobs.shut_down`), the running jobs end at once, as 503s.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager, suppress
from typing import Any, TypeVar

from starlette.concurrency import run_in_threadpool
from starlette.requests import Request

from app.config import RETRY_AFTER_SECONDS, Settings
from app.web.errors import ApiError
from app.web.workers import (
    ALLOCATION_FAILED,
    GRACE_SECONDS,
    SPARE,
    JobTimedOut,
    ServerThread,
    Worker,
    WorkerCrashed,
    WorkerDied,
    WorkerOutOfMemory,
    WorkerPool,
)
from mesh_normal.allocator import give_back
from mesh_normal.files import expansion

logger = logging.getLogger(__name__)

Value = TypeVar("Value")

BUSY = (
    "The server is busy with other files right now; try again in a few seconds "
    "(Retry-After says when)."
)
#: When, after the last heavy job ended, the server gives the memory it freed back to the
#: system: soon (the job's answer has usually been sent by then), and once more later.
TRIM_DELAYS_SECONDS = (1.0, 10.0)

#: How often a job whose client left is asked to stop, until it does.
STOP_AGAIN_SECONDS = 0.1

NO_MEMORY = (
    "The server ran out of memory while working on this file; try again later, "
    "or send a smaller file."
)


SHUTTING_DOWN = "The server is restarting; try again in a few seconds (Retry-After says when)."


def busy() -> ApiError:
    return ApiError(503, BUSY, None, headers={"retry-after": str(RETRY_AFTER_SECONDS)})


def out_of_memory() -> ApiError:
    return ApiError(503, NO_MEMORY, None, headers={"retry-after": str(RETRY_AFTER_SECONDS)})


def shutting_down() -> ApiError:
    return ApiError(503, SHUTTING_DOWN, None, headers={"retry-after": str(RETRY_AFTER_SECONDS)})


def too_long(seconds: float) -> ApiError:
    return ApiError(
        422,
        f"This file took longer than the {seconds:g} s one file may take here; "
        "send a smaller file.",
        "file",
    )


def beyond_allowance(allowance: int) -> ApiError:
    return ApiError(
        413,
        f"This file needs more memory than the {allowance / 2**20:,.0f} MB this server gives "
        "one file; send a smaller file.",
        "file",
    )


def beyond_budget(estimate: int, budget: int) -> ApiError:
    return ApiError(
        413,
        f"This file would need about {estimate / 2**20:,.0f} MB of memory, more than this "
        f"server ever gives one file ({budget / 2**20:,.0f} MB); send a smaller file.",
        "file",
    )


class Admission:
    """How many jobs run and how much of the memory budget they hold, on one event loop."""

    def __init__(self, slots: int, budget: int, wait_seconds: float, queue_length: int) -> None:
        self.slots = slots
        self.budget = budget
        self.wait_seconds = wait_seconds
        self.queue_length = queue_length
        self.running = 0
        self.charged = 0
        self.waiting = 0
        self._changed: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    def _fits(self, estimate: int) -> bool:
        return self.running < self.slots and self.charged + estimate <= self.budget

    def _event(self) -> asyncio.Event:
        # Made on first use, in the loop that serves (a test client may bring its own loop).
        loop = asyncio.get_running_loop()
        if self._changed is None or self._loop is not loop:
            self._changed, self._loop = asyncio.Event(), loop
        return self._changed

    @asynccontextmanager
    async def admit(self, estimate: int) -> AsyncIterator[None]:
        """Hold a slot and ``estimate`` bytes of the budget for the ``with`` block."""
        if estimate > self.budget:
            raise beyond_budget(estimate, self.budget)
        if not self._fits(estimate):
            await self._wait(estimate)
        self.running += 1
        self.charged += estimate
        try:
            yield
        finally:
            self.running -= 1
            self.charged -= estimate
            event, self._changed = self._event(), None
            event.set()

    async def _wait(self, estimate: int) -> None:
        if self.waiting >= self.queue_length:
            raise busy()
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.wait_seconds
        self.waiting += 1
        try:
            while not self._fits(estimate):
                left = deadline - loop.time()
                if left <= 0:
                    raise busy()
                with suppress(TimeoutError):
                    await asyncio.wait_for(self._event().wait(), left)
        finally:
            self.waiting -= 1


class Jobs:
    """The server's heavy jobs: admission, then a worker process (or a thread)."""

    def __init__(
        self,
        settings: Settings,
        *,
        warm: Callable[[], object] | None = None,
        preload: tuple[str, ...] = (),
    ) -> None:
        self.settings = settings
        self._trim: asyncio.TimerHandle | None = None
        self._trim_loop: asyncio.AbstractEventLoop | None = None
        self._trim_step = 0  # of TRIM_DELAYS_SECONDS, the one the pending trim is
        self.closing = False  # the server is stopping: no job runs any more
        self.admission = Admission(
            settings.workers,
            settings.memory_budget,
            settings.queue_seconds,
            settings.queue_length,
        )
        limit = settings.worker_memory_mb
        self.pool = (
            None
            if settings.in_process
            else WorkerPool(
                settings.workers,
                spare=SPARE,
                warm=warm,
                preload=preload,
                memory_limit=None if limit is None else int(limit * 2**20),
                job_memory=settings.memory_budget if limit is None else None,
                job_seconds=settings.job_seconds,
                expansion_most=settings.expansion_limit,
            )
        )

    def start(self) -> None:
        if self.pool is not None:
            self.pool.start()

    def shut_down(self) -> None:
        """The server is stopping: end the running jobs now (each answers a 503) and refuse
        new ones, so that the server does not wait for them."""
        self.closing = True
        if self.pool is not None:
            self.pool.close()

    def close(self) -> None:
        if self._trim is not None:
            self._trim.cancel()
            self._trim = None
        if self.pool is not None:
            self.pool.close()

    async def run(
        self,
        request: Request,
        estimate: int,
        function: Callable[..., Value],
        *args: Any,
    ) -> Value:
        """``function(*args)`` as a heavy job of about ``estimate`` bytes, for ``request``."""
        try:
            async with self.admission.admit(estimate):
                if self.closing:
                    raise shutting_down()
                if self.pool is None:
                    # This task's context, which the thread runs in: no other request's.
                    expansion.set_most(self.settings.expansion_limit)
                    try:
                        return await run_in_threadpool(function, *args)
                    except MemoryError:
                        raise out_of_memory() from None
                return await self._in_worker(self.pool, request, function, args)
        finally:
            self._trim_soon()

    def _trim_soon(self) -> None:
        """Give freed memory back to the system (``malloc_trim``, in a thread) a moment after
        a job, when its upload, its result and the answer written from it are let go of, and
        once more a while later (an answer streamed to a slow client ends late). Blocks of
        1 MB or more go back as they are freed (``tune_allocator``); this returns the smaller
        ones an answer is written in (JSON and CSV blocks, h11's buffers), which the allocator
        would otherwise keep resident."""
        loop = asyncio.get_running_loop()
        if self._trim is not None and self._trim_loop is loop:
            if self._trim_step == 1:  # one is coming soon: under load, one a second at most
                return
            self._trim.cancel()
        self._trim_loop = loop
        self._trim_step = 1
        self._trim = loop.call_later(TRIM_DELAYS_SECONDS[0], self._trimmed, loop)

    def _trimmed(self, loop: asyncio.AbstractEventLoop) -> None:
        loop.run_in_executor(None, give_back)
        self._trim = None
        if self._trim_step < len(TRIM_DELAYS_SECONDS):
            delay = TRIM_DELAYS_SECONDS[self._trim_step]
            self._trim_step += 1
            self._trim = loop.call_later(delay, self._trimmed, loop)

    async def _in_worker(
        self,
        pool: WorkerPool,
        request: Request,
        function: Callable[..., Value],
        args: tuple[Any, ...],
    ) -> Value:
        worker = await pool.acquire(self.settings.queue_seconds, (function, args))
        if worker is None:  # the workers are still starting, or being replaced
            raise shutting_down() if self.closing else busy()
        job = asyncio.ensure_future(worker.run(function, args))
        gone = asyncio.ensure_future(disconnected(request))
        clean = False
        try:
            await asyncio.wait({job, gone}, return_when=asyncio.FIRST_COMPLETED)
            if not job.done():  # the client hung up: stop its work
                clean = await stop(worker, job)
                logger.info(
                    "client left during %s: its job %s",
                    request.url.path,
                    "stopped" if clean else "did not stop, its worker was replaced",
                )
                raise ApiError(499, "The client closed the connection before the answer.")
            value: Value = job.result()
            clean = True
            return value
        except ApiError as error:  # the job's refusal, or the client gone
            clean = clean or error.status_code != 499
            raise
        except (WorkerOutOfMemory, JobTimedOut, WorkerDied) as error:
            clean = True  # the worker lives on, unless it died or was killed (release sees)
            raise self._answer(request, worker, error) from None
        except WorkerCrashed as error:
            logger.error("a job failed on %s:\n%s", request.url.path, error)
            raise
        finally:
            gone.cancel()
            job.cancel()
            with suppress(BaseException):
                await job
            pool.release(worker, clean)

    def _answer(
        self,
        request: Request,
        worker: Worker | ServerThread,
        error: WorkerOutOfMemory | JobTimedOut | WorkerDied,
    ) -> ApiError:
        """What a job that ran out of time or memory, or whose worker died, answers; logged."""
        path = request.url.path
        if self.closing and not isinstance(error, WorkerOutOfMemory):
            return shutting_down()  # its worker was stopped with the server
        if isinstance(error, JobTimedOut):
            logger.warning("a job on %s ran past its %g s", path, self.settings.job_seconds)
            return too_long(self.settings.job_seconds)
        logger.warning("a worker ran out of memory or ended on %s: %s", path, error)
        capped = isinstance(error, WorkerOutOfMemory) or error.exitcode in ALLOCATION_FAILED
        if capped and worker.allowance is not None:
            return beyond_allowance(worker.allowance)
        return out_of_memory()


async def stop(worker: Worker | ServerThread, job: asyncio.Future[Any]) -> bool:
    """Stop ``worker``'s job (its client left); True if it stopped within ``GRACE_SECONDS``
    (the worker lives on), False if the worker must be replaced."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + GRACE_SECONDS
    while not job.done() and loop.time() < deadline:
        # Asked again until it stops: a client that leaves right after its body may do so
        # before the worker has the job, when a stop is ignored.
        worker.interrupt()
        await asyncio.wait({job}, timeout=STOP_AGAIN_SECONDS)
    if not job.done():
        return False
    error = job.exception()
    return not isinstance(error, WorkerDied | JobTimedOut)


async def disconnected(request: Request) -> None:
    """Return when the client hangs up (the body is read, so only ``http.disconnect`` is left)."""
    while True:
        message = await request.receive()
        if message["type"] == "http.disconnect":
            return
