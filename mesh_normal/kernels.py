"""The numba machinery of the kernels not yet in the compiled core, and their shared helpers.

A kernel here is compiled with numba (``cache=True``: compiled on first use, once, then
loaded from the cache; ``NUMBA_CACHE_DIR`` moves the cache). ``error_model="numpy"`` drops
Python's zero-division checks (IEEE rules apply); a parallel kernel's blocks write disjoint
rows, so the bits do not depend on the number of cores. The face, vertex and corner normals'
loops are in the compiled core instead (``mesh_normal._core``, ``cpp/faces.cpp``).

The first use of a kernel that is not in the cache says so on stderr, once per process
(:func:`announce_compiling`): the compile takes several seconds.
"""

from __future__ import annotations

import functools
import sys
import threading
from collections.abc import Callable
from typing import Any, Literal, TypeVar

import numpy as np

from mesh_normal.collector import paused
from mesh_normal.types import IndexArray, Vector

Function = TypeVar("Function", bound=Callable[..., Any])

#: Faces per block of a kernel.
BLOCK = 512

#: Held while a parallel kernel runs. numba's thread pools (its "workqueue" layer, the one
#: left where neither OpenMP nor TBB is installed) abort the process when two threads launch
#: parallel work at once; the web server calls the kernels from several worker threads.
PARALLEL_KERNELS = threading.Lock()

#: About how long ``compile_kernels()`` takes into an empty cache, in seconds: the mesh kernels
#: take about 10 s on two cores (about 2 s to load from the cache), the point-cloud kernels
#: about two thirds more, and a busy machine takes longer.
COMPILE_SECONDS = 20

# --- the compile announcement -----------------------------------------------------------------

#: Every kernel of the package, in the order its module defined it.
_KERNELS: list[Any] = []
#: The kernels that their callers name to :func:`announce_compiling` (see :func:`kernel`).
_NAMED: set[Any] = set()
_announce = threading.Lock()
_looked_at = 0
_announced = False


#: The stand-in for ``numba.prange`` in a kernel's module until numba is loaded (the kernels
#: import it from here); :func:`load_numba` puts numba's own in its place.
prange = range

#: A call of a kernel marked ``python=True`` whose arrays hold this many elements or fewer, in
#: a process that has not loaded numba, runs the kernel's Python source instead (a tiny mesh
#: is reported in milliseconds that way, where importing numba and loading the kernels from
#: its cache take 1-2 s). The same operations on the same doubles, one at a time and in the
#: same order: the bits are the same (``tests/mesh_normal/test_kernels_in_python.py``).
PYTHON_ELEMENTS = 6000

_load = threading.Lock()
_numba_loaded = False


class Kernel:
    """A kernel before numba is loaded: its Python source, and the options of its dispatcher.

    Calling it loads numba (:func:`load_numba`) unless the call is small enough to run in
    Python (see :data:`PYTHON_ELEMENTS`); any other attribute is the dispatcher's.
    """

    def __init__(self, function: Callable[..., Any], options: dict[str, Any], python: int) -> None:
        self.py_func, self.options, self.python = function, options, python
        self.dispatcher: Any = None
        functools.update_wrapper(self, function)

    def __call__(self, *args: Any) -> Any:
        if self.dispatcher is None:
            if not _numba_loaded and _small(args, self.python):
                return self.py_func(*args)
            load_numba()
            announce_compiling()
            if self in _NAMED:  # left out of the look-up above: this call runs it
                announce_compiling(self)
            if self.options["parallel"] and _takes_workers(self.py_func):
                # Its workers were counted before numba was loaded (one): all of numba's now.
                args = (*args[:-1], workers()[1])
        return self.dispatcher(*args)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name == "dispatcher":
            raise AttributeError(name)
        load_numba()
        return getattr(self.dispatcher, name)


def _takes_workers(function: Callable[..., Any]) -> bool:
    """Whether a kernel's last parameter is the number of workers (see :func:`workers`)."""
    code = function.__code__
    return code.co_argcount > 0 and code.co_varnames[code.co_argcount - 1] == "workers"


