"""Python's cyclic garbage collector, paused while a process loads a lot at once.

Importing a large package or loading compiled kernels creates hundreds of thousands of
objects, nearly all of them kept for the life of the process, and each pass of the collector
over its oldest generation walks them all, again and again as they grow. Measured on this
project's machine (median of 10): ``import numba`` 385 against 257 ms with the collector
paused; loading every kernel from numba's cache (``compile_kernels``) 1.17 against 0.99 s;
the server's worker processes' preload (the jobs, trimesh's glTF loader, numba's cache) 1.73
against 0.90 s. Nothing that these steps make is garbage to collect meanwhile.
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
