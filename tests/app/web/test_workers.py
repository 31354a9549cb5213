"""app/web/workers.py over mesh_normal/workers.py: real worker processes, one job at a time; a
dead one is replaced, by a spare at once if the pool keeps one."""

from __future__ import annotations

import asyncio
import os
import signal
import threading
from collections.abc import Awaitable, Callable
from typing import Any

import numpy as np
import pytest

from app.mesh.uploads import Upload
from app.web import workers
from app.web.errors import ApiError
from app.web.workers import (
    JobCancelled,
    JobTimedOut,
    Worker,
    WorkerDied,
    WorkerOutOfMemory,
    WorkerPool,
)
from mesh_normal import allocator
from mesh_normal import workers as library
from mesh_normal.files import expansion
from tests.app import jobhooks
from tests.meshes import binary_stl

#: How long a test waits for something that should happen at once (only a failure waits).
PATIENCE_S = 30


def with_pool(
    scenario: Callable[[WorkerPool], Awaitable[Any]], count: int = 1, **limits: Any
) -> Any:
    async def main() -> Any:
        pool = WorkerPool(count, **limits)
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
        value = await worker.run(function, args)
        clean = True
        return value
    except (ApiError, WorkerOutOfMemory, JobTimedOut, JobCancelled):
        clean = True  # the job failed, its worker is fine unless it was killed (release sees)
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
        job = asyncio.ensure_future(worker.run(jobhooks.sleep_forever, ()))
        await asyncio.sleep(0)
        job.cancel()
        with pytest.raises(asyncio.CancelledError):
            await job
        pool.release(worker, clean=False)
        assert not worker.alive()
        await call(pool, jobhooks.value, b"")  # the replacement works

    with_pool(scenario)


def test_a_worker_starts_while_the_event_loop_goes_on(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each worker's start (the first, and a replacement) waits, in the thread that starts
    the process, until a coroutine has run: the wait ends at once if the start leaves the
    event loop free, and only after PATIENCE_S, as False, if it blocks the loop."""
    loop_ran = threading.Event()
    waits: list[bool] = []

    class Waiting(Worker):
        def __init__(self, *args: Any) -> None:
            waits.append(loop_ran.wait(PATIENCE_S))
            super().__init__(*args)

    monkeypatch.setattr(workers, "Worker", Waiting)

    async def scenario(pool: WorkerPool) -> list[bool]:
        assert not pool.idle  # start() returned before the worker was ready
        await asyncio.sleep(0)  # the worker's start begins
        loop_ran.set()
        first, _ = await call(pool, jobhooks.value, b"")
        loop_ran.clear()
        with pytest.raises(WorkerDied):  # its replacement starts as the first did
            await call(pool, jobhooks.abort, None)
        await asyncio.sleep(0)
        loop_ran.set()
        second, _ = await call(pool, jobhooks.value, b"")
        assert second != first
        return waits

    assert with_pool(scenario) == [True, True]


def test_a_worker_whose_start_ends_after_the_pool_closed_is_stopped(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    closed = threading.Event()
    started: list[Worker] = []

    class Late(Worker):
        def __init__(self, *args: Any) -> None:
            assert closed.wait(PATIENCE_S)
            super().__init__(*args)
            started.append(self)

    monkeypatch.setattr(workers, "Worker", Late)

    pool = WorkerPool(1)

    async def main() -> None:
        pool.start()
        await asyncio.sleep(0)  # the worker's start begins, in its thread
        pool.close()
        closed.set()

    asyncio.run(main())
    pool.executor.shutdown(wait=True)  # the thread that started it has ended
    assert len(started) == 1
    assert not started[0].alive()


def test_a_small_job_marked_so_runs_in_the_server_until_a_worker_is_ready(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Before the first worker is ready, a marked job whose arguments pass its test runs in a
    thread of this process; an unmarked job, or one that fails the test, waits for a worker;
    once a worker is ready, every job goes to one."""
    monkeypatch.setattr(workers, "_STARTUP_JOBS", {})
    workers.run_in_server_while_starting(jobhooks.value, lambda data: len(data) <= 4)

    async def scenario(pool: WorkerPool) -> None:
        assert not pool.idle  # the worker is still starting
        thread = await pool.acquire(60, (jobhooks.value, (b"tiny",)))
        assert isinstance(thread, workers.ServerThread)
        pid, back = await thread.run(jobhooks.value, (b"tiny",))
        pool.release(thread, clean=True)
        assert (pid, back) == (os.getpid(), b"tiny")
        with pytest.raises(ApiError):  # a refusal comes back as from a worker
            await workers.ServerThread().run(jobhooks.refuse, ())
        # Too large for its test, then not marked: both wait for the worker.
        worker = await pool.acquire(60, (jobhooks.value, (b"large",)))
        assert isinstance(worker, Worker)
        pool.release(worker, clean=True)
        assert pool._warmed is not None and pool._warmed.is_set()
        worker = await pool.acquire(60, (jobhooks.value, (b"tiny",)))
        assert isinstance(worker, Worker)  # a worker is ready now: it takes the job
        pid, _ = await worker.run(jobhooks.value, (b"tiny",))
        pool.release(worker, clean=True)
        assert pid != os.getpid()

    with_pool(scenario)


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="reads /proc")
def test_a_large_binary_stl_has_its_memory_faulted_in_and_given_back_after() -> None:
    """A job reading a 10 MB binary STL (faulted in ahead from that size on, here) finds 3
    times that faulted in for its arrays; the next job finds it given back (the prefaulting
    ended before the trim)."""
    corners = np.random.default_rng(7).random((200_000, 3, 3))
    stl = Upload(binary_stl(corners), "big.stl")
    faulted = allocator.ARRAYS_PER_STL_BYTE * len(stl.data) >> 20

    async def scenario(pool: WorkerPool) -> tuple[int, int, int]:
        before = await call(pool, jobhooks.resident, None)
        during = await call(pool, jobhooks.resident, stl, len(stl.data))
        after = await call(pool, jobhooks.resident, None)
        return before, during, after

    before, during, after = with_pool(scenario)
    assert during > before + faulted
    assert after < during - faulted + 8


