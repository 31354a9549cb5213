"""What the fork server of the worker processes imports once, before it forks each worker.

``multiprocessing`` imports this module by name in the fork server. It imports
:data:`MODULES` with Python's garbage collector paused (their hundreds of thousands of objects,
walked again and again by the collector's passes as they grow, would make the same imports
take about twice as long), then freezes what they made out of the
collector's later passes (``gc.freeze``: what Python's documentation advises before a fork, so
that no collection in a worker writes to the pages those objects share with the fork server)
and lets it run again.
"""

from __future__ import annotations

import gc
import importlib

#: The jobs (and with them the compiled core, ``mesh_normal._core``), the warm-up each worker
#: runs, and trimesh's glTF loader, which takes seconds to import. A worker, the first or a
#: replacement, starts without importing them itself, and the pages they touch are shared until
#: written.
MODULES = (
    "app.mesh.work",
    "app.points.work",
    "app.mesh.warmup",
    "trimesh.exchange.gltf",
)


def load() -> None:
    """Import :data:`MODULES`, the collector paused, and freeze what they made. A module that
    cannot be imported is left, as the fork server leaves each module it is given (the worker
    imports it, or says why, when a job needs it); the others still load."""
    gc.disable()  # this process is the fork server: nothing else runs in it meanwhile
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
