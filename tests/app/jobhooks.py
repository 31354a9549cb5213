"""Jobs for the tests of the worker processes: top-level functions, so that a worker imports
them by name (a test puts one in place of ``app.mesh.work.report``, which the routes look up
when called). They find their folder of marker files from the upload's name."""

from __future__ import annotations

import os
import signal
import threading
import time
from pathlib import Path
from typing import Any

from app.mesh import work
from app.mesh.uploads import Upload
from app.web.errors import ApiError
from mesh_normal.mesh.report.models import MeshReport

#: The real report, taken before a test puts a hook in its place.
REPORT = work.report


def folder(upload: Upload) -> Path:
    return Path(upload.filename or ".").parent


def abort(*_args: Any) -> MeshReport:
    """Die as pydantic-core does when an allocation fails (SIGABRT, exit code 134)."""
    os.abort()


def exhaust(*_args: Any) -> MeshReport:
    raise MemoryError


def held(upload: Upload, weld: float | None) -> MeshReport:
    """Say ``started`` (with this process's id), then hold the GIL in pure Python until the
    file ``release`` appears; then write ``finished`` and report as usual. With a file
    ``stubborn`` in the folder, ignore the signals that ask a job to stop, as a job in a native
    loop does."""
    here = folder(upload)
    if (here / "stubborn").exists():
        signal.signal(signal.SIGALRM, signal.SIG_IGN)
        signal.signal(signal.SIGUSR1, signal.SIG_IGN)
    # Written whole, then named: a test that sees ``started`` reads the id, never an empty file.
    (here / "started.part").write_text(str(os.getpid()))
    (here / "started.part").rename(here / "started")
    spins = 0
    while not (here / "release").exists():
        spins += sum(range(10_000))  # GIL-holding work, as a regex pass over a big file is
    (here / "finished").write_text(str(spins))
    return REPORT(upload, weld)


def value(data: bytes, *, times: int = 1) -> tuple[int, bytes]:
    return os.getpid(), data * times


def sleep_forever(*_args: Any) -> None:
    while True:
        time.sleep(1)


def stuck(*_args: Any) -> None:
    """Never stop, not even when asked to: as a job in a native loop, which sees no signal."""
    signal.signal(signal.SIGALRM, signal.SIG_IGN)
    signal.signal(signal.SIGUSR1, signal.SIG_IGN)
    while True:
        time.sleep(1)


def killed(*_args: Any) -> MeshReport:
    """Be killed from outside, as the system's out-of-memory killer does (SIGKILL)."""
    os.kill(os.getpid(), signal.SIGKILL)
    raise AssertionError("not reached")


def crash(*_args: Any) -> None:
    """Die as native code does on an allocation it did not check (SIGSEGV)."""
    os.kill(os.getpid(), signal.SIGSEGV)


def warm_numeric() -> None:
    """A worker's warm-up for :func:`allocate`: NumPy loaded and its first array made, so that
    what a job may take is all the job's."""
    allocate(1)


def allocate(megabytes: int) -> int:
    """Write ``megabytes`` of a NumPy array."""
    import numpy as np

    return int(np.ones(megabytes * 2**20, dtype=np.uint8).sum())


def refuse(*_args: Any) -> None:
    raise ApiError(400, "No.", "file")


def resident(upload: Upload | None, fault_ahead_from: int | None = None) -> int:
    """The worker's resident memory in MB after reading ``upload`` as its jobs do (if one is
    given; with ``work.FAULT_AHEAD_FROM`` set to ``fault_ahead_from`` if that is given), once
    the prefaulting (if any) has ended."""
    if upload is not None:
        usual = work.FAULT_AHEAD_FROM
        if fault_ahead_from is not None:
            work.FAULT_AHEAD_FROM = fault_ahead_from
        try:
            work.load(upload)
        finally:
            work.FAULT_AHEAD_FROM = usual
    for thread in threading.enumerate():
        if thread.name == "prefault":
            thread.join()
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") >> 20