def _sent_and_received(value: Any) -> Any:
    """``value`` through a pipe as a job goes to its worker (the sending in a thread, as the
    pipe's buffer may fill)."""
    import multiprocessing

    ours, theirs = multiprocessing.Pipe()
    sender = threading.Thread(target=library.send, args=(ours, value, library.SHARED_FROM))
    sender.start()
    try:
        return library.receive(theirs)
    finally:
        sender.join()
        ours.close()
        theirs.close()


@pytest.mark.skipif(not hasattr(os, "memfd_create"), reason="shared memory needs memfd_create")
def test_a_large_upload_travels_in_shared_memory_and_reads_the_same() -> None:
    import mmap

    from app.mesh import work
    from benchmarks.mesh_kernels import torus_mesh
    from mesh_normal.files import write_mesh

    vertices, faces = torus_mesh(42_000)
    stl = write_mesh(vertices, faces, "stl")
    obj = write_mesh(vertices, faces, "obj")
    assert len(stl) >= library.SHARED_FROM and len(obj) >= library.SHARED_FROM
    small = write_mesh(vertices[:3], np.array([[0, 1, 2]]), "stl")
    descriptors = set(os.listdir("/proc/self/fd"))
    for upload in (Upload(stl, "torus.stl"), Upload(obj, "torus.obj"), Upload(small, "t.stl")):
        function, (received, weld) = _sent_and_received((work.report, (upload, None)))
        assert function is work.report and weld is None
        assert received.filename == upload.filename and received.size == upload.size
        if len(upload.data) >= library.SHARED_FROM:
            assert isinstance(received.mapped, mmap.mmap) and received.data == b""
            assert received.mapped[:] == upload.data
        else:
            assert received.mapped is None and received.data == upload.data
        assert work.report(received, None) == work.report(upload, None)
        del received
    assert set(os.listdir("/proc/self/fd")) <= descriptors  # no descriptor left open


