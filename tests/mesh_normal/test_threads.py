"""The compiled kernels may be called from several threads at once (the web server does)."""

from __future__ import annotations

import threading

import numpy as np

from mesh_normal import face_normals, vertex_normals


def test_kernels_called_from_several_threads_at_once_give_the_results_of_one() -> None:
    # Each call releases the GIL and runs its own threads: four callers at once, each getting
    # the bytes of a call made alone.
    rng = np.random.default_rng(0)
    vertices = rng.normal(size=(20_000, 3))
    faces = rng.integers(0, len(vertices), size=(40_000, 3))
    alone = (
        face_normals(vertices, faces).normals.tobytes(),
        vertex_normals(vertices, faces).normals.tobytes(),
    )
    found: list[tuple[bytes, bytes]] = []
    errors: list[BaseException] = []

    def work() -> None:
        try:
            for _ in range(5):
                found.append(
                    (
                        face_normals(vertices, faces).normals.tobytes(),
                        vertex_normals(vertices, faces).normals.tobytes(),
                    )
                )
        except BaseException as error:  # reported by the test's thread
            errors.append(error)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors, errors
    assert len(found) == 20 and all(result == alone for result in found)
