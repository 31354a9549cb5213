"""The C library's allocator, tuned for one large job: the command line's process, or one job
of a server's worker (:func:`start_job` to :func:`end_job`), that reads a large binary STL.

A large mesh's steps each take and free arrays of hundreds of megabytes. glibc gives every block
of 32 MB or more its own mapping and unmaps it when freed, so the next step's arrays are new
pages again, each faulted in as it is first written. :func:`start_job` keeps what was freed for
the next step (:func:`keep_freed`) and faults the arrays' memory in ahead, on another thread,
while the file is read (:func:`prefault`). For a 700 MB binary STL (14M faces), without the
two ``mesh-normal analyze`` takes 11% (best run) to 21% (median) longer and a server's job
31% longer, for 7% and 6% less peak memory (2.52 against 2.70 GB); keeping freed memory
without faulting ahead gains under 10% there. For a mesh of 871,414 faces they gain no time
and raise the peak (a 45 MB OBJ's from 257 to 326 MB), hence only from a large binary STL on.
Nothing happens where the C library is not glibc.
"""

from __future__ import annotations

import ctypes
import functools
import threading
from typing import Any

#: glibc's ``mallopt`` parameters (malloc.h).
M_TRIM_THRESHOLD = -1
M_MMAP_MAX = -4
M_MMAP_THRESHOLD = -3

#: ``mallopt`` takes a C int: the largest free top of the heap kept rather than returned.
_KEPT = 2**31 - 1


#: Linux's ``madvise`` advice (5.14 on): fault a range in as if written, leaving its bytes.
MADV_POPULATE_WRITE = 23
#: The largest block :func:`prefault` reserves at once: below the kept free top (``_KEPT``), so
#: not returned; and the most it reserves in all.
PREFAULT_LIMIT = 7 * 2**28
PREFAULT_MOST = 2**32
_SPACER = 64
_PAGE = 4096

#: The memory a binary STL's arrays take per byte of its file, as :func:`prefault` is asked for
#: it (a 700 MB file of 14M faces: 2.1 GB besides the file).
ARRAYS_PER_STL_BYTE = 3

_keeping = False


def keep_freed() -> bool:
    """Serve every block from the heap and keep freed memory for reuse (until
    :func:`give_back`): no block gets its own mapping, and the heap's free top is not returned
    while under 2 GiB. True where it took effect (glibc)."""
    global _keeping
    mallopt = libc("mallopt")
    if mallopt is None:
        return False
    _keeping = bool(mallopt(M_MMAP_MAX, 0)) and bool(mallopt(M_TRIM_THRESHOLD, _KEPT))
    return _keeping


def prefault(size: int) -> threading.Thread | None:
    """Grow the heap by ``size`` bytes (at most ``PREFAULT_MOST``) for the arrays to come,
    and fault those pages in on a thread of their own, a batch per call to the kernel
    (``MADV_POPULATE_WRITE``), while this thread goes on. Only after :func:`keep_freed` took
    effect (so the blocks freed here stay in the heap, where the next arrays are cut from them).

    Faulting in new memory one page at a time, as arrays first write it, is what a large mesh
    spends most on here: with the pages populated by the kernel ahead, ``analyze`` of a 14M
    faces binary STL spends about half the system time it spends without. The bytes are never
    written here, so the allocator's own use of the blocks (the heap's headers) is safe
    meanwhile; a range the heap no longer holds is refused by the kernel (ENOMEM) and left.
    Returns the thread, or None where nothing was done.
    """
    malloc, free, madvise = libc("malloc"), libc("free"), libc("madvise")
    if not _keeping or size < 2 * _PAGE or None in (malloc, free, madvise):
        return None
    malloc.restype, malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
    free.argtypes = [ctypes.c_void_p]
    madvise.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int]
    # Blocks of at most PREFAULT_LIMIT, each followed by a small one that stays allocated
    # (64 bytes): freed, they stay apart instead of merging into a free top larger than the
    # allocator keeps (it would return it to the system at once).
    blocks: list[tuple[int, int]] = []
    left = min(size, PREFAULT_MOST)
    while left >= 2 * _PAGE:
        part = min(left, PREFAULT_LIMIT)
        block = malloc(part)
        if not block:
            break
        blocks.append((block, part))
        left -= part
        if left >= 2 * _PAGE and not malloc(_SPACER):
            break
    for block, _ in blocks:
        free(block)
    if not blocks:
        return None
    ranges = []
    for block, part in blocks:
        start = (block + _PAGE - 1) // _PAGE * _PAGE
        ranges.append((start, (block + part - start) // _PAGE * _PAGE))

    def populate() -> None:
        for start, length in ranges:
            madvise(start, length, MADV_POPULATE_WRITE)

    thread = threading.Thread(target=populate, name="prefault", daemon=True)
    thread.start()
    return thread


#: glibc's defaults, put back by :func:`end_job`.
_DEFAULT_MMAP_MAX = 65536
_DEFAULT_TRIM_THRESHOLD = 128 * 1024

_jobs_enabled = False
_faulting: threading.Thread | None = None


def enable_jobs() -> None:
    """In a process that runs one job after another (a job worker) or one job only (the
    command line's own): let :func:`start_job` act. Elsewhere (a server's own threads, a
    host's process) it does nothing."""
    global _jobs_enabled
    _jobs_enabled = True


def start_job(size: int) -> None:
    """For the job about to run, in a process that :func:`enable_jobs`: keep freed memory
    (:func:`keep_freed`) and fault ``size`` bytes in ahead (:func:`prefault`; none for 0),
    until :func:`end_job`."""
    global _faulting
    if _jobs_enabled and _faulting is None and keep_freed():
        _faulting = prefault(size)


def end_job(mapped_from: int) -> None:
    """After a job: wait for its prefaulting (so no page is faulted back in after the trim),
    put glibc's mapping and trimming back (blocks of ``mapped_from`` bytes or more mapped on
    their own), and return what the job freed (:func:`give_back`)."""
    global _keeping, _faulting
    if _faulting is not None:
        _faulting.join()
    _faulting = None
    mallopt = libc("mallopt")
    if _keeping and mallopt is not None:
        mallopt(M_MMAP_MAX, _DEFAULT_MMAP_MAX)
        mallopt(M_TRIM_THRESHOLD, _DEFAULT_TRIM_THRESHOLD)
        _keeping = False
    map_from(mapped_from)
    give_back()


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