def _small(args: tuple[Any, ...], limit: int) -> bool:
    """Whether the arrays of a call hold ``limit`` elements at most (:data:`PYTHON_ELEMENTS`
    for a limit of 1, i.e. ``python=True``)."""
    if limit == 1:
        limit = PYTHON_ELEMENTS
    return bool(limit) and sum(arg.size for arg in args if isinstance(arg, np.ndarray)) <= limit


def kernel(
    *,
    parallel: bool = False,
    error_model: Literal["python", "numpy"] = "numpy",
    python: bool | int = False,
    named: bool = False,
    nogil: bool = False,
) -> Callable[[Function], Function]:
    """``numba.njit(cache=True, ...)`` with :class:`~mesh_normal._numba_cache.KernelCache`
    (which also reads a read-only cache), made when numba is loaded; remember the kernel for
    :func:`announce_compiling`. ``python``: small calls may run the Python source (only for
    kernels whose every step gives the same bits in Python: float64 and int64 arithmetic,
    ``math.sqrt``, comparisons; no NumPy reductions or sorts, no integer overflow); a number
    over 1 is the largest call, in array elements, for a kernel much slower in Python.

    ``named``: one of several kernels for the same work, of which a call runs one (the face
    normals from a mesh or from a geometry): left out of the look-up of every kernel defined,
    which would otherwise find the other one never compiled, and named by its caller instead.

    ``nogil``: the compiled kernel releases the GIL while it runs, for callers that run it on
    several threads at once (one OBJ chunk each).
    """

    def compiled(function: Function) -> Function:
        options = {"error_model": error_model, "parallel": parallel, "nogil": nogil}
        made: Any = _dispatcher(function, options) if _numba_loaded else None
        if made is None:
            made = Kernel(function, options, int(python))
        _KERNELS.append(made)
        if named:
            _NAMED.add(made)
        return made  # type: ignore[no-any-return]

    return compiled


def _dispatcher(function: Callable[..., Any], options: dict[str, Any]) -> Any:
    """What ``njit(cache=True, **options)`` makes, with the cache that can also only read."""
    from numba import njit

    from mesh_normal._numba_cache import KernelCache

    dispatcher = njit(**options)(function)
    # What cache=True does (Dispatcher.enable_caching), with the cache that can read only.
    dispatcher._cache = KernelCache(function)  # type: ignore[no-untyped-call]
    return dispatcher


def load_numba() -> None:
    """Import numba and make every kernel its dispatcher (each compiled, or loaded from the
    cache, at its first call): in each kernel's module the name now means the dispatcher, as
    numba needs for the kernels that call it, and each Python stand-in that a kernel's module
    imported under its own name means numba's or LLVM's own: ``prange`` numba's, ``claim``,
    ``peek`` and ``bump`` the atomic steps (:func:`_counter_intrinsic`), ``prefetch`` and
    ``prefetch_row`` the CPU's (:func:`_prefetch_intrinsic`), ``load_word`` one unaligned load
    (:func:`_load_word_intrinsic`)."""
    global _numba_loaded
    if _numba_loaded:
        return
    with _load, paused():
        if _numba_loaded:
            return
        import numba

        compiled = {  # name: (the stand-in, what takes its place)
            "prange": (range, numba.prange),
            "claim": (claim, _claim_intrinsic()),
            "prefetch": (prefetch, _prefetch_intrinsic()),
            "prefetch_row": (prefetch_row, _prefetch_intrinsic(write=False, whole_row=True)),
            "peek": (peek, _peek_intrinsic()),
            "bump": (bump, _bump_intrinsic()),
            "load_word": (load_word, _load_word_intrinsic()),
        }
        waiting = [made for made in _KERNELS if isinstance(made, Kernel)]
        for made in waiting:
            made.dispatcher = _dispatcher(made.py_func, made.options)
        for made in waiting:
            namespace = made.py_func.__globals__
            for name, value in list(namespace.items()):
                if isinstance(value, Kernel):
                    namespace[name] = value.dispatcher
                elif name in compiled and value is compiled[name][0]:
                    namespace[name] = compiled[name][1]
        _numba_loaded = True


