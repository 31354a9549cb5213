"""The compiled kernels may be called from several threads at once (the web server does)."""

from __future__ import annotations

import os
import subprocess
import sys

from tests.paths import ROOT

SCRIPT = """
import threading
import numpy as np
from mesh_normal import face_normals, vertex_normals

rng = np.random.default_rng(0)
vertices = rng.normal(size=(20_000, 3))
faces = rng.integers(0, len(vertices), size=(40_000, 3))

def work():
    for _ in range(5):
        face_normals(vertices, faces)
        vertex_normals(vertices, faces)

threads = [threading.Thread(target=work) for _ in range(4)]
for thread in threads:
    thread.start()
for thread in threads:
    thread.join()
print("done")
"""


def test_parallel_kernels_from_several_threads_under_the_workqueue_layer() -> None:
    # numba's own thread pool (used where neither OpenMP nor TBB is installed, as in a slim
    # container) aborts the process on concurrent launches unless the kernels are serialised.
    root = ROOT
    environment = {**os.environ, "NUMBA_THREADING_LAYER": "workqueue"}
    result = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        cwd=root,
        env=environment,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == "done"
