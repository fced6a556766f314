"""Tests of planner.kernels.variants: the parallel variant is picked only for large work."""

from __future__ import annotations

import numba

from planner.kernels import PARALLEL_MIN_WALKS, use_parallel


def test_parallel_only_for_large_work():
    assert not use_parallel(10)
    assert not use_parallel(PARALLEL_MIN_WALKS - 1)
    assert use_parallel(PARALLEL_MIN_WALKS) == (numba.get_num_threads() > 1)
