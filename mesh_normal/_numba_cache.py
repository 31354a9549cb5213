"""numba's cache of compiled kernels, which also reads a cache it may not write.

Imported by :func:`mesh_normal.kernels.load_numba` with numba itself, when the first kernel is
compiled or loaded from the cache, so that importing the library does not import numba.
"""

from __future__ import annotations

import hashlib
import os
from typing import Any

from numba.core import config as numba_config
from numba.core.caching import (
    CompileResultCacheImpl,
    FunctionCache,
    InTreeCacheLocator,
    UserProvidedCacheLocator,
)

# --- the cache, also on a read-only filesystem ------------------------------------------------
#
# numba's own cache locators each insist on a folder they can write: they test it by writing a
# temporary file there. On a read-only root filesystem (``docker run --read-only``) every one
# refuses, even for a NUMBA_CACHE_DIR that holds every kernel compiled while the image was
# built (or a mount the app's user may not write), and ``njit(cache=True)`` then raises at
# import: "cannot cache function 'index_range_kernel': no locator available". The locators below are
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


# --- kernels that call kernels of another module ---------------------------------------------
#
# numba compiles a kernel that calls another into one piece of machine code, and caches it under
# the caller's own source file: its entry stays valid, with the callee's old code in it, when
# only the callee's module changes (a working checkout after an edit of ``kernels.py``; the
# callee itself is then never compiled, and ``announce_compiling`` says "compiling" in every
# process). Every kernel's entry is therefore also stamped with the modules whose kernels
# other modules' kernels call (``tests/mesh_normal/test_numba_cache.py`` finds them): an edit of
# one of them compiles every kernel again. An installed package or the image never changes its
# files, so their entries stay valid.

#: The package's modules whose kernels are called by kernels of other modules.
SHARED_MODULES = ("kernels.py", "vertices.py", "visibility.py")


def _shared_stamp() -> tuple[bytes, ...]:
    """The SHA-256 of each of :data:`SHARED_MODULES`' source (what numba's own stamp of a
    kernel's file is, in numba 0.68)."""
    package = os.path.dirname(os.path.abspath(__file__))
    stamps = []
    for name in SHARED_MODULES:
        with open(os.path.join(package, name), "rb") as source:
            stamps.append(hashlib.sha256(source.read()).digest())
    return tuple(stamps)


_SHARED_STAMP = _shared_stamp()


class _SharedStamp:
    """A locator whose source stamp (numba's test of a cache entry) also covers
    :data:`SHARED_MODULES`."""

    def get_source_stamp(self) -> Any:
        return (super().get_source_stamp(), _SHARED_STAMP)  # type: ignore[misc]


def _stamped(locator: Any) -> Any:
    return type(locator.__name__, (_SharedStamp, locator), {})


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [  # noqa: RUF012 (numba's own class attribute)
        _stamped(locator)
        for locator in (
            CompileResultCacheImpl._locator_classes[0],  # NUMBA_CACHE_DIR, if numba may write it
            ReadOnlyCacheDirLocator,
            *CompileResultCacheImpl._locator_classes[1:],
            ReadOnlyInTreeLocator,
        )
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