def test_a_job_s_buffers_without_shared_memory_come_through_the_pipe() -> None:
    import multiprocessing

    value = (np.arange(300_000), b"x" * 10, Upload(b"y" * (library.SHARED_FROM + 1), "y.stl"))
    ours, theirs = multiprocessing.Pipe()
    sender = threading.Thread(target=library.send, args=(ours, value))  # no shared_from
    sender.start()
    array, text, upload = library.receive(theirs)
    sender.join()
    np.testing.assert_array_equal(array, value[0])
    assert text == value[1] and upload.data == value[2].data and upload.mapped is None


def test_a_job_past_its_time_is_stopped_and_its_worker_lives_on() -> None:
    async def scenario(pool: WorkerPool) -> None:
        first, _ = await call(pool, jobhooks.value, b"")
        with pytest.raises(JobTimedOut):
            await call(pool, jobhooks.sleep_forever)
        again, _ = await call(pool, jobhooks.value, b"")
        assert again == first and pool.replaced == 0

    with_pool(scenario, job_seconds=0.5, preload=("tests.app.jobhooks",))


def test_a_job_that_does_not_stop_in_time_costs_its_worker() -> None:
    """A job that sees no signal (as one in a native loop) is killed after its time and the
    grace; a new worker takes the next job."""

    async def scenario(pool: WorkerPool) -> None:
        first, _ = await call(pool, jobhooks.value, b"")
        with pytest.raises(JobTimedOut):
            await asyncio.wait_for(call(pool, jobhooks.stuck), PATIENCE_S)
        again, _ = await call(pool, jobhooks.value, b"")
        assert again != first and pool.replaced == 1

    with_pool(scenario, job_seconds=0.5, preload=("tests.app.jobhooks",))


def test_a_job_asked_to_stop_stops_and_its_worker_lives_on() -> None:
    async def scenario(pool: WorkerPool) -> None:
        first, _ = await call(pool, jobhooks.value, b"")
        worker = await pool.acquire(60)
        assert isinstance(worker, Worker)
        job = asyncio.ensure_future(worker.run(jobhooks.sleep_forever, ()))
        await asyncio.sleep(0.5)  # the job is running (or about to: the stop waits for it)
        worker.interrupt()
        with pytest.raises(JobCancelled):
            await asyncio.wait_for(job, PATIENCE_S)
        pool.release(worker, clean=True)
        again, _ = await call(pool, jobhooks.value, b"")
        assert again == first and pool.replaced == 0

    with_pool(scenario)


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="reads /proc")
def test_a_job_past_its_worker_s_memory_cap_is_a_memory_error() -> None:
    """The cap (200 MB beyond the warm worker's own) refuses 400 MB in NumPy as a MemoryError,
    not a crash; the worker lives on and takes 100 MB after."""

    async def scenario(pool: WorkerPool) -> None:
        first, _ = await call(pool, jobhooks.value, b"")
        assert {worker.allowance for worker in pool.idle} == {200 * 2**20}
        with pytest.raises(WorkerOutOfMemory):
            await call(pool, jobhooks.allocate, 400)
        assert await call(pool, jobhooks.allocate, 100) == 100 * 2**20
        again, _ = await call(pool, jobhooks.value, b"")
        assert again == first and pool.replaced == 0

    with_pool(scenario, warm=jobhooks.warm_numeric, job_memory=200 * 2**20)


def test_a_job_whose_message_is_beyond_the_cap_is_a_memory_error_and_its_worker_replaced() -> None:
    """80 MB of bytes travel inside the pickle, which the worker cannot take in 30 MB: it says
    so and ends (the rest of the message is unread); a new worker takes the next job."""

    async def scenario(pool: WorkerPool) -> None:
        first, _ = await call(pool, jobhooks.value, b"")
        with pytest.raises(WorkerOutOfMemory):
            await call(pool, jobhooks.value, b"x" * (80 * 2**20))
        again, _ = await call(pool, jobhooks.value, b"")
        assert again != first and pool.replaced == 1

    with_pool(scenario, warm=jobhooks.warm_numeric, job_memory=30 * 2**20)


