"""Tests of planner.kernels: serial and parallel variants agree exactly; the variant is picked by work size."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from planner import EnergyCost
from planner.kernels import PARALLEL_MIN_WALKS, use_parallel
from planner.kernels import graph as graph_kernels
from planner.kernels import walk as walk_kernels
from terrain.procedural import procedural_map


def _cost() -> EnergyCost:
    tmap = procedural_map((30, 36), 1.0, seed=3, grounds=("a", "b"), obstacle_fraction=0.05)
    grades = np.linspace(-0.4, 0.4, 17)
    grade = np.vstack([40.0 + 300.0 * np.maximum(grades, 0.0), 60.0 + 200.0 * np.abs(grades)])
    turn = np.tile(np.linspace(0.0, 30.0, 9), (2, 1))
    return EnergyCost(tmap, np.asarray(tmap.ground), grade, turn, speed_mps=0.5, max_slope_rad=np.arctan(0.4),
                      battery_voltage_v=24.0, turn_rate_radps=0.5)


def test_segment_walk_variants_agree_exactly():
    arr = _cost().arrays
    rng = np.random.default_rng(0)
    xa, xb = rng.uniform(0, 36, (2, 500))
    ya, yb = rng.uniform(0, 30, (2, 500))
    serial = walk_kernels.walk_many_serial(arr.cells, arr.grade_table, arr.geo, xa, ya, xb, yb)
    parallel = walk_kernels.walk_many_parallel(arr.cells, arr.grade_table, arr.geo, xa, ya, xb, yb)
    assert np.array_equal(serial, parallel)
    assert np.isfinite(serial).any() and np.isinf(serial).any()
    one = [walk_kernels.walk_forward(arr.cells, arr.grade_table, arr.geo, *p) for p in zip(xa, ya, xb, yb)]
    assert np.array_equal(serial, one)


def test_lattice_weight_variants_agree_exactly():
    arr = _cost().arrays
    half = np.array([(0, 1), (1, 0), (1, 1), (1, -1), (1, 2), (2, 1), (2, -1), (1, -2)], dtype=np.int64)
    args = (arr.cells, arr.grade_table, arr.geo, 1, 0, 30, 36, half)
    serial = graph_kernels.lattice_weights_serial(*args)
    assert np.array_equal(serial, graph_kernels.lattice_weights_parallel(*args))
    assert np.array_equal(serial, graph_kernels.lattice_weights(*args))


def test_parallel_only_for_large_work():
    assert not use_parallel(10)
    assert not use_parallel(PARALLEL_MIN_WALKS - 1)
    assert use_parallel(PARALLEL_MIN_WALKS) == (numba.get_num_threads() > 1)


@pytest.mark.parametrize("n", [3, 3000])
def test_segment_energy_is_the_same_whichever_variant_runs(n, monkeypatch):
    cost = _cost()
    rng = np.random.default_rng(n)
    a = np.column_stack([rng.uniform(0, 36, n), rng.uniform(0, 30, n)])
    b = np.column_stack([rng.uniform(0, 36, n), rng.uniform(0, 30, n)])
    chosen = cost.segment_energy_j(a, b)
    monkeypatch.setattr(walk_kernels, "use_parallel", lambda n_walks: True)
    assert np.array_equal(chosen, cost.segment_energy_j(a, b))
