"""numba's cache entries are stamped with the modules whose kernels other modules' kernels call."""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path

import mesh_normal
from mesh_normal import kernels


def _all_kernels() -> list:
    for module in pkgutil.walk_packages(mesh_normal.__path__, "mesh_normal."):
        importlib.import_module(module.name)
    return list(kernels._KERNELS)


def test_every_module_whose_kernels_others_call_is_in_the_stamp() -> None:
    # A kernel compiled with a callee of another module carries the callee's code; its cache
    # entry must go stale when that module changes, so the module must be in SHARED_MODULES.
    from mesh_normal._numba_cache import SHARED_MODULES

    made = _all_kernels()
    files = {}
    for kernel in made:  # a module's name for a kernel: the kernel, or its dispatcher once made
        for named in (kernel, getattr(kernel, "dispatcher", None)):
            if named is not None:
                files[id(named)] = getattr(kernel, "py_func", kernel).__code__.co_filename
    package = Path(mesh_normal.__file__).parent
    called = set()
    for kernel in made:
        function = getattr(kernel, "py_func", kernel)
        for name in function.__code__.co_names:
            callee = function.__globals__.get(name)
            here = function.__code__.co_filename
            if callee is not None and id(callee) in files and files[id(callee)] != here:
                called.add(Path(files[id(callee)]).relative_to(package).as_posix())
    assert "kernels.py" in called  # the search finds them at all
    assert called <= set(SHARED_MODULES), called - set(SHARED_MODULES)


def test_a_kernel_s_entry_is_stamped_with_its_file_and_the_shared_modules() -> None:
    from mesh_normal._numba_cache import SHARED_MODULES, _shared_stamp, _SharedStamp

    kernels.load_numba()
    cache = kernels.dot._cache
    locator = cache._impl.locator
    own = super(_SharedStamp, locator).get_source_stamp()  # numba's stamp of kernels.py
    stamp = locator.get_source_stamp()
    assert stamp == (own, _shared_stamp())
    assert cache._cache_file._source_stamp == stamp  # what numba compares an index with
    assert len(stamp[1]) == len(SHARED_MODULES) and all(len(digest) == 32 for digest in stamp[1])
