"""Serial and parallel compilations of one kernel, and the work size that picks between them.

numba's parallel loops pay a thread launch and join per call: on small work (a few dozen
segments, a small lattice) that costs more than the work itself, most on a loaded machine
(a lattice plan on the bundled map: 0.096 s with two threads, 0.012 s with one). Each
parallel kernel is therefore compiled twice from the same Python source, and the caller
picks the parallel one only when the work is large enough (:func:`use_parallel`);
``benchmarks/plan_bench.py`` measures the threshold.
"""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

import numba

__all__ = ["PARALLEL_MIN_WALKS", "use_parallel", "compile_variants"]

#: Fewest cell walks (segments, or lattice moves) a call must make to run in parallel.
PARALLEL_MIN_WALKS = 20_000


def use_parallel(n_walks: int) -> bool:
    """Whether a kernel call of ``n_walks`` cell walks should use the parallel variant."""
    return n_walks >= PARALLEL_MIN_WALKS and numba.get_num_threads() > 1


def compile_variants(py_func: Callable[..., Any]) -> tuple[Any, Any]:
    """``(serial, parallel)`` numba dispatchers of one Python function using ``numba.prange``.

    The parallel copy gets its own qualified name, so numba's on-disk cache keeps the two
    compilations apart (the cache file is named after the function's qualified name).
    """
    serial = numba.njit(cache=True, nogil=True)(py_func)
    twin = types.FunctionType(py_func.__code__, py_func.__globals__, py_func.__name__ + "_parallel",
                              py_func.__defaults__, py_func.__closure__)
    twin.__qualname__ = py_func.__qualname__ + "_parallel"
    twin.__doc__ = py_func.__doc__
    twin.__module__ = py_func.__module__
    parallel = numba.njit(cache=True, nogil=True, parallel=True)(twin)
    return serial, parallel
