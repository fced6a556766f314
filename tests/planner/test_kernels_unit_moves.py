"""Tests of planner.kernels.unit_moves: the stride-1 move kernel equals the general lattice kernel."""

from __future__ import annotations

import numpy as np
import pytest
from reach_samples import one_way_cost

import terrain
from planner.cost_spec import CostSpec


@pytest.mark.parametrize("case", ["hilly", "offset", "steep", "example"])
def test_stride1_move_kernel_equals_the_lattice_kernel(case):
    from planner.kernels import UNIT_HALF, lattice_weights, unit_lattice_weights
    from planner.lattice import LATTICE_OFFSETS

    assert np.array_equal(UNIT_HALF, LATTICE_OFFSETS[:8])
    if case == "hilly":
        cost = CostSpec().build(terrain.procedural_map((45, 52), 1.0, seed=3, n_walls=2, obstacle_fraction=0.05))
    elif case == "offset":  # odd cell size, far origin, steep ground: coordinates do not round like 1 m cells
        tmap = terrain.procedural_map((41, 37), 0.7, seed=5, origin_xy_m=(4321.5, -77.3), slope_deg=15.0, n_walls=1)
        cost = CostSpec().build(tmap)
    elif case == "steep":  # moves undrivable uphill only: one direction inf, the other finite
        cost = one_way_cost(terrain.ramp_map((20, 24), 0.5, grade=0.12), max_uphill_grade=0.1)
    else:
        cost = CostSpec().build(terrain.example_map())
    arr = cost.arrays
    rows, cols = cost.shape
    ref = lattice_weights(arr.cells, arr.grade_table, arr.geo, 1, 0, rows, cols, LATTICE_OFFSETS[:8])
    got = unit_lattice_weights(arr.cells, arr.grade_table, arr.geo, rows, cols)
    assert np.array_equal(np.isinf(got), np.isinf(ref))
    np.testing.assert_allclose(got[np.isfinite(ref)], ref[np.isfinite(ref)], rtol=1e-9)
    if case == "steep":
        one_way = np.isinf(ref[:, :8]) != np.isinf(ref[:, 8:])
        assert one_way.any()
