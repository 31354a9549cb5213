"""The server's start: the first page without the heavy modules, which load right after."""

from __future__ import annotations

import subprocess
import sys

from tests.paths import ROOT

HEAVY = (
    "numpy",
    "mesh_normal._core",
    "trimesh",
    "app.mesh.work",
    "app.mesh.warmup",
    "app.points.work",
    "mesh_normal.mesh.orientation",
)


def run(code: str) -> str:
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_the_app_imports_none_of_the_heavy_modules() -> None:
    loaded = run(f"import sys, app.main; print([m for m in {HEAVY!r} if m in sys.modules])")
    assert loaded == "[]"


def test_the_first_page_needs_none_of_them_and_they_load_after_start() -> None:
    code = f"""
import sys, time
from fastapi.testclient import TestClient
import app.main
app.main.HEAVY_IMPORT_DELAY = 3600.0  # the page alone: the timer does not fire meanwhile
with TestClient(app.main.create_app()) as client:
    page = client.get("/")
    mesh = client.get("/mesh")
    before = [m for m in {HEAVY!r} if m in sys.modules]
app.main.HEAVY_IMPORT_DELAY = 0.0
with TestClient(app.main.create_app()) as client:
    deadline = time.monotonic() + 60
    while "app.points.work" not in sys.modules or "app.mesh.work" not in sys.modules:
        assert time.monotonic() < deadline
        time.sleep(0.02)
print(page.status_code, mesh.status_code, before, "numpy" in sys.modules)
"""
    # The calculator's and the mesh form's pages load none of them; the timer loads the jobs.
    assert run(code).splitlines()[-1] == "200 200 [] True"


def test_every_route_is_built_with_the_app_not_at_a_request(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """FastAPI builds an included router's routes lazily, at the first request, inside a
    ``warnings.catch_warnings`` that other threads can undo; ``create_app`` builds them first."""
    import fastapi.routing
    from fastapi.testclient import TestClient

    import app.main

    built = app.main.create_app()

    def refuse(*_args, **_kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("a route was built at a request")

    monkeypatch.setattr(fastapi.routing._EffectiveRouteContext, "from_api_route", refuse)
    client = TestClient(built, raise_server_exceptions=True)  # no lifespan: no workers
    assert client.get("/").status_code == 200
    assert client.get("/mesh").status_code == 200
    answer = client.post("/api/points?k=2", content=b"")
    assert answer.status_code == 422
    assert answer.json()["field"] == "k"
    assert client.get("/api/normal", params={"ax": "x"}).status_code in (405, 422)


def test_importing_the_app_leaves_the_garbage_collector_alone() -> None:
    # Process-wide settings belong to entry points: a process that imports the app (a test, a
    # script) collects its garbage as before and has nothing frozen.
    code = """
import gc
assert gc.isenabled()
import app.main
print(gc.isenabled(), gc.get_freeze_count())
"""
    assert run(code) == "True 0"


def test_a_worker_s_preload_loads_the_jobs_and_freezes_them() -> None:
    # What a worker runs as it starts: the heavy modules imported, the collector paused
    # meanwhile and running again after, with their objects frozen out of its passes.
    code = """
import gc, sys
import app.preload
from app.main import HEAVY_MODULES
print(gc.isenabled(), gc.get_freeze_count() > 100_000,
      all(name in sys.modules for name in app.preload.MODULES), "mesh_normal._core" in sys.modules,
      set(HEAVY_MODULES) <= set(app.preload.MODULES))
"""
    assert run(code) == "True True True True True"


def test_a_preload_module_that_fails_leaves_the_others_loading() -> None:
    # A preload module that cannot be imported is left: the rest still load, the collector
    # runs again.
    code = """
import gc, importlib, sys
real = importlib.import_module
def load(name, package=None):
    if name == "app.mesh.work":
        raise ImportError("a broken install")
    return real(name, package)
importlib.import_module = load
import app.preload
print(gc.isenabled(), "app.points.work" in sys.modules, "trimesh.exchange.gltf" in sys.modules)
"""
    assert run(code) == "True True True"  # the modules after the broken one still loaded


def test_a_worker_s_warm_up_comes_without_the_app() -> None:
    """A worker is handed the warm-up by reference: unpickling it must not build the app."""
    code = (
        "import pickle, sys\n"
        "from app import warm\n"
        "pickle.loads(pickle.dumps(warm.warm_workers))\n"
        "print([m for m in ('app.main', 'fastapi') if m in sys.modules])"
    )
    assert run(code) == "[]"
