"""Tests of planner.kernels.walk: serial and parallel segment walks agree exactly, whichever variant runs."""

from __future__ import annotations

import numpy as np
import pytest
from kernel_samples import kernel_cost

from planner.kernels import walk as walk_kernels


def test_segment_walk_variants_agree_exactly():
    arr = kernel_cost().arrays
    rng = np.random.default_rng(0)
    xa, xb = rng.uniform(0, 36, (2, 500))
    ya, yb = rng.uniform(0, 30, (2, 500))
    serial = walk_kernels.walk_many_serial(arr.cells, arr.grade_table, arr.geo, xa, ya, xb, yb)
    parallel = walk_kernels.walk_many_parallel(arr.cells, arr.grade_table, arr.geo, xa, ya, xb, yb)
    assert np.array_equal(serial, parallel)
    assert np.isfinite(serial).any() and np.isinf(serial).any()
    one = [walk_kernels.walk_forward(arr.cells, arr.grade_table, arr.geo, *p) for p in zip(xa, ya, xb, yb)]
    assert np.array_equal(serial, one)


@pytest.mark.parametrize("n", [3, 3000])
def test_segment_energy_is_the_same_whichever_variant_runs(n, monkeypatch):
    cost = kernel_cost()
    rng = np.random.default_rng(n)
    a = np.column_stack([rng.uniform(0, 36, n), rng.uniform(0, 30, n)])
    b = np.column_stack([rng.uniform(0, 36, n), rng.uniform(0, 30, n)])
    chosen = cost.segment_energy_j(a, b)
    monkeypatch.setattr(walk_kernels, "use_parallel", lambda n_walks: True)
    assert np.array_equal(chosen, cost.segment_energy_j(a, b))
