"""app/web/jobs.py: admission against the job slots and the memory budget (no timed waits:
every step is driven by the test)."""

from __future__ import annotations

import asyncio
import os
import threading

import pytest

from app.web.errors import ApiError
from app.web.jobs import BUSY, Admission
from app.web.workers import Worker

MB = 2**20


def run(coroutine):  # type: ignore[no-untyped-def]
    return asyncio.run(coroutine)


def test_a_job_beyond_the_whole_budget_is_a_413() -> None:
    async def scenario() -> None:
        admission = Admission(slots=2, budget=100 * MB, wait_seconds=0, queue_length=4)
        with pytest.raises(ApiError) as caught:
            async with admission.admit(101 * MB):
                pass
        assert caught.value.status_code == 413 and caught.value.field == "file"
        assert "101 MB" in caught.value.error and "100 MB" in caught.value.error
        async with admission.admit(100 * MB):  # exactly the budget fits
            assert admission.charged == 100 * MB
        assert (admission.running, admission.charged) == (0, 0)

    run(scenario())


@pytest.mark.parametrize(("first", "second"), [(10, 10), (60, 50)])
def test_full_slots_or_budget_is_a_503_with_retry_after(first: int, second: int) -> None:
    """One slot taken (10 + 10 MB) or the budget taken (60 + 50 > 100 MB): the next is busy."""

    async def scenario() -> None:
        slots = 1 if first == 10 else 2
        admission = Admission(slots=slots, budget=100 * MB, wait_seconds=0, queue_length=4)
        async with admission.admit(first * MB):
            with pytest.raises(ApiError) as caught:
                async with admission.admit(second * MB):
                    pass
        assert caught.value.status_code == 503 and caught.value.error == BUSY
        assert int(caught.value.headers["retry-after"]) > 0
        assert admission.waiting == 0

    run(scenario())


def test_a_waiting_job_starts_when_a_slot_frees() -> None:
    async def scenario() -> None:
        admission = Admission(slots=1, budget=100 * MB, wait_seconds=600, queue_length=1)
        order: list[str] = []
        release = asyncio.Event()

        async def first() -> None:
            async with admission.admit(MB):
                order.append("first runs")
                await release.wait()
            order.append("first done")

        async def second() -> None:
            async with admission.admit(MB):
                order.append("second runs")

        one = asyncio.create_task(first())
        await asyncio.sleep(0)
        two = asyncio.create_task(second())
        await asyncio.sleep(0)
        assert admission.waiting == 1 and order == ["first runs"]
        with pytest.raises(ApiError):  # the queue holds one: a third is refused at once
            async with admission.admit(MB):
                pass
        release.set()
        await asyncio.gather(one, two)
        assert order == ["first runs", "first done", "second runs"]

    run(scenario())


