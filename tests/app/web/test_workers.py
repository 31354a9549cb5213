"""app/web/workers.py: real worker processes, one job at a time; a dead one is replaced."""

from __future__ import annotations

import asyncio
import os
import signal
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from app.web.errors import ApiError
from app.web.workers import WorkerDied, WorkerOutOfMemory, WorkerPool
from tests.app import jobhooks


def with_pool(scenario: Callable[[WorkerPool], Awaitable[Any]], count: int = 1) -> Any:
    async def main() -> Any:
        pool = WorkerPool(count)
        pool.start()
        try:
            return await scenario(pool)
        finally:
            pool.close()

    return asyncio.run(main())


async def call(pool: WorkerPool, function: Callable[..., Any], *args: Any) -> Any:
    worker = await pool.acquire(60)
    assert worker is not None
    clean = False
    try:
        value = await worker.call(function, args)
        clean = True
        return value
    except (ApiError, WorkerOutOfMemory):
        clean = True  # the job failed, its worker is fine (as app.web.jobs treats it)
        raise
    finally:
        pool.release(worker, clean)


def test_a_job_runs_in_another_process_and_large_bytes_travel_whole() -> None:
    data = bytes(range(256)) * 4096  # 1 MB, out of band both ways

    async def scenario(pool: WorkerPool) -> tuple[int, bytes]:
        return await call(pool, jobhooks.value, data)

    pid, back = with_pool(scenario)
    assert pid != os.getpid()
    assert back == data


def test_an_aborted_worker_is_replaced() -> None:
    async def scenario(pool: WorkerPool) -> tuple[int | None, int, int]:
        first, _ = await call(pool, jobhooks.value, b"")
        with pytest.raises(WorkerDied) as died:
            await call(pool, jobhooks.abort, None)
        second, _ = await call(pool, jobhooks.value, b"")
        assert second != first
        return died.value.exitcode, pool.replaced, len(pool.idle)

    assert with_pool(scenario) == (-signal.SIGABRT, 1, 1)


def test_memory_errors_and_refusals_come_back_as_such() -> None:
    async def scenario(pool: WorkerPool) -> None:
        first, _ = await call(pool, jobhooks.value, b"")
        with pytest.raises(WorkerOutOfMemory):
            await call(pool, jobhooks.exhaust, None)
        with pytest.raises(ApiError) as refused:
            await call(pool, jobhooks.refuse, None)
        assert (refused.value.status_code, refused.value.error, refused.value.field) == (
            400,
            "No.",
            "file",
        )
        again, _ = await call(pool, jobhooks.value, b"")
        assert again == first and pool.replaced == 0

    with_pool(scenario)


def test_a_cancelled_call_stops_its_worker() -> None:
    async def scenario(pool: WorkerPool) -> None:
        worker = await pool.acquire(60)
        assert worker is not None
        job = asyncio.ensure_future(worker.call(jobhooks.sleep_forever, ()))
        await asyncio.sleep(0)
        job.cancel()
        with pytest.raises(asyncio.CancelledError):
            await job
        pool.release(worker, clean=False)
        assert not worker.process.is_alive()
        await call(pool, jobhooks.value, b"")  # the replacement works

    with_pool(scenario)
