"""The server's start: the first page without the heavy modules, which load right after."""

from __future__ import annotations

import subprocess
import sys

from tests.paths import ROOT

HEAVY = (
    "numpy",
    "numba",
    "trimesh",
    "app.mesh.work",
    "app.mesh.warmup",
    "app.points.work",
    "mesh_normal.orientation",
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
