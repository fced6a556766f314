"""Tests of planner.kernels.arrays: CostArrays, the read-only seam between an EnergyCost and the kernels."""

from __future__ import annotations

import math

import numpy as np
import pytest
from edge_cost_samples import LinearModel, ramp_terrain

from planner import CostSpec


def test_arrays_are_the_read_only_kernel_seam():
    cost = CostSpec(energy_model=LinearModel(), grounds={"asphalt": 1.0}, speed_mps=0.5).build(ramp_terrain())
    arr = cost.arrays
    assert arr.grid == cost.terrain.grid
    assert arr.cells.shape == cost.shape + (3,)
    assert np.array_equal(arr.cells[..., 2] < 0, cost.blocked)
    assert arr.grade_table is cost.tables.grade_table_j_per_m and arr.turn_table is cost.tables.turn_table_j
    for a in (arr.cells, arr.grade_table, arr.turn_table, arr.geo):
        assert not a.flags.writeable
    assert arr.grade_max == pytest.approx(math.tan(cost.max_slope_rad))
