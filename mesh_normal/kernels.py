"""The compiled per-face loops that the face, vertex and corner normals share.

The per-face work is compiled with numba (``cache=True``: compiled on first use, once, then
loaded from the cache; ``NUMBA_CACHE_DIR`` moves the cache). It is the only implementation:
NumPy alone measured 3-5 times slower than Open3D, whose times are the target (see the
README's mesh kernels section). So this part of ``mesh_normal`` is not pure NumPy.
``error_model="numpy"`` drops Python's zero-division checks (no division here can be by zero,
and IEEE rules apply); the face kernel runs its blocks of faces on every core
(``parallel=True``: blocks write disjoint rows, so the bits do not depend on the number of
cores).

Each kernel goes through the faces in blocks: it first copies the scaled corners of a block
of faces (independent loads, so their cache misses overlap), then does its work for each
face, through :func:`face_edges` and :func:`face_cross`. Constants are frozen at compile time.

The first use of a kernel that is not in the cache says so on stderr, once per process
(:func:`announce_compiling`): the compile takes several seconds.
"""

from __future__ import annotations

import math
import os
import sys
import threading
from collections.abc import Callable
from typing import Any, Literal, TypeVar

import numpy as np
from numba import njit, prange, types
from numba.core import config as numba_config
from numba.core.caching import (
    CompileResultCacheImpl,
    FunctionCache,
    InTreeCacheLocator,
    UserProvidedCacheLocator,
)
from numba.extending import intrinsic

from mesh_normal.tolerances import MESH_DEGENERATE_SINE, MESH_RECOMPUTE_SINE
from mesh_normal.types import BoolArray, Edges, FloatArray, IndexArray, Vector

Function = TypeVar("Function", bound=Callable[..., Any])

#: Faces per block of a kernel.
BLOCK = 512

#: Held while a parallel kernel runs. numba's thread pools (its "workqueue" layer, the one
#: left where neither OpenMP nor TBB is installed) abort the process when two threads launch
#: parallel work at once; the web server calls the kernels from several worker threads.
PARALLEL_KERNELS = threading.Lock()

#: What :func:`face_cross` found: the product at corner A is good, it was taken again at
#: the largest corner, or the face is degenerate.
AT_FIRST_CORNER, AT_LARGEST_CORNER, DEGENERATE = range(3)

#: Measured: ``compile_kernels()`` into an empty cache took 9.7 s on a 2-core machine for the
#: mesh kernels (loading them from the cache, 1.8 s); the point-cloud kernels add about two
#: thirds (29 s and 19 s on the same machine under a load of 4).
COMPILE_SECONDS = 20

_RECOMPUTE = MESH_RECOMPUTE_SINE**2
_DEGENERATE = MESH_DEGENERATE_SINE**2

# --- the compile announcement -----------------------------------------------------------------

#: Every kernel of the package, in the order its module defined it.
_KERNELS: list[Any] = []
#: The kernels that their callers name to :func:`announce_compiling` (see :func:`kernel`).
_NAMED: set[Any] = set()
_announce = threading.Lock()
_looked_at = 0
_announced = False


# --- the cache, also on a read-only filesystem ------------------------------------------------
#
# numba's own cache locators each insist on a folder they can write: they test it by writing a
# temporary file there. On a read-only root filesystem (``docker run --read-only``) every one
# refuses, even for a NUMBA_CACHE_DIR that holds every kernel compiled while the image was
# built (or a mount the app's user may not write), and ``njit(cache=True)`` then raises at
# import: "cannot cache function 'index_range': no locator available". The locators below are
# tried after numba's writable ones: they read the same folder and never write it. A kernel
# that is not in such a cache (another CPU, another signature) is compiled in memory, as
# without a cache, and kept for the process.


class _ReadOnlyLocator:
    """A locator whose folder is read as it is: nothing checked by writing, nothing saved."""

    def ensure_cache_path(self) -> None:
        """Nothing to ensure: the folder is only read (a missing one is an empty cache)."""