def announce_compiling(*kernels: Any) -> None:
    """Say once on stderr that the kernels are being compiled, if one is not in the cache.

    Called before the kernels run. Each kernel defined since the last call is looked up in
    numba's cache index, as numba itself will: the entry must be for this numba version,
    this source file (its stamp), this CPU and this bytecode. Given ``kernels``, only those
    are looked up: a caller that runs only its own (the point-cloud estimate) does not say
    so for the mesh kernels its imports defined but it never runs.
    """
    global _looked_at, _announced
    if not _numba_loaded and not kernels:  # a call that loads numba says so then
        return
    if not _numba_loaded and all(isinstance(made, Kernel) and made.python for made in kernels):
        return  # they may run in Python; the call that loads numba says so then
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
    where they are missing (or ``dispatcher`` is not one: a test's stand-in), it answers
    True (no announcement rather than a wrong one).
    """
    try:
        if dispatcher.overloads:
            return True
        cache = dispatcher._cache
        codegen = dispatcher.targetctx.codegen()
        index = cache._cache_file._load_index()
        return any(cache._index_key(key[0], codegen) == key for key in index)
    except (AttributeError, TypeError, IndexError):
        return True


# --- prefetching ------------------------------------------------------------------------------
#
# A face's corners are rows far apart in the points (and its vertices rows far apart in the sums
# of the vertex normals): each is a cache miss on a large mesh. Asking for the rows of the face
# ``AHEAD`` faces on before they are needed keeps many misses in flight at once: on a large
# mesh it nearly halves the time of the vertex sums' scatter.

#: How many faces ahead a kernel asks for the rows it will read (8 and 32 are slower).
AHEAD = 16


def prefetch(array: np.ndarray, row: int) -> None:
    """Ask the CPU to bring row ``row`` of a 1-D or 2-D array into its cache, for a write. The
    stand-in for a kernel's Python source does nothing (a hint, not a step: the bits are the
    same); :func:`load_numba` puts :func:`_prefetch_intrinsic`'s in its place."""


def prefetch_row(array: np.ndarray, row: int) -> None:
    """Ask the CPU to bring the whole of row ``row`` of a 2-D array into its cache, to be read:
    its first and its last element (a row of three doubles lies across two cache lines once
    in about three). On a large mesh this makes the face normals' gather about a tenth faster
    than one write prefetch of the row's first element. A stand-in, as :func:`prefetch`."""


def _prefetch_intrinsic(write: bool = True, whole_row: bool = False) -> Any:
    """numba's ``prefetch`` (and, with ``write=False, whole_row=True``, ``prefetch_row``):
    LLVM's ``llvm.prefetch`` (write or read, keep in every cache level) of the address of
    ``array[row]`` or ``array[row, 0]`` (and ``array[row, -1]``). An address past the array is
    harmless: a prefetch never faults."""
    from llvmlite import ir  # type: ignore[import-untyped]
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def _prefetch(typingctx: Any, array: Any, row: Any) -> Any:  # noqa: ARG001
        if not (isinstance(array, types.Array) and array.ndim in (1, 2)):
            return None
        if not isinstance(row, types.Integer):
            return None

        def codegen(context: Any, builder: Any, signature: Any, arguments: Any) -> Any:
            array_type, row_type = signature.args
            made = context.make_array(array_type)(context, builder, arguments[0])
            index = context.cast(builder, arguments[1], row_type, types.intp)
            columns = [context.get_constant(types.intp, 0)] * (array_type.ndim - 1)
            if whole_row and array_type.ndim == 2:
                last = builder.sub(
                    cgutils.unpack_tuple(builder, made.shape)[1],  # type: ignore[no-untyped-call]
                    context.get_constant(types.intp, 1),
                )
                columns = [columns[0], last]
            byte = ir.IntType(8).as_pointer()
            word = ir.IntType(32)
            function = cgutils.get_or_insert_function(  # type: ignore[no-untyped-call]
                builder.module,
                ir.FunctionType(ir.VoidType(), [byte, word, word, word]),
                "llvm.prefetch.p0i8",
            )
            for column in columns if array_type.ndim == 2 else [None]:
                indices = [index] if column is None else [index, column]
                address = cgutils.get_item_pointer(  # type: ignore[no-untyped-call]
                    context, builder, array_type, made, indices, wraparound=False
                )
                # write (1) or read (0), high locality (3), data cache (1)
                builder.call(
                    function,
                    [builder.bitcast(address, byte), word(int(write)), word(3), word(1)],
                )
            return context.get_dummy_value()

        return types.none(array, row), codegen

    return _prefetch


