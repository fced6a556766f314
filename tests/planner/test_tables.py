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


# ------------------------------------------------------------------ the stop-turn-go turn table
def test_the_stop_turn_go_rows_are_the_physics_of_the_driven_profile():
    from energy import PhysicsEnergyModel, ground_preset, robot_preset
    from energy.profiles import pivot_commands, waypoint_commands
    from planner import CostSpec
    from planner.tables import STOP_GO_DT_S, stop_turn_go_rows
    from terrain import flat_map

    model = PhysicsEnergyModel(robot_preset("husky"))
    grounds = [ground_preset("asphalt"), ground_preset("sand")]
    rows = stop_turn_go_rows(model, 0.5, grounds, turn_samples=5, turn_rate_radps=0.5)
    assert rows.shape == (2, 5) and rows[0, 0] != rows[1, 0]  # a stop-and-go per ground
    for ground, row in zip(grounds, rows):
        for length in (3.0, 11.5):  # the stop-and-go of any segment that reaches the cruise speed
            p = waypoint_commands([[0.0, 0.0], [length, 0.0]], 0.5, dt_s=STOP_GO_DT_S)
            driven = model.energy_j(p.time_s, p.v_mps, p.omega_radps, ground)
            assert row[0] == pytest.approx(driven - length * float(model.energy_per_metre_j(0.5, 0.0, ground)), abs=0.3)
        for angle, entry in zip(turn_grid(5)[1:], row[1:]):
            p = pivot_commands(angle, turn_rate_radps=0.5, dt_s=STOP_GO_DT_S)
            assert entry - row[0] == pytest.approx(model.energy_j(p.time_s, p.v_mps, p.omega_radps, ground), rel=1e-12)
            assert entry - row[0] > float(model.turn_energy_j(angle, ground)) + 20.0  # the yaw ramps cost more
    cost = CostSpec().build(flat_map((4, 4), 1.0, ground="sand"))  # the physics model's tables are these
    np.testing.assert_allclose(cost.tables.turn_table_j[0, ::16], rows[1], rtol=1e-12)
    with pytest.raises(InvalidParameterError, match="energy_j"):
        stop_turn_go_rows(object(), 0.5, grounds, turn_samples=5, turn_rate_radps=0.5)


def test_a_turn_below_the_collinear_tolerance_is_free_in_the_cost_and_the_kernel():
    from energy.profiles import COLLINEAR_TOL_RAD
    from planner import CostSpec
    from planner.kernels.walk import turn_energy
    from terrain import flat_map

    cost = CostSpec().build(flat_map((10, 10), 1.0, ground="asphalt"))
    stop_go = float(cost.stop_go_at([0])[0])
    for angle, expected in ((0.0, 0.0), (0.5 * COLLINEAR_TOL_RAD, 0.0), (2 * COLLINEAR_TOL_RAD, stop_go)):
        assert float(cost.turn_energy_at([0], [angle])[0]) == pytest.approx(expected, abs=0.01)
        arr = cost.arrays
        xn, yn = 5.0 + 3.0 * math.cos(angle), 5.0 + 3.0 * math.sin(angle)
        assert turn_energy(arr.cells, arr.turn_table, arr.geo, 2.0, 5.0, 5.0, 5.0, xn, yn) == pytest.approx(
            expected, abs=0.01)
    angles, energies = cost.turn_energies_j([[1.5, 1.5], [5.5, 1.5], [5.5, 6.5]])
    assert energies[0] == energies[2] == pytest.approx(stop_go / 2)  # the start from rest, the stop at rest
    assert energies[1] == pytest.approx(float(cost.turn_energy_at([0], [math.pi / 2])[0]))
