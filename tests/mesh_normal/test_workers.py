"""mesh_normal/workers.py: a worker process, on its own (no pool, no event loop)."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import time

import pytest

from mesh_normal.workers import (
    JobCancelled,
    JobTimedOut,
    Settings,
    Worker,
    WorkerCrashed,
    WorkerDied,
    WorkerNotStarted,
)
from tests.paths import ROOT

#: How soon a worker must be gone once its parent is.
GONE_WITHIN_S = 5


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, ended but not yet reaped, does not)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(") ", 1)[1][0] != "Z"
    except FileNotFoundError:
        return False


def gone_within(pid: int, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while alive(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def sleep_forever() -> None:
    while True:
        time.sleep(1)


def divide(a: int, b: int) -> float:
    return a / b


def refuse() -> None:
    raise LookupError("not here")


def test_a_job_runs_in_the_worker_and_ends_as_it_ended() -> None:
    worker = Worker(Settings(refusals=(LookupError,)))
    try:
        worker.wait_ready()
        assert worker.call(os.getpid, ()) == worker.pid != os.getpid()
        assert worker.call(divide, (1, 4)) == 0.25
        with pytest.raises(WorkerCrashed, match="ZeroDivisionError"):
            worker.call(divide, (1, 0))
        with pytest.raises(LookupError, match="not here"):  # a refusal, raised again here
            worker.call(refuse, ())
        assert worker.call(divide, (3, 4)) == 0.75 and worker.alive()
    finally:
        worker.kill()
    assert not worker.alive()


def test_a_job_past_its_time_stops_in_the_worker_which_lives_on() -> None:
    worker = Worker(Settings(job_seconds=0.3))
    try:
        worker.wait_ready()
        with pytest.raises(JobTimedOut):
            worker.call(sleep_forever, ())
        assert worker.call(os.getpid, ()) == worker.pid
    finally:
        worker.kill()


def test_a_job_asked_to_stop_stops_and_a_caller_s_own_time_limit_kills() -> None:
    import threading

    worker = Worker(Settings())
    try:
        worker.wait_ready()
        threading.Timer(0.3, worker.interrupt).start()
        with pytest.raises(JobCancelled):
            worker.call(sleep_forever, ())
        with pytest.raises(JobTimedOut):  # the caller's limit: the worker is killed
            worker.call(sleep_forever, (), 0.3)
        assert not worker.alive()
        with pytest.raises(WorkerDied):
            worker.call(os.getpid, ())
    finally:
        worker.kill()


def test_a_start_called_off_kills_the_worker() -> None:
    import threading

    called_off = threading.Event()
    called_off.set()
    worker = Worker(Settings(imports=("numpy",)))
    with pytest.raises(WorkerNotStarted):
        worker.wait_ready(called_off=called_off)
    assert not worker.alive()


def test_a_worker_works_in_a_daemonic_process() -> None:
    """Where multiprocessing refuses children (a Dask worker is daemonic)."""
    context = multiprocessing.get_context("spawn")
    answers = context.Queue()
    daemon = context.Process(target=_in_a_daemon, args=(answers,), daemon=True)
    daemon.start()
    try:
        assert answers.get(timeout=120) == 0.5
    finally:
        daemon.join(30)


def _in_a_daemon(answers: multiprocessing.Queue) -> None:  # type: ignore[type-arg]
    worker = Worker(Settings())
    worker.wait_ready()
    answers.put(worker.call(divide, (1, 2)))
    worker.kill()


PARENT = """
import sys, time
from mesh_normal.workers import Settings, Worker
from tests.mesh_normal.test_workers import sleep_forever
worker = Worker(Settings(imports=("numpy",)))
if sys.argv[1] == "ready":
    worker.wait_ready()
print(worker.pid, flush=True)
if sys.argv[1] == "ready":
    worker.call(sleep_forever, ())  # busy with a job when the parent is killed
time.sleep(600)
"""


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="reads /proc")
@pytest.mark.parametrize("when", ["starting", "ready"])
def test_a_worker_whose_parent_is_killed_ends(when: str) -> None:
    """SIGKILL to the parent while its worker starts (imports) or runs a job: the worker ends
    within 5 s (it watches a pipe only its parent held)."""
    command = [sys.executable, "-c", PARENT, when]
    with subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, text=True) as parent:
        try:
            assert parent.stdout is not None
            worker = int(parent.stdout.readline())
            if when == "ready":
                time.sleep(0.3)  # the job has started
            assert alive(worker)
            parent.send_signal(signal.SIGKILL)
            parent.wait(30)
            assert gone_within(worker, GONE_WITHIN_S)
        finally:
            parent.kill()
