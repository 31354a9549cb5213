"""app/web/jobs.py: admission against the job slots and the memory budget (no timed waits:
every step is driven by the test)."""

from __future__ import annotations

import asyncio
import threading

import pytest

from app.web.errors import ApiError
from app.web.jobs import BUSY, Admission

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


def test_without_a_writable_temporary_folder_the_jobs_run_in_the_server(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A read-only root without a tmpfs: worker processes cannot start (the forkserver needs a
    # socket folder), so the pages and small uploads go on in the server's threads.
    from app.config import load_settings
    from app.web import jobs

    monkeypatch.setattr(jobs, "temp_dir_problem", lambda: "No usable temporary directory")
    assert jobs.Jobs(load_settings(in_process=False)).pool is None
    monkeypatch.setattr(jobs, "temp_dir_problem", lambda: None)
    pool = jobs.Jobs(load_settings(in_process=False)).pool
    assert pool is not None  # made, not started: no process runs until start()


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
