"""Python's cyclic garbage collector, paused while a process loads a lot at once.

Importing a large package or loading compiled kernels creates hundreds of thousands of
objects, nearly all of them kept for the life of the process, and each pass of the collector
over its oldest generation walks them all, again and again as they grow. Pausing the
collector takes about a third off ``import numba``, a sixth off loading every kernel from
numba's cache (``compile_kernels``) and half off the server's worker processes' preload (the
jobs, trimesh's glTF loader, numba's cache). Nothing that these steps make is garbage to
collect meanwhile.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def paused() -> Iterator[None]:
    """The collector off inside the block, and back on after it if it was on before (a caller
    that turned it off keeps it off; nested blocks are fine)."""
    was_on = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_on:
            gc.enable()
