"""Tests of planner.cost_source: edge_costs, from the presets or from a saved model."""

from __future__ import annotations

import numpy as np
import pytest

from energy import robot_preset
from terrain import InvalidParameterError

from planner import EnergyCost, model_energy_cost
from planner.cost_source import edge_costs


def test_without_a_model_the_presets_price_the_map(ramp_map):
    cost = edge_costs(ramp_map, robot="jackal", speed_mps=0.8, max_slope_rad=0.3)
    same = EnergyCost.from_presets(ramp_map, robot="jackal", speed_mps=0.8, max_slope_rad=0.3)
    np.testing.assert_array_equal(cost.grade_table_j_per_m, same.grade_table_j_per_m)
    np.testing.assert_array_equal(cost.blocked, same.blocked)


def test_with_a_model_the_model_prices_the_map_and_unknown_ground_does_not_apply(corridor_map, known_model):
    model = known_model()
    cost = edge_costs(corridor_map, model=model, unknown_ground=None)
    same = model_energy_cost(corridor_map, model, robot_preset("husky"), 0.5)
    assert cost.ground_labels == same.ground_labels == ("loam", "gravel") and cost.has_interval
    np.testing.assert_array_equal(cost.grade_table_j_per_m, same.grade_table_j_per_m)


def test_errors_are_those_of_the_pricers(flat_map):
    with pytest.raises(InvalidParameterError):
        edge_costs(flat_map, speed_mps=-1.0)