class ReadOnlyCacheDirLocator(_ReadOnlyLocator, UserProvidedCacheLocator):
    """``NUMBA_CACHE_DIR`` when numba may not write it: e.g. the image's, on a read-only root."""

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> ReadOnlyCacheDirLocator | None:
        cache_dir = getattr(numba_config, "CACHE_DIR", "")
        if not cache_dir or not os.path.exists(py_file):
            return None
        return cls(py_func, py_file)


class ReadOnlyInTreeLocator(_ReadOnlyLocator, InTreeCacheLocator):
    """The ``__pycache__`` beside the source, read only: the last resort, so import never fails."""

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> ReadOnlyInTreeLocator | None:
        return cls(py_func, py_file) if os.path.exists(py_file) else None


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [  # noqa: RUF012 (numba's own class attribute)
        CompileResultCacheImpl._locator_classes[0],  # NUMBA_CACHE_DIR, if numba may write it
        ReadOnlyCacheDirLocator,
        *CompileResultCacheImpl._locator_classes[1:],
        ReadOnlyInTreeLocator,
    ]


class KernelCache(FunctionCache):
    """numba's cache of compiled functions, which also reads a cache it may not write."""

    _impl_class = _KernelCacheImpl

    @property
    def read_only(self) -> bool:
        return isinstance(self._impl.locator, _ReadOnlyLocator)

    def save_overload(self, sig: Any, data: Any) -> None:
        if not self.read_only:  # read-only: the kernel stays compiled in memory only
            super().save_overload(sig, data)  # type: ignore[no-untyped-call]


def kernel(
    *,
    parallel: bool = False,
    error_model: Literal["python", "numpy"] = "numpy",
    named: bool = False,
) -> Callable[[Function], Function]:
    """``numba.njit(cache=True, ...)`` with :class:`KernelCache` (which also reads a read-only
    cache), and remember the kernel for :func:`announce_compiling`.

    ``named``: one of several kernels for the same work, of which a call runs one (the face
    normals from a mesh or from a geometry): left out of the look-up of every kernel defined,
    which would otherwise find the other one never compiled, and named by its caller instead.
    """

    def compiled(function: Function) -> Function:
        dispatcher = njit(error_model=error_model, parallel=parallel)(function)
        # What cache=True does (Dispatcher.enable_caching), with the cache that can read only.
        dispatcher._cache = KernelCache(function)  # type: ignore[attr-defined,no-untyped-call]
        _KERNELS.append(dispatcher)
        if named:
            _NAMED.add(dispatcher)
        return dispatcher  # type: ignore[return-value]

    return compiled


def announce_compiling(*kernels: Any) -> None:
    """Say once on stderr that the kernels are being compiled, if one is not in the cache.

    Called before the kernels run. Each kernel defined since the last call is looked up in
    numba's cache index, as numba itself will: the entry must be for this numba version,
    this source file (its stamp), this CPU and this bytecode. Given ``kernels``, only those
    are looked up: a caller that runs only its own (the point-cloud estimate) does not say
    so for the mesh kernels its imports defined but it never runs.
    """
    global _looked_at, _announced
    if kernels:
        with _announce:
            if not _announced and not all(map(is_cached, kernels)):
                _announced = True
                _say_compiling()
        return
    if _announced or _looked_at == len(_KERNELS):
        return
    with _announce:
        fresh, _looked_at = _KERNELS[_looked_at:], len(_KERNELS)
        fresh = [kernel for kernel in fresh if kernel not in _NAMED]
        if not _announced and not all(map(is_cached, fresh)):
            _announced = True
            _say_compiling()


def _say_compiling() -> None:
    print(
        "mesh-normal: compiling the mesh kernels (each once, about "
        f"{COMPILE_SECONDS} s for all of them; later runs load them from the cache)",
        file=sys.stderr,
        flush=True,
    )


