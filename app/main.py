"""The ASGI app: ``uvicorn app.main:app``."""

from __future__ import annotations

import asyncio
import importlib
import signal
import threading
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from types import FrameType
from typing import Any

from fastapi import FastAPI

import mesh_normal
from app import config, warm
from app.calculator import api as calculator_api
from app.calculator import pages
from app.mesh import api as mesh_api
from app.mesh import page as mesh_page
from app.points import api as points_api
from app.points import page as points_page
from app.web import handlers, health
from app.web.jobs import Jobs
from app.web.jsonio import FastJSONResponse
from app.web.middleware import BodyLimit, HeadAsGet, PageCompression, SecurityHeaders
from app.web.static import STATIC_DIR, CompressedStaticFiles
from app.web.workers import tune_allocator

#: The modules of the heavy work: the jobs with their readers, the compiled core and NumPy.
#: The server answers its first page without them, and imports them in a thread once it is up
#: (:func:`lifespan`), so that neither the first page nor the first upload waits for them.
HEAVY_MODULES = ("app.mesh.work", "app.points.work")
#: What each worker imports as it starts: :mod:`app.preload` (the jobs, the warm-up and
#: trimesh's glTF loader, the garbage collector paused meanwhile).
PRELOAD = ("app.preload",)
#: Seconds after start-up before :data:`HEAVY_MODULES` load: the first page, which a
#: supervisor's health check or a reader often asks for at once, does not share the CPU with
#: them.
HEAVY_IMPORT_DELAY = 0.25

DESCRIPTION = """
Surface normals of triangles, exact to the last bit.

For points A, B, C: u = B - A, v = C - A, the normal n = u x v, |n| is twice the area and
n / |n| the unit normal. Every value is the exact result rounded once to the nearest double;
a value outside the double range is `null` with a `message`. Errors are
`{"error": "<one sentence>", "field": "<input name or null>"}`.

Whole meshes (STL, OBJ, PLY, OFF, GLB/glTF) are sent as the multipart field `file` (or as the
raw body, named with `?filename=`): `/api/mesh` reports on them, `/api/mesh/normals` returns
face, vertex or corner normals in the file's order, and `/api/mesh/fix` returns the file with
consistent, outward winding. Point clouds (PLY, XYZ/PTS/TXT/CSV, PCD, LAS/LAZ, or any mesh
file's vertices) go the same way to `/api/points` (a report: spacing, neighbourhoods, the
orientation of each part, agreement with stored normals) and `/api/points/normals` (estimated,
oriented normals in the file's order). The server keeps no file after its response.
"""


@asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    """Start the worker processes for the heavy mesh work, in the background (each loads
    everything a job can need as it starts: :func:`app.mesh.warmup.warm`), and import the jobs'
    modules here, in the background, so that the first mesh upload does not wait for them
    (with ``MESH_IN_PROCESS`` the jobs run in the server). A signal to stop ends the running
    jobs at once (:func:`end_jobs_on_stop`)."""
    jobs: Jobs = app.state.jobs
    heavy = threading.Timer(HEAVY_IMPORT_DELAY, load_heavy_modules)
    heavy.daemon = True
    heavy.start()
    jobs.start()
    restore = end_jobs_on_stop(jobs)
    try:
        yield
    finally:
        restore()
        jobs.close()


#: The signals that stop the server (uvicorn's own: SIGTERM from ``kill`` or ``docker stop``,
#: SIGINT from Ctrl+C).
STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT)


def end_jobs_on_stop(jobs: Jobs) -> Callable[[], None]:
    """On a signal to stop, end the running jobs (:meth:`Jobs.shut_down`: their requests
    answer 503 at once), then let the server's own handler go on: uvicorn stops taking
    connections and waits for the requests in flight, which no longer wait for their jobs,
    however it was started (``--timeout-graceful-shutdown`` or not). Returns what puts the
    server's handlers back. Only where the server handles signals itself, in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    loop = asyncio.get_running_loop()
    previous: dict[int, Callable[[int, FrameType | None], Any]] = {}

    def stop(number: int, frame: FrameType | None) -> None:
        loop.call_soon_threadsafe(jobs.shut_down)
        previous[number](number, frame)

    for number in STOP_SIGNALS:
        handler = signal.getsignal(number)
        if callable(handler):
            previous[number] = handler
            signal.signal(number, stop)

    def restore() -> None:
        for number, handler in previous.items():
            if signal.getsignal(number) is stop:
                signal.signal(number, handler)

    return restore


def load_heavy_modules() -> None:
    """Import :data:`HEAVY_MODULES`."""
    for name in HEAVY_MODULES:
        importlib.import_module(name)


def create_app(upload_limit: int | None = None, settings: config.Settings | None = None) -> FastAPI:
    """The app; ``upload_limit`` (bytes) overrides ``$MESH_UPLOAD_LIMIT_MB`` for mesh files,
    ``settings`` the environment's settings."""
    if settings is None:
        given = {} if upload_limit is None else {"upload_limit_mb": upload_limit / 2**20}
        settings = config.load_settings(**given)
    tune_allocator()  # large uploads and results go back to the system once freed
    app = FastAPI(
        title="Mesh Normal Calculator",
        version=mesh_normal.__version__,
        description=DESCRIPTION,
        docs_url=None,
        redoc_url=None,
        lifespan=lifespan,
        default_response_class=FastJSONResponse,
    )
    handlers.install(app)
    calculator_api.add_post_normal(app)
    app.include_router(calculator_api.router)
    app.include_router(mesh_api.router)
    app.include_router(points_api.router)
    app.include_router(pages.router)
    app.include_router(mesh_page.router)
    app.include_router(points_page.router)
    app.include_router(health.router)
    app.mount("/static", CompressedStaticFiles(directory=STATIC_DIR), name="static")
    app.add_middleware(PageCompression)
    app.state.upload_limit = settings.upload_limit if upload_limit is None else upload_limit
    app.state.docs_url = settings.docs_url  # the pages' links to the guide (app.web.links)
    # The heavy mesh work: worker processes, started by the lifespan (or at the first job).
    app.state.jobs = Jobs(settings, warm=warm.warm_workers, preload=PRELOAD)
    app.add_middleware(BodyLimit, upload_limit=app.state.upload_limit)
    app.add_middleware(SecurityHeaders)
    app.add_middleware(HeadAsGet)
    build_routes(app.router.routes)
    return app


def build_routes(routes: list[Any]) -> None:
    """Build every included router's routes now, as the app is made, instead of at the first
    request that reaches them (FastAPI builds them lazily).

    Building one creates its parameters' pydantic adapters inside ``warnings.catch_warnings``,
    which swaps the process's warning filters: at a request, with other threads in their own
    ``catch_warnings`` (the background imports, the workers' launchers), one thread's exit can
    put back filters that drop FastAPI's ignore of pydantic's ``UnsupportedFieldAttributeWarning``
    while it is still building (with warnings as errors, the request fails). Built here, before
    the lifespan starts any thread, they are safe, and the first request does not pay for them.
    """
    for route in routes:
        candidates = getattr(route, "effective_candidates", None)
        if callable(candidates):
            build_routes(candidates())
            route.effective_low_priority_routes()


app = create_app()
