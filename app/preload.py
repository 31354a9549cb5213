"""What each worker process imports as it starts, before its warm-up (:mod:`app.web.workers`).

It imports :data:`MODULES` with Python's garbage collector paused (their hundreds of thousands
of objects, walked again and again by the collector's passes as they grow, would make the same
imports take about twice as long), then freezes what they made out of the collector's later
passes (``gc.freeze``: they live as long as the worker, and no job's collection walks them
again) and lets it run again.
"""

from __future__ import annotations

import gc
import importlib

#: The jobs (and with them the compiled core, ``mesh_normal._core``), the warm-up each worker
#: runs, and trimesh's glTF loader, which takes seconds to import: loaded as the worker
#: starts, so that no job waits for them.
MODULES = (
    "app.mesh.work",
    "app.points.work",
    "app.mesh.warmup",
    "trimesh.exchange.gltf",
)


def load() -> None:
    """Import :data:`MODULES`, the collector paused, and freeze what they made. A module that
    cannot be imported is left (the worker imports it, or says why, when a job needs it); the
    others still load."""
    gc.disable()  # this process is a worker starting: nothing else runs in it meanwhile
    try:
        for name in MODULES:
            try:
                importlib.import_module(name)
            except ImportError:
                continue
        gc.freeze()
    finally:
        gc.enable()


load()