# --- the kernels -------------------------------------------------------------------------------


# --- sorting and searching, ours ----------------------------------------------------------
#
# The kernels sort and search with these instead of numba's ``.sort()``, ``np.sort``,
# ``np.argsort`` and ``np.searchsorted``. numba generates its sort and its argsort from one
# quicksort whose functions have the same names, and compiled code of each, saved in numba's
# cache by different processes, can carry the same symbol: a process that loads both from the
# cache runs whichever it loaded first for both (with numba 0.68, a cached argsort loaded
# after a cached ``.sort()`` of int64 returns the sorted values as indices, and the reverse
# order breaks the sort). Our own functions have names of their own, so no other code
# in the process (a user's cached argsort) can take their place, nor they its.


@kernel(python=True)
def sort_run(values: IndexArray, first: int, last: int) -> None:
    """Sort ``values[first:last]`` in place, ascending: an insertion sort for up to 16 values
    (a few, mostly in order: a vertex's half-edges), a heapsort beyond (no recursion, no
    scratch). Integers, so any correct sort gives the same array."""
    if last - first <= 16:
        for row in range(first + 1, last):
            value = values[row]
            place = row
            while place > first and values[place - 1] > value:
                values[place] = values[place - 1]
                place -= 1
            values[place] = value
        return
    count = last - first
    for start in range(count // 2 - 1, -1, -1):
        _sift_down(values, first, start, count)
    for end in range(count - 1, 0, -1):
        values[first], values[first + end] = values[first + end], values[first]
        _sift_down(values, first, 0, end)


@kernel(python=True)
def _sift_down(values: IndexArray, first: int, root: int, count: int) -> None:
    """Move ``values[first + root]`` down the max-heap of ``count`` values from ``first``."""
    value = values[first + root]
    while True:
        child = 2 * root + 1
        if child >= count:
            break
        if child + 1 < count and values[first + child + 1] > values[first + child]:
            child += 1
        if values[first + child] <= value:
            break
        values[first + root] = values[first + child]
        root = child
    values[first + root] = value


@kernel(python=True)
def lower_bound(values: IndexArray, first: int, last: int, target: int) -> int:
    """The first place in the sorted ``values[first:last]`` whose value is at least
    ``target`` (``last`` if none): ``first + np.searchsorted(values[first:last], target)``."""
    low, high = first, last
    while low < high:
        middle = (low + high) // 2
        if values[middle] < target:
            low = middle + 1
        else:
            high = middle
    return low


@kernel(python=True)
def dot(p: Vector, q: Vector) -> float:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


# --- dynamic blocks -------------------------------------------------------------------------
#
# A parallel kernel runs one worker per thread (``prange(workers)``), and each worker claims the
# next block of faces from a shared counter until none is left: a thread that starts late or is
# descheduled (a shared machine, the first call after an idle second) leaves its blocks to the
# others instead of stalling the call, as numba's static split of a ``prange`` in equal parts
# does. Where each block writes its own rows, the bits do not depend on who ran it.


def claim(counter: IndexArray) -> int:
    """``counter[0] += 1``, returning the value before: the next task. This is the stand-in
    for a kernel's Python source, run by one worker (:func:`workers` gives one until numba is
    loaded); :func:`load_numba` puts :func:`_claim_intrinsic`'s atomic add in its place."""
    value = int(counter[0])
    counter[0] = value + 1
    return value


def _counter_intrinsic(step: Callable[[Any, Any, Any], Any], returns: bool) -> Any:
    """A numba intrinsic on ``counter[0]`` of an int64 array: ``step(context, builder,
    address)`` emits its one atomic step, whose value the intrinsic returns where ``returns``."""
    from numba import types
    from numba.extending import intrinsic

    @intrinsic
    def _on_counter(typingctx: Any, counter: Any) -> Any:  # noqa: ARG001 (numba's typing context)
        if not (isinstance(counter, types.Array) and counter.dtype == types.int64):
            return None

        def codegen(context: Any, builder: Any, signature: Any, arguments: Any) -> Any:
            array = context.make_array(signature.args[0])(context, builder, arguments[0])
            value = step(context, builder, array.data)
            return value if returns else context.get_dummy_value()

        return (types.int64 if returns else types.none)(counter), codegen

    return _on_counter


def _add_one(ordering: str) -> Callable[[Any, Any, Any], Any]:
    """The step ``counter[0] += 1`` as one atomic add with LLVM's ``ordering``, giving the
    value before."""

    def step(context: Any, builder: Any, address: Any) -> Any:
        from numba import types

        one = context.get_constant(types.int64, 1)
        return builder.atomic_rmw("add", address, one, ordering)

    return step


def _claim_intrinsic() -> Any:
    """numba's ``claim``: ``counter[0] += 1`` as one atomic step, returning the value before."""
    return _counter_intrinsic(_add_one("monotonic"), returns=True)


def peek(counter: IndexArray) -> int:
    """``counter[0]``, read as one atomic step that later reads do not pass (an acquire): what
    a worker waits on while another one finishes a task (:func:`bump`). The stand-in for a
    kernel's Python source reads it; :func:`load_numba` puts :func:`_peek_intrinsic` in its
    place."""
    return int(counter[0])


def bump(counter: IndexArray) -> None:
    """``counter[0] += 1`` as one atomic step that earlier writes do not pass (a release): a
    worker says that a task's results are written (see :func:`peek`). The stand-in for a
    kernel's Python source adds; :func:`load_numba` puts :func:`_bump_intrinsic` in its
    place."""
    counter[0] += 1


def _peek_intrinsic() -> Any:
    """numba's ``peek``: an atomic load (acquire) of ``counter[0]``, never hoisted out of the
    loop that waits on it."""
    return _counter_intrinsic(
        lambda _context, builder, address: builder.load_atomic(address, "acquire", 8), True
    )


def _bump_intrinsic() -> Any:
    """numba's ``bump``: ``counter[0] += 1`` as one atomic add (release)."""
    return _counter_intrinsic(_add_one("release"), returns=False)


def load_word(data: np.ndarray, at: int, signed: bool) -> int:
    """The 4-byte integer at byte ``at`` of the uint8 array ``data``, in this machine's byte
    order, wherever it lies (a binary PLY's records are 13 bytes long). The stand-in for a
    kernel's Python source; :func:`load_numba` puts :func:`_load_word_intrinsic` in its place."""
    return int.from_bytes(bytes(data[at : at + 4]), sys.byteorder, signed=signed)


def _load_word_intrinsic() -> Any:
    """numba's ``load_word``: one unaligned 32-bit load (LLVM ``align 1``), sign- or
    zero-extended to int64: what four byte loads and shifts compute, one instruction."""
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def _load_word(typingctx: Any, data: Any, at: Any, signed: Any) -> Any:  # noqa: ARG001
        if not (isinstance(data, types.Array) and data.ndim == 1 and data.dtype == types.uint8):
            return None

        def codegen(context: Any, builder: Any, signature: Any, arguments: Any) -> Any:
            array_type, at_type, _ = signature.args
            made = context.make_array(array_type)(context, builder, arguments[0])
            index = context.cast(builder, arguments[1], at_type, types.intp)
            address = cgutils.get_item_pointer(  # type: ignore[no-untyped-call]
                context, builder, array_type, made, [index], wraparound=False
            )
            word = builder.load(builder.bitcast(address, ir.IntType(32).as_pointer()), align=1)
            wide = ir.IntType(64)
            flag = context.cast(builder, arguments[2], signature.args[2], types.boolean)
            return builder.select(flag, builder.sext(word, wide), builder.zext(word, wide))

        return types.int64(data, at, signed), codegen

    return _load_word


def workers() -> tuple[IndexArray, int]:
    """A fresh task counter and the number of workers for a parallel kernel: numba's threads,
    or one where numba is not loaded (a kernel run as Python)."""
    counter = np.zeros(1, dtype=np.int64)
    if not _numba_loaded:
        return counter, 1
    import numba

    return counter, numba.get_num_threads()