def is_cached(dispatcher: Any) -> bool:
    """Whether numba will load ``dispatcher`` from its cache rather than compile it.

    True when it is compiled already in this process, or when the cache index holds an
    entry that numba's own lookup (``Cache._index_key``) would accept for one of its
    signatures. This reads numba internals (``_cache``, ``_cache_file._load_index``);
    where they are missing, it answers True (no announcement rather than a wrong one).
    """
    if dispatcher.overloads:
        return True
    try:
        cache = dispatcher._cache
        codegen = dispatcher.targetctx.codegen()
        index = cache._cache_file._load_index()
        return any(cache._index_key(key[0], codegen) == key for key in index)
    except (AttributeError, TypeError, IndexError):
        return True


# --- the kernels -------------------------------------------------------------------------------


@kernel()
def index_range(faces: IndexArray) -> tuple[int, int]:
    """The smallest and largest of the indices and 0, in one pass."""
    low, high = 0, 0
    for index in faces.ravel():
        low, high = min(low, int(index)), max(high, int(index))
    return low, high


@kernel()
def gather(
    points: FloatArray, factor: float, faces: IndexArray, start: int, corners: FloatArray
) -> int:
    """Copy A, B, C of faces ``start`` on, times ``factor``, into the rows of ``corners``.

    ``corners`` is (block, 9); returns how many rows were filled.
    """
    count = min(len(corners), len(faces) - start)
    for row in range(count):
        for k in range(3):
            vertex = faces[start + row, k]
            corners[row, 3 * k] = points[vertex, 0] * factor
            corners[row, 3 * k + 1] = points[vertex, 1] * factor
            corners[row, 3 * k + 2] = points[vertex, 2] * factor
    return count


@kernel()
def dot(p: Vector, q: Vector) -> float:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


@kernel()
def cross(p: Vector, q: Vector) -> Vector:
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


@kernel()
def face_edges(corners: FloatArray, row: int) -> Edges:
    """The edges B - A, C - B, A - C of one face: corner k lies between edges k - 1 and k."""
    ax, ay, az = corners[row, 0], corners[row, 1], corners[row, 2]
    bx, by, bz = corners[row, 3], corners[row, 4], corners[row, 5]
    cx, cy, cz = corners[row, 6], corners[row, 7], corners[row, 8]
    return (bx - ax, by - ay, bz - az), (cx - bx, cy - by, cz - bz), (ax - cx, ay - cy, az - cz)


@kernel()
def face_cross(edges: Edges) -> tuple[Vector, float, int]:
    """(B - A) x (C - A) from its most accurate corner, its squared length, and where from.

    The product is taken at corner A (``AT_FIRST_CORNER``); if that corner's sine is small,
    again at the largest corner (opposite the longest edge, edge k being opposite corner
    k + 2; ``AT_LARGEST_CORNER``). There a sine of at most ``MESH_DEGENERATE_SINE`` makes the
    face degenerate: zero normal, ``DEGENERATE``. At corner A, (A - C) x (B - A) has the same
    bits as (B - A) x (C - A): negating a difference is exact.
    """
    normal = cross(edges[2], edges[0])
    square = dot(normal, normal)
    if square > _RECOMPUTE * dot(edges[2], edges[2]) * dot(edges[0], edges[0]):
        return normal, square, AT_FIRST_CORNER
    e0, e1, e2 = edges
    s0, s1, s2 = dot(e0, e0), dot(e1, e1), dot(e2, e2)
    # The two edges after the longest, by name: a tuple indexed at run time is slow.
    if s0 >= s1 and s0 >= s2:
        p, q, sp, sq = e1, e2, s1, s2
    elif s1 >= s2:
        p, q, sp, sq = e2, e0, s2, s0
    else:
        p, q, sp, sq = e0, e1, s0, s1
    normal = cross(p, q)
    square = dot(normal, normal)
    if square <= _DEGENERATE * sp * sq:
        return (0.0, 0.0, 0.0), 0.0, DEGENERATE
    return normal, square, AT_LARGEST_CORNER


