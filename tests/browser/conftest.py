"""Browser fixtures: the real app under uvicorn, Debian's Chromium, pages that watch the console.

Chromium is the system one at ``/usr/bin/chromium`` (``CHROMIUM`` overrides it); Playwright's
own browser download is never used. In CI (``CI`` set to anything but ``0``/``false``/``no``) a
missing Chromium fails the run; locally the browser tests are skipped with the reason.
Playwright itself is a test dependency (``pip install -e '.[test]'``), not optional.
"""

from __future__ import annotations

import contextlib
import html
import os
import re
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

import pytest
from playwright.sync_api import (
    Browser,
    BrowserContext,
    ConsoleMessage,
    Error,
    Page,
    sync_playwright,
)

from tests.paths import ROOT

CHROMIUM = Path(os.environ.get("CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
#: Playwright's default timeout (ms) for waits and expect(); the page answers in well under this.
TIMEOUT_MS = 10_000
SERVER_START_S = 30.0


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


def unavailable(reason: str) -> None:
    """Fail in CI, skip locally: a browser suite that silently skips in CI tests nothing."""
    if in_ci():
        pytest.fail(f"{reason} (CI is set, so this is an error, not a skip)", pytrace=False)
    pytest.skip(reason)


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture(scope="session")
def base_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The real app under uvicorn on a free local port (or BROWSER_TEST_PORT), for the session."""
    port = int(os.environ.get("BROWSER_TEST_PORT") or free_port())
    log_path = tmp_path_factory.mktemp("uvicorn") / "server.log"
    with log_path.open("wb") as log:
        process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "uvicorn",
                "app.main:app",
                "--host",
                "127.0.0.1",
                "--port",
                str(port),
                "--log-level",
                "warning",
            ],
            cwd=ROOT,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        url = f"http://127.0.0.1:{port}"
        try:
            deadline = time.monotonic() + SERVER_START_S
            while True:
                if process.poll() is not None:
                    pytest.fail(
                        f"uvicorn exited with {process.returncode}:\n"
                        f"{log_path.read_text(errors='replace')}",
                        pytrace=False,
                    )
                try:
                    with urllib.request.urlopen(
                        f"{url}/api/normal?ax=0&ay=0&az=0&bx=1&by=0&bz=0&cx=0&cy=1&cz=0", timeout=1
                    ) as answer:
                        if answer.status == 200:
                            break
                except (urllib.error.URLError, OSError):
                    pass
                if time.monotonic() > deadline:
                    pytest.fail(
                        f"uvicorn did not answer on {url} within {SERVER_START_S} s:\n"
                        f"{log_path.read_text(errors='replace')}",
                        pytrace=False,
                    )
                time.sleep(0.05)
            yield url
        finally:
            process.terminate()
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=10)


class _FramingHost(BaseHTTPRequestHandler):
    """``GET /frame?src=URL``: a page of another origin that puts URL in an iframe."""

    def do_GET(self) -> None:
        parts = urlsplit(self.path)
        sources = parse_qs(parts.query).get("src", [])
        if parts.path != "/frame" or not sources:
            self.send_error(404)
            return
        body = (
            "<!doctype html><html lang='en'><head><meta charset='utf-8'>"
            "<title>Someone else's page</title><link rel='icon' href='data:,'></head>"
            "<body><h1>A blog post with an embedded chart</h1>"
            f"<iframe id='framed' name='framed' src='{html.escape(sources[0])}' "
            "width='560' height='380' style='border:0' title='Framed page'></iframe>"
            "</body></html>"
        ).encode()
        self.send_response(200)
        self.send_header("content-type", "text/html; charset=utf-8")
        self.send_header("content-length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base signature
        pass


@pytest.fixture(scope="session")
def framing_host() -> Iterator[str]:
    """Base URL of a second local site (``localhost``, another port: another origin).

    It is a real server rather than ``page.route``: Chromium's Local Network Access checks
    block a routed (hence "public") page from framing 127.0.0.1, which is not what a real
    embedding site meets.
    """
    server = ThreadingHTTPServer(("127.0.0.1", 0), _FramingHost)
    thread = threading.Thread(target=server.serve_forever, name="framing-host", daemon=True)
    thread.start()
    try:
        yield f"http://localhost:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)


@pytest.fixture(scope="session")
def browser() -> Iterator[Browser]:
    if not (CHROMIUM.is_file() and os.access(CHROMIUM, os.X_OK)):
        unavailable(f"Chromium not found at {CHROMIUM} (install Debian's chromium package)")
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


#: Warnings that headless Chromium (software WebGL) prints whenever the 3D view draws; the view
#: can draw on any calculator page once it scrolls into sight, so every test accepts them.
WEBGL_WARNINGS = (
    r"^console\.warning: Canvas2D: Multiple readback operations",
    r"^console\.warning: .*GL Driver Message .*GPU stall due to ReadPixels",
)


@dataclass
class ConsoleWatch:
    """Console errors and warnings and uncaught page errors of every page in a test.

    Every test ends with none left, unless the test itself declared one as expected with
    :meth:`allow` (for example a frame that the browser must refuse).
    """

    messages: list[str] = field(default_factory=list)
    allowed: list[re.Pattern[str]] = field(
        default_factory=lambda: [re.compile(pattern) for pattern in WEBGL_WARNINGS]
    )

    def attach(self, page: Page) -> None:
        page.on("console", self._on_console)
        page.on("pageerror", lambda error: self.messages.append(f"pageerror: {error}"))

    def _on_console(self, message: ConsoleMessage) -> None:
        if message.type in ("error", "warning"):
            where = message.location.get("url", "")
            self.messages.append(f"console.{message.type}: {message.text} ({where})")

    def allow(self, pattern: str) -> None:
        """Accept messages matching ``pattern`` (a regular expression) in this test."""
        self.allowed.append(re.compile(pattern))

    def unexpected(self) -> list[str]:
        return [
            text
            for text in self.messages
            if not any(pattern.search(text) for pattern in self.allowed)
        ]

    def matching(self, pattern: str) -> list[str]:
        return [text for text in self.messages if re.search(pattern, text)]


@pytest.fixture
def console() -> ConsoleWatch:
    return ConsoleWatch()


NewPage = Callable[..., Page]

#: Every context starts like this unless a test asks otherwise.
CONTEXT_DEFAULTS: dict[str, Any] = {
    "color_scheme": "light",
    "locale": "en-US",
    "viewport": {"width": 1280, "height": 900},
}


@pytest.fixture(scope="session")
def shared_context(browser: Browser, base_url: str) -> Iterator[BrowserContext]:
    """One context for the plain pages, so Plotly (about 1 MB) is fetched and compiled once.

    The app keeps no cookies or storage, so pages in it do not affect each other; every test
    still gets a page of its own, and tests that need other settings get their own context.
    """
    context = browser.new_context(base_url=base_url, **CONTEXT_DEFAULTS)
    context.set_default_timeout(TIMEOUT_MS)
    yield context
    context.close()


@pytest.fixture
def new_page(
    browser: Browser, shared_context: BrowserContext, console: ConsoleWatch, base_url: str
) -> Iterator[NewPage]:
    """Open a page; with keyword arguments (for ``browser.new_context``) in a fresh context.

    When the test ends, every page must have logged no console error or warning and thrown
    no uncaught error, apart from what the test allowed with ``console.allow``.
    """
    contexts: list[BrowserContext] = []
    pages: list[Page] = []

    def open_page(**options: Any) -> Page:
        if options:
            context = browser.new_context(**{"base_url": base_url, **CONTEXT_DEFAULTS, **options})
            context.set_default_timeout(TIMEOUT_MS)
            contexts.append(context)
        else:
            context = shared_context
        page = context.new_page()
        pages.append(page)
        console.attach(page)
        return page

    yield open_page
    for page in pages:
        with contextlib.suppress(Error):
            page.close()
    for context in contexts:
        with contextlib.suppress(Error):
            context.close()
    problems = console.unexpected()
    assert not problems, "console errors or warnings on the page:\n" + "\n".join(problems)


@pytest.fixture
def page(new_page: NewPage) -> Page:
    return new_page()