def test_without_a_writable_temporary_folder_the_jobs_still_run_in_workers(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A read-only root without a tmpfs: the workers need no file (a socket pair and a pipe
    join them to the server), so a job runs in one."""
    import tempfile

    from app.config import load_settings
    from app.web import jobs
    from tests.app import jobhooks

    monkeypatch.setattr(tempfile, "tempdir", None)
    monkeypatch.setattr(tempfile, "_candidate_tempdir_list", list)  # no folder to try

    async def scenario() -> int:
        pool = jobs.Jobs(load_settings(in_process=False, workers=1)).pool
        assert pool is not None
        try:
            worker = await pool.acquire(60)
            assert isinstance(worker, Worker)
            pid, _ = await worker.run(jobhooks.value, (b"",))
            pool.release(worker, clean=True)
            return int(pid)
        finally:
            pool.close()

    with pytest.raises(FileNotFoundError):
        tempfile.gettempdir()
    assert run(scenario()) != os.getpid()


def test_after_a_job_the_server_gives_freed_memory_back_twice(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """malloc_trim soon after the job (in a thread), and once more later; the waits are the
    test's, not the clock's (the delays are set to nothing)."""
    from app.config import load_settings
    from app.web import jobs

    trims: list[str] = []
    monkeypatch.setattr(jobs, "TRIM_DELAYS_SECONDS", (0.0, 0.0))

    async def scenario() -> None:
        loop = asyncio.get_running_loop()
        trimmed = asyncio.Event()

        def give_back() -> None:
            trims.append(threading.current_thread().name)
            if len(trims) == 2:
                loop.call_soon_threadsafe(trimmed.set)

        monkeypatch.setattr(jobs, "give_back", give_back)
        heavy = jobs.Jobs(load_settings(in_process=True))
        assert await heavy.run(None, MB, sum, [1, 2]) == 3  # type: ignore[arg-type]
        assert trims == []  # not while the answer is being written
        await asyncio.wait_for(trimmed.wait(), 60)
        heavy.close()

    run(scenario())
    assert len(trims) == 2
    assert threading.main_thread().name not in trims  # never in the event loop's thread


def test_jobs_one_after_another_do_not_put_the_trim_off(monkeypatch: pytest.MonkeyPatch) -> None:
    """Under steady load the trim still comes a second after the first job of a run of them."""
    from app.config import load_settings
    from app.web import jobs

    monkeypatch.setattr(jobs, "TRIM_DELAYS_SECONDS", (600.0, 600.0))

    async def scenario() -> None:
        heavy = jobs.Jobs(load_settings(in_process=True))
        await heavy.run(None, MB, sum, [1])  # type: ignore[arg-type]
        pending = heavy._trim
        assert pending is not None
        await heavy.run(None, MB, sum, [2])  # type: ignore[arg-type]
        assert heavy._trim is pending and not pending.cancelled()
        heavy.close()
        assert pending.cancelled()

    run(scenario())


def test_a_worker_s_memory_cap_is_by_default_the_budget_beyond_its_own() -> None:
    from app.config import load_settings
    from app.web import jobs

    pool = jobs.Jobs(load_settings(in_process=False, memory_budget_mb=300)).pool
    assert pool is not None
    assert (pool.settings.memory_limit, pool.settings.job_memory) == (None, 300 * MB)
    pool = jobs.Jobs(load_settings(in_process=False, worker_memory_mb=500)).pool
    assert pool is not None
    assert (pool.settings.memory_limit, pool.settings.job_memory) == (500 * MB, None)
    pool = jobs.Jobs(load_settings(in_process=False, job_seconds=7)).pool
    assert pool is not None and pool.settings.job_seconds == 7


@pytest.mark.parametrize(
    ("error", "allowance", "status", "words"),
    [
        ("time", 100 * MB, 422, "took longer than the 60 s one file may take here"),
        ("memory", 100 * MB, 413, "needs more memory than the 100 MB this server gives one file"),
        ("segfault", 100 * MB, 413, "needs more memory than the 100 MB"),
        ("abort", 100 * MB, 413, "needs more memory than the 100 MB"),
        ("killed", 100 * MB, 503, "ran out of memory"),
        ("memory", None, 503, "ran out of memory"),
        ("abort", None, 503, "ran out of memory"),
    ],
)
def test_a_job_that_ran_out_of_time_or_memory_says_so(
    error: str, allowance: int | None, status: int, words: str
) -> None:
    """Beyond its time or its worker's cap (MemoryError, or death by a signal that a failed
    allocation gives) the file is the cause: 422 or 413, never "try again". A worker killed
    from outside, or one without a cap, is the server's memory: 503, try again later."""
    import signal
    from types import SimpleNamespace

    from app.config import load_settings
    from app.web import jobs, workers

    exceptions: dict[str, Exception] = {
        "time": workers.JobTimedOut(),
        "memory": workers.WorkerOutOfMemory(),
        "segfault": workers.WorkerDied(-signal.SIGSEGV),
        "abort": workers.WorkerDied(-signal.SIGABRT),
        "killed": workers.WorkerDied(-signal.SIGKILL),
    }
    heavy = jobs.Jobs(load_settings(in_process=True, job_seconds=60))
    request = SimpleNamespace(url=SimpleNamespace(path="/api/mesh"))
    worker = SimpleNamespace(allowance=allowance)
    answer = heavy._answer(request, worker, exceptions[error])  # type: ignore[arg-type]
    assert answer.status_code == status and words in answer.error
    assert (answer.field == "file") == (status != 503)
    assert ("retry-after" in answer.headers) == (status == 503)


def test_once_the_server_stops_no_job_runs_and_stopped_ones_say_so() -> None:
    import signal
    from types import SimpleNamespace

    from app.config import load_settings
    from app.web import jobs, workers

    heavy = jobs.Jobs(load_settings(in_process=True))
    heavy.shut_down()
    with pytest.raises(ApiError) as refused:
        run(heavy.run(None, MB, sum, [1]))  # type: ignore[arg-type]
    assert refused.value.status_code == 503 and refused.value.error == jobs.SHUTTING_DOWN
    request = SimpleNamespace(url=SimpleNamespace(path="/api/mesh"))
    died = workers.WorkerDied(-signal.SIGKILL)
    answer = heavy._answer(request, SimpleNamespace(allowance=MB), died)  # type: ignore[arg-type]
    assert answer.error == jobs.SHUTTING_DOWN and "retry-after" in answer.headers
    heavy.close()
