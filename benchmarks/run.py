"""Side-by-side speed measurements of the calculator.

    .venv/bin/python -m benchmarks.run [--seconds 10] [--rounds 3] [--markdown PATH]

1. Requests per second of POST /api/normal against bare FastAPI echo endpoints, each app on
   its own single uvicorn worker, measured alternately in one run with wrk (Debian's package):
   the ratio to the bare echo (best and median of the rounds), and an echo route inside our
   own app (``benchmarks.echo_in_app``), which shows what our middleware and routing cost.
   ``--api-only`` leaves out the page load.
2. First load of the calculator page in headless Chromium: bytes transferred (compressed) and
   the time from navigation start to the chart being drawn, median of fresh loads.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from benchmarks import tables

BODY = (
    '{"a": [1.5, -2.25, 0.1], "b": [4.0, 0.5, -3.0], "c": [0.3, 7.0, 2.5], "swap_winding": false}'
)
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextmanager
def server(target: str) -> Iterator[str]:
    """One uvicorn worker serving ``target`` on a free loopback port."""
    port = free_port()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "uvicorn",
            target,
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--workers",
            "1",
            "--no-access-log",
            "--log-level",
            "warning",
        ],
    )
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(200):
            try:
                urllib.request.urlopen(base + "/openapi.json", timeout=1).read()
                break
            except OSError:
                time.sleep(0.05)
        yield base
    finally:
        process.terminate()
        process.wait(timeout=10)


def wrk(url: str, seconds: int, script: Path) -> float:
    output = subprocess.run(
        ["wrk", "-t1", "-c16", f"-d{seconds}s", "-s", str(script), url],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    match = re.search(r"Requests/sec:\s+([\d.]+)", output)
    if not match or "Non-2xx" in output:
        raise RuntimeError(f"wrk failed against {url}:\n{output}")
    return float(match.group(1))


def bench_api(seconds: int, rounds: int) -> dict[str, list[float]]:
    if shutil.which("wrk") is None:
        sys.exit("wrk is missing: apt-get install -y wrk")
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "post.lua"
        script.write_text(
            'wrk.method = "POST"\n'
            f"wrk.body = '{BODY}'\n"
            'wrk.headers["Content-Type"] = "application/json"\n'
        )
        targets = {
            "POST /api/normal": ("app.main:app", "/api/normal"),
            "echo (body: dict)": ("benchmarks.echo_app:app", "/echo"),
            "echo (raw JSON)": ("benchmarks.echo_app:app", "/echo-raw"),
            "echo inside our app": ("benchmarks.echo_in_app:app", "/api/echo"),
        }
        samples: dict[str, list[float]] = {name: [] for name in targets}
        with (
            server("app.main:app") as ours,
            server("benchmarks.echo_app:app") as echo,
            server("benchmarks.echo_in_app:app") as inside,
        ):
            bases = {
                "app.main:app": ours,
                "benchmarks.echo_app:app": echo,
                "benchmarks.echo_in_app:app": inside,
            }
            for app_name, path in targets.values():  # warm-up
                wrk(bases[app_name] + path, 2, script)
            for _ in range(rounds):
                for name, (app_name, path) in targets.items():
                    samples[name].append(wrk(bases[app_name] + path, seconds, script))
    return samples


def bench_page(loads: int) -> tuple[float, float]:
    from playwright.sync_api import sync_playwright

    with server("app.main:app") as base, sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS
        )
        urllib.request.urlopen(base + "/").read()  # let the server compress its assets once
        times, sizes = [], []
        for _ in range(loads):
            context = browser.new_context()
            page = context.new_page()
            page.goto(base + "/")
            page.wait_for_function("window.__chartDrawnAt", timeout=20_000)
            times.append(page.evaluate("window.__chartDrawnAt"))
            sizes.append(
                page.evaluate(
                    "performance.getEntriesByType('navigation')[0].transferSize + "
                    "performance.getEntriesByType('resource')"
                    ".reduce((sum, r) => sum + r.transferSize, 0)"
                )
            )
            context.close()
        browser.close()
    return statistics.median(times), max(sizes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=int, default=10)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--loads", type=int, default=3)
    parser.add_argument("--api-only", action="store_true", help="leave out the page load")
    tables.add_option(parser)
    args = parser.parse_args()
    report = tables.Report(args.markdown)

    before = os.getloadavg()[0]
    samples = bench_api(args.seconds, args.rounds)
    after = os.getloadavg()[0]
    ours = samples["POST /api/normal"]
    report.print(
        f"| endpoint (1 uvicorn worker, wrk -c16, {args.rounds} rounds of {args.seconds} s, "
        "alternating) | requests/s, median | best | ours as share, median | best round |"
    )
    report.print("|---|---:|---:|---:|---:|")
    for name, values in samples.items():
        share = statistics.median(o / v for o, v in zip(ours, values, strict=True))
        best = max(o / v for o, v in zip(ours, values, strict=True))
        report.print(
            f"| {name} | {statistics.median(values):,.0f} | {max(values):,.0f} "
            f"| {share:.2f} | {best:.2f} |"
        )
    print(f"\nload average (1 min) {before:.2f} before, {after:.2f} after (2 cores)")
    if args.api_only:
        report.write()
        return

    drawn, size = bench_page(args.loads)
    report.print(
        f"\n| first load of / (headless Chromium, median of {args.loads} fresh loads) "
        "| value | target |"
    )
    report.print("|---|---:|---:|")
    report.print(f"| transferred, compressed | {size / 1024:,.0f} KB | 500 KB |")
    report.print(f"| chart drawn after navigation start | {drawn:,.0f} ms | 1000 ms |")
    report.write()


if __name__ == "__main__":
    main()
