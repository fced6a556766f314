"""Tests of planner.tables: the grade and turn grids and their size checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.tables import DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES, check_table_sizes, grade_grid, turn_grid
from terrawatt_base.errors import InvalidParameterError


def test_grade_grid_is_symmetric_with_zero_in_the_middle():
    g = grade_grid(math.atan(0.5), 5)
    np.testing.assert_allclose(g, [-0.5, -0.25, 0.0, 0.25, 0.5])


def test_turn_grid_spans_zero_to_pi():
    np.testing.assert_allclose(turn_grid(3), [0.0, math.pi / 2, math.pi])


def test_table_sizes_are_checked():
    assert check_table_sizes(3, 2) == (3, 2)
    assert check_table_sizes(DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES) == (DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES)
    with pytest.raises(InvalidParameterError, match="grade_samples must be an odd integer >= 3, got 4"):
        check_table_sizes(4, 2)
    with pytest.raises(InvalidParameterError, match="grade_samples"):
        check_table_sizes(1, 2)
    with pytest.raises(InvalidParameterError, match="turn_samples"):
        check_table_sizes(3, 1)


def test_at_quantile_prices_every_entry_at_its_rows_quantile_and_keeps_the_spreads() -> None:
    from energy.models.forecast import predictive_quantile
    from planner import CostTables

    tables = CostTables([[20.0, 10.0, 1.0], [5.0, 5.0, 5.0]], [[0.0, 4.0], [0.0, 2.0]], ("known", "new"),
                        grade_sd_table_j_per_m=[[2.0, 2.0, 2.0], [1.0, 1.0, 1.0]],
                        turn_sd_table_j=[[0.0, 1.0], [0.0, 1.0]], spread_dof=(math.inf, 3.0))
    q90 = tables.at_quantile(0.9)
    z_known, z_new = predictive_quantile(0.9), predictive_quantile(0.9, 3.0)
    np.testing.assert_array_equal(q90.grade_table_j_per_m, [[20 + 2 * z_known, 10 + 2 * z_known, 1 + 2 * z_known],
                                                           [5 + z_new] * 3])
    np.testing.assert_array_equal(q90.turn_table_j, [[0.0, 4 + z_known], [0.0, 2 + z_new]])
    np.testing.assert_array_equal(q90.grade_sd_table_j_per_m, tables.grade_sd_table_j_per_m)
    assert q90.spread_dof == tables.spread_dof and q90.ground_labels == ("known", "new")
    low = tables.at_quantile(0.01)  # floored at 0: an edge never pays back energy
    assert low.grade_table_j_per_m[0, 2] == 0.0 and low.grade_table_j_per_m[0, 0] > 0
    np.testing.assert_array_equal(tables.at_quantile(0.5).grade_table_j_per_m, tables.grade_table_j_per_m)


@pytest.mark.parametrize("q", [0.0, 1.0, 1.5, float("nan"), "high"])
def test_at_quantile_refuses_a_level_outside_the_open_unit_interval(q) -> None:
    from planner import CostTables

    tables = CostTables([[1.0, 1.0, 1.0]], [[0.0, 1.0]], grade_sd_table_j_per_m=[[1.0] * 3], turn_sd_table_j=[[0.0, 1.0]])
    with pytest.raises(InvalidParameterError, match="q"):
        tables.at_quantile(q)


def test_at_quantile_needs_spreads() -> None:
    from planner import CostTables

    with pytest.raises(InvalidParameterError, match="no standard deviations") as err:
        CostTables([[1.0, 1.0, 1.0]], [[0.0, 1.0]]).at_quantile(0.9)
    assert err.value.parameter == "tables"
