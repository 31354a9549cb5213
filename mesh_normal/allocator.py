"""The C library's allocator, tuned for one large job in one process (the command line).

A large mesh's steps each take and free arrays of hundreds of megabytes. glibc gives every block
of 32 MB or more its own mapping and unmaps it when freed, so the next step's arrays are new
pages again; on a virtual machine whose host backs guest memory on first touch (this one), a
new page costs far more than the arithmetic on it: touching 1 GiB measured 2.9-6.9 s the first
time, 0.13-0.16 s after a free and remap in the same process, 0.04 s when kept. Keeping what was
freed for the next step (:func:`keep_freed`) took the Lucy-size ``analyze`` from 24.6 to 19.5 s,
with the same peak. Nothing happens where the C library is not glibc.
"""

from __future__ import annotations

import ctypes
import functools
from typing import Any

#: glibc's ``mallopt`` parameters (malloc.h).
M_TRIM_THRESHOLD = -1
M_MMAP_MAX = -4
M_MMAP_THRESHOLD = -3

#: ``mallopt`` takes a C int: the largest free top of the heap kept rather than returned.
_KEPT = 2**31 - 1


def keep_freed() -> bool:
    """Serve every block from the heap and keep freed memory for reuse (until
    :func:`give_back`): no block gets its own mapping, and the heap's free top is not returned
    while under 2 GiB. True where it took effect (glibc)."""
    mallopt = libc("mallopt")
    if mallopt is None:
        return False
    return bool(mallopt(M_MMAP_MAX, 0)) and bool(mallopt(M_TRIM_THRESHOLD, _KEPT))


def map_from(size: int) -> bool:
    """Give every block of ``size`` bytes or more its own mapping, returned to the system when
    freed. glibc otherwise raises that threshold (up to 32 MB) after large frees, and then keeps
    what a large job once took resident for good. True where it took effect (glibc)."""
    mallopt = libc("mallopt")
    return mallopt is not None and bool(mallopt(M_MMAP_THRESHOLD, size))


def give_back() -> None:
    """Return the memory the process freed to the system (glibc's ``malloc_trim``, which also
    releases free pages inside the heap). Nothing where the C library has no such call."""
    trim = libc("malloc_trim")
    if trim is not None:
        trim(0)


@functools.cache
def libc(name: str) -> Any:
    """The C library's function ``name``, or None where there is none (not glibc)."""
    try:
        return getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError):
        return None
