"""The kernels' own sort and binary search (``mesh_normal.kernels``), and that no kernel calls
numba's: its sort, argsort and searchsorted are generated functions whose names repeat, and
loaded from numba's cache one can run in place of another."""

from __future__ import annotations

import ast

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from mesh_normal.kernels import load_numba, lower_bound, sort_run
from tests.paths import ROOT

BIG = 2**62


@given(
    values=st.lists(st.integers(-BIG, BIG), max_size=200),
    cut=st.integers(0, 200),
    targets=st.lists(st.integers(-BIG, BIG), min_size=1, max_size=5),
)
def test_the_python_source_agrees_with_numpy(
    values: list[int], cut: int, targets: list[int]
) -> None:
    array = np.array([*values, 7], dtype=np.int64)
    first, last = min(cut, len(values)), len(array)
    expected = array.copy()
    expected[first:last] = np.sort(expected[first:last])
    sort_run.py_func(array, first, last)  # type: ignore[attr-defined]
    assert np.array_equal(array, expected)
    for target in targets:
        found = lower_bound.py_func(array, first, last, target)  # type: ignore[attr-defined]
        assert found == first + np.searchsorted(array[first:last], target)


def test_the_compiled_kernels_agree_with_numpy_on_short_and_long_runs() -> None:
    load_numba()
    rng = np.random.default_rng(3)
    for size in (0, 1, 2, 16, 17, 100, 5000):
        values = rng.integers(-50, 50, size + 3)
        expected = values.copy()
        expected[3:] = np.sort(expected[3:])
        sort_run(values, 3, size + 3)
        assert np.array_equal(values, expected)
        for target in (-51, 0, 7, 51):
            at = lower_bound(values, 3, size + 3, target)
            assert at == 3 + np.searchsorted(values[3:], target)


def test_no_kernel_calls_numbas_sorts_or_searches() -> None:
    found = []
    for path in (ROOT / "mesh_normal").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.FunctionDef):
                continue
            if not any("kernel" in ast.unparse(decorator) for decorator in node.decorator_list):
                continue
            for call in ast.walk(node):
                if (
                    isinstance(call, ast.Call)
                    and isinstance(call.func, ast.Attribute)
                    and call.func.attr in ("sort", "argsort", "searchsorted", "lexsort")
                ):
                    found.append(f"{path.name}:{call.lineno} {node.name}")
    assert found == []
