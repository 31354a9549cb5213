"""Worker processes (``mesh_normal.workers``): a start, a replacement, a server's stop.

Three tables. A worker's start with the server's settings (``app.preload`` imported, the
warm-up run) until it says it is ready, and its resident memory then. The next job after a
worker was killed with its job (as when a job stuck in native code ignores its client's
leaving): the time from the kill to a small job's answer, in a pool with a warm spare (the
server's) and without one. A real ``uvicorn app.main:app`` with two workers stopped by SIGTERM
or SIGINT at three moments: the seconds from the signal until no process it started is left.

    .venv/bin/python -m benchmarks.workers [--rounds N] [--markdown PATH]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

import httpx

from benchmarks import tables
from benchmarks.stalls import free_port

ROOT = Path(__file__).resolve().parent.parent


def server_settings() -> object:
    from app.main import PRELOAD
    from app.warm import warm_workers
    from app.web.workers import REFUSALS, WORKER_NICENESS
    from mesh_normal.workers import Settings

    return Settings(
        imports=PRELOAD,
        warm=warm_workers,
        niceness=WORKER_NICENESS,
        tune_memory=True,
        refusals=REFUSALS,
    )


def resident_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return 0.0


def starts(rounds: int) -> tuple[list[float], list[float]]:
    """Seconds from a worker's start to its word that it is ready; its resident MB then."""
    from mesh_normal.workers import Worker

    settings = server_settings()
    seconds, memory = [], []
    for _ in range(rounds):
        begun = time.perf_counter()
        worker = Worker(settings)  # type: ignore[arg-type]
        worker.wait_ready()
        seconds.append(time.perf_counter() - begun)
        memory.append(resident_mb(worker.pid))
        worker.kill()
    return seconds, memory


def replacement(rounds: int, spare: int) -> list[float]:
    """Seconds from a worker killed with its job to the next small job's answer."""
    from app.main import PRELOAD
    from app.warm import warm_workers
    from app.web.workers import WorkerPool
    from tests.app import jobhooks

    async def main() -> list[float]:
        pool = WorkerPool(1, spare=spare, preload=PRELOAD, warm=warm_workers)
        pool.start()
        found = []
        try:
            for _ in range(rounds):
                while len(pool.idle) < pool.count:  # every worker ready, the spare too
                    await asyncio.sleep(0.05)
                worker = await pool.acquire(60)
                assert worker is not None
                job = asyncio.ensure_future(worker.run(jobhooks.stuck, ()))
                await asyncio.sleep(0.2)
                begun = time.perf_counter()
                job.cancel()
                pool.release(worker, clean=False)
                next_one = await pool.acquire(120)
                assert next_one is not None
                await next_one.run(jobhooks.value, (b"",))
                found.append(time.perf_counter() - begun)
                pool.release(next_one, clean=True)
        finally:
            pool.close()
        return found

    return asyncio.run(main())


def tagged(tag: str) -> list[int]:
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{entry}/environ", "rb") as environ:
                if f"MESH_BENCH_TAG={tag}".encode() in environ.read().split(b"\0"):
                    with open(f"/proc/{entry}/stat") as stat:
                        if stat.read().rsplit(") ", 1)[1][0] != "Z":
                            found.append(int(entry))
        except OSError:
            continue
    return found


def workers_of(tag: str) -> list[int]:
    found = []
    for pid in tagged(tag):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as cmdline:
                if b"mesh_normal.workers" in cmdline.read():
                    found.append(pid)
        except OSError:
            continue
    return found


def wait_for(condition: object, seconds: float = 120) -> None:
    deadline = time.monotonic() + seconds
    while not condition():  # type: ignore[operator]
        if time.monotonic() > deadline:
            raise TimeoutError("what the benchmark waited for never happened")
        time.sleep(0.01)


def proportional_mb(pid: int) -> float:
    """The process's proportional set size (its pages, shared ones split among sharers), MB."""
    with open(f"/proc/{pid}/smaps_rollup") as rollup:
        for line in rollup:
            if line.startswith("Pss:"):
                return int(line.split()[1]) / 1024
    return 0.0


#: The idle server's memory, measured once its workers are ready: (server, [each worker]) MB.
idle_memory: list[tuple[float, list[float]]] = []


def stop(number: signal.Signals, moment: str) -> float:
    """Seconds from ``number`` to no process of the server left, sent at ``moment``."""
    port = free_port()
    tag = f"{os.getpid()}-{time.monotonic_ns()}"
    command = [sys.executable, "-m", "uvicorn", "app.main:app", "--port", str(port)]
    env = {**os.environ, "MESH_WORKERS": "2", "MESH_BENCH_TAG": tag}
    process = subprocess.Popen(
        [*command, "--host", "127.0.0.1"],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
    )
    url = f"http://127.0.0.1:{port}"

    def answers() -> bool:
        try:
            return httpx.get(url + "/").status_code == 200
        except httpx.TransportError:
            return False

    try:
        if moment == "first worker starting":
            wait_for(lambda: bool(workers_of(tag)))
        else:
            wait_for(answers)
        if moment == "workers ready":
            from tests.meshes import CUBE_OBJ

            cube = {"filename": "cube.obj"}
            httpx.post(url + "/api/mesh", params=cube, content=CUBE_OBJ, timeout=120)
            wait_for(lambda: len(workers_of(tag)) == 3)
            time.sleep(15)  # the last ones warm up, even on a busy machine
            idle_memory.append(
                (proportional_mb(process.pid), [proportional_mb(pid) for pid in workers_of(tag)])
            )
        process.send_signal(number)
        begun = time.perf_counter()
        wait_for(lambda: not tagged(tag), 60)
        return time.perf_counter() - begun
    finally:
        for pid in tagged(tag):
            os.kill(pid, signal.SIGKILL)
        process.kill()
        process.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    tables.add_option(parser)
    args = parser.parse_args()
    report = tables.Report(args.markdown)

    seconds, memory = starts(args.rounds)
    report.print(f"| a worker ({args.rounds} starts) | best | median |")
    report.print("|---|---:|---:|")
    report.print(f"| start to ready, s | {min(seconds):.2f} | {statistics.median(seconds):.2f} |")
    report.print(
        f"| resident once ready, MB | {min(memory):.0f} | {statistics.median(memory):.0f} |"
    )
    report.print()
    report.print(
        f"| the next small job after a killed worker ({args.rounds} rounds), ms | best | median |"
    )
    report.print("|---|---:|---:|")
    for label, spare in (("a warm spare (the server's pool)", 1), ("no spare: a new worker", 0)):
        found = replacement(args.rounds, spare)
        report.print(
            f"| {label} | {min(found) * 1000:.0f} | {statistics.median(found) * 1000:.0f} |"
        )
    report.print()
    report.print("| the server stopped (2 workers and a spare) | SIGTERM, s | SIGINT, s |")
    report.print("|---|---:|---:|")
    for moment in ("first worker starting", "first page", "workers ready"):
        term = stop(signal.SIGTERM, moment)
        interrupt = stop(signal.SIGINT, moment)
        report.print(f"| {moment} | {term:.2f} | {interrupt:.2f} |")
    server, each = idle_memory[0]
    report.print()
    report.print(
        f"Idle, its workers ready: the server {server:.0f} MB and each worker "
        f"{statistics.median(each):.0f} MB of proportional memory (PSS), {server + sum(each):.0f}"
        " MB in all."
    )
    report.write()


if __name__ == "__main__":
    main()