def test_a_worker_that_crashes_is_replaced_and_says_how_it_ended() -> None:
    async def scenario(pool: WorkerPool) -> int | None:
        with pytest.raises(WorkerDied) as died:
            await call(pool, jobhooks.crash)
        await call(pool, jobhooks.value, b"")
        return died.value.exitcode

    assert with_pool(scenario) == -signal.SIGSEGV


async def gone(worker: Worker) -> None:
    """Wait until ``worker``'s process has ended and can be reaped. A killed process shows as a
    zombie while its other threads still exit, and waitpid does not report it until they have:
    the pool's check would still find it running then."""
    for _ in range(PATIENCE_S * 20):
        if not worker.alive():
            return
        await asyncio.sleep(0.05)
    raise AssertionError(f"process {worker.pid} still runs")


def test_workers_killed_from_outside_are_replaced() -> None:
    """The busy one's job ends as WorkerDied; the idle one is skipped when next lent."""

    async def scenario(pool: WorkerPool) -> None:
        busy = await pool.acquire(60)
        idle = await pool.acquire(60)
        assert isinstance(busy, Worker) and isinstance(idle, Worker)
        pool.release(idle, clean=True)
        job = asyncio.ensure_future(busy.run(jobhooks.sleep_forever, ()))
        await asyncio.sleep(0.5)
        os.kill(busy.pid, signal.SIGKILL)
        os.kill(idle.pid, signal.SIGKILL)
        with pytest.raises(WorkerDied):
            await asyncio.wait_for(job, PATIENCE_S)
        pool.release(busy, clean=False)
        await gone(idle)
        pid, _ = await call(pool, jobhooks.value, b"")  # the dead idle worker is skipped
        assert pid not in (busy.pid, idle.pid)

    with_pool(scenario, count=2)


def test_a_spare_takes_a_killed_worker_s_place_at_once() -> None:
    """With a worker to spare, a job that does not stop costs no wait: the next job runs in the
    spare, which was started before, while a new spare starts."""

    async def scenario(pool: WorkerPool) -> tuple[int, set[int], float]:
        while len(pool.idle) < 2:  # both ready
            await asyncio.sleep(0.05)
        ready = {worker.pid for worker in pool.idle}
        worker = await pool.acquire(60)
        assert isinstance(worker, Worker)
        job = asyncio.ensure_future(worker.run(jobhooks.stuck, ()))
        await asyncio.sleep(0.2)
        job.cancel()
        pool.release(worker, clean=False)  # as when its client left and it did not stop
        loop = asyncio.get_running_loop()
        begun = loop.time()
        spare = await pool.acquire(0)  # no wait at all
        assert isinstance(spare, Worker)
        pid, _ = await spare.run(jobhooks.value, (b"",))
        seconds = loop.time() - begun
        pool.release(spare, clean=True)
        assert pool.replaced == 1
        return pid, ready - {worker.pid}, seconds

    pid, spares, seconds = with_pool(scenario, count=1, spare=1)
    assert pid in spares  # a worker ready before the kill: none had to start for this job
    print(f"next job after a killed worker: {seconds * 1000:.0f} ms")


def test_a_worker_limits_what_an_upload_expands_into_as_the_pool_says() -> None:
    async def scenario(pool: WorkerPool) -> int:
        return int(await call(pool, expansion.expansion_limit, 2**40))

    assert with_pool(scenario, expansion_most=300 * 2**20) == 300 * 2**20


def test_a_worker_runs_at_a_lower_priority_than_the_server() -> None:
    async def scenario(pool: WorkerPool) -> int:
        return int(await call(pool, os.nice, 0))

    assert with_pool(scenario) == min(os.nice(0) + workers.WORKER_NICENESS, 19)