# --- dynamic blocks -------------------------------------------------------------------------
#
# A parallel kernel runs one worker per thread (``prange(workers)``), and each worker claims the
# next block of faces from a shared counter until none is left: a thread that starts late or is
# descheduled (a shared machine, the first call after an idle second) leaves its blocks to the
# others instead of stalling the call, as numba's static split of a ``prange`` in equal parts
# does. Where each block writes its own rows, the bits do not depend on who ran it.


@intrinsic
def _claim(typingctx: Any, counter: Any) -> Any:  # noqa: ARG001 (numba's typing context)
    """``counter[0] += 1`` as one atomic step, returning the value before: the next task."""
    if not (isinstance(counter, types.Array) and counter.dtype == types.int64):
        return None

    def codegen(context: Any, builder: Any, signature: Any, arguments: Any) -> Any:
        array = context.make_array(signature.args[0])(context, builder, arguments[0])
        one = context.get_constant(types.int64, 1)
        return builder.atomic_rmw("add", array.data, one, "monotonic")

    return types.int64(counter), codegen


#: :func:`_claim` as the kernels call it: ``claim(counter)`` (an intrinsic's own type takes
#: the typing context first).
claim: Callable[[IndexArray], int] = _claim  # type: ignore[assignment]


def workers() -> tuple[IndexArray, int]:
    """A fresh task counter and the number of workers for a parallel kernel (numba's threads)."""
    import numba

    return np.zeros(1, dtype=np.int64), numba.get_num_threads()


@kernel(parallel=True, named=True)
def geometry_kernel(
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    crosses: FloatArray,
    lengths: FloatArray,
    degenerate: BoolArray,
    recomputed: BoolArray,
    counter: IndexArray,
    workers: int,
) -> None:
    """Each face's cross product, |cross| and flags (see ``FaceGeometry``)."""
    blocks = (len(faces) + BLOCK - 1) // BLOCK
    for _ in prange(workers):  # blocks write disjoint rows: any worker may take any block
        corners = np.empty((BLOCK, 9))
        block = claim(counter)
        while block < blocks:
            start = block * BLOCK
            for row in range(gather(points, factor, faces, start, corners)):
                face = start + row
                (x, y, z), square, found = face_cross(face_edges(corners, row))
                crosses[face, 0], crosses[face, 1], crosses[face, 2] = x, y, z
                lengths[face] = math.sqrt(square)
                degenerate[face] = found == DEGENERATE
                recomputed[face] = found != AT_FIRST_CORNER
            block = claim(counter)


@kernel(parallel=True, named=True)
def face_normals_kernel(
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    exponent: int,
    normals: FloatArray,
    areas: FloatArray,
    degenerate: BoolArray,
    counter: IndexArray,
    workers: int,
) -> None:
    """Each face's unit normal, area and degenerate flag in one pass, with the arithmetic of
    ``geometry_kernel`` then ``FaceGeometry.unit_normals`` and ``geometry_areas``: the unit
    normal is the cross product over |cross| (over 1 where degenerate, where it is zero) plus
    0.0, the area ``ldexp(|cross|, exponent)``: times 2**exponent where that is a normal
    double (the same single rounding, without a call per face; measured a third of the
    kernel's time)."""
    blocks = (len(faces) + BLOCK - 1) // BLOCK
    power = math.ldexp(1.0, exponent) if -1022 <= exponent <= 1023 else 0.0
    for _ in prange(workers):
        corners = np.empty((BLOCK, 9))
        block = claim(counter)
        while block < blocks:
            start = block * BLOCK
            for row in range(gather(points, factor, faces, start, corners)):
                face = start + row
                (x, y, z), square, found = face_cross(face_edges(corners, row))
                length = math.sqrt(square)
                divisor = 1.0 if found == DEGENERATE else length
                normals[face, 0] = x / divisor + 0.0  # -0.0 becomes 0.0
                normals[face, 1] = y / divisor + 0.0
                normals[face, 2] = z / divisor + 0.0
                areas[face] = length * power if power else math.ldexp(length, exponent)
                degenerate[face] = found == DEGENERATE
            block = claim(counter)
