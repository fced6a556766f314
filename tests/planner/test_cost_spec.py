"""Tests of planner.cost_spec: CostSpec, one immutable value pricing a map from the presets or from a saved model."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from energy import robot_preset
from planner.cost_spec import CostSpec, PlanModel
from planner.model_cost import model_energy_cost
from terrain import InvalidParameterError, UnknownNameError


def test_without_a_model_the_presets_price_the_map(ramp_map):
    spec = CostSpec(robot="jackal", speed_mps=0.8, max_slope_deg=math.degrees(0.3))
    cost = spec.build(ramp_map)
    same = CostSpec(robot="jackal", speed_mps=0.8, max_slope_deg=math.degrees(0.3)).build(ramp_map)
    np.testing.assert_array_equal(cost.tables.grade_table_j_per_m, same.tables.grade_table_j_per_m)
    np.testing.assert_array_equal(cost.blocked, same.blocked)
    assert spec.plan_model(cost) is None and spec.at_risk(cost) is cost and spec.model_name == "the physics model"


def test_with_a_model_the_model_prices_the_map_and_unknown_ground_does_not_apply(corridor_map, known_model):
    model = known_model()
    spec = CostSpec(model=model, model_label="m.tw")
    cost = spec.build(corridor_map)
    same = model_energy_cost(corridor_map, model, robot_preset("husky"), 0.5)
    assert cost.tables.ground_labels == same.tables.ground_labels == ("loam", "gravel") and cost.has_interval
    np.testing.assert_array_equal(cost.tables.grade_table_j_per_m, same.tables.grade_table_j_per_m)
    assert spec.preset_unknown_ground is None and spec.model_name == "m.tw"
    assert spec.plan_model(cost) == PlanModel(file="m.tw", class_name=type(model).__name__, model_ground=None,
                                              grounds=("loam", "gravel"), gives_interval=True, risk_q=None)


def test_at_risk_prices_every_edge_at_the_quantile_of_its_tables(corridor_map, known_model):
    spec = CostSpec(model=known_model(), risk=0.9)
    mean = spec.build(corridor_map)
    risky = spec.at_risk(mean)
    np.testing.assert_array_equal(risky.tables.grade_table_j_per_m, mean.tables.at_quantile(0.9).grade_table_j_per_m)
    np.testing.assert_array_equal(risky.tables.grade_sd_table_j_per_m, mean.tables.grade_sd_table_j_per_m)  # kept
    assert (risky.tables.grade_table_j_per_m >= mean.tables.grade_table_j_per_m).all()
    assert spec.plan_model(mean).risk_q == 0.9 and dataclasses.replace(spec, risk=None).plan_model(mean).risk_q is None


def test_risk_without_an_interval_names_the_parameter(flat_map):
    spec = CostSpec(risk=0.9)
    with pytest.raises(InvalidParameterError, match="risk 0.9 needs a model with a predictive interval") as err:
        spec.at_risk(spec.build(flat_map))
    assert err.value.parameter == "risk"
    with pytest.raises(InvalidParameterError, match="risk and draw_from model need") as err:
        spec.needs_interval(spec.build(flat_map), also="draw_from")
    assert err.value.parameter == ("risk", "draw_from")


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"speed_mps": -1.0}, "speed_mps"),
    ({"speed_mps": "fast"}, "speed_mps"),
    ({"max_slope_deg": 90.0}, "max_slope_deg"),
    ({"max_slope_deg": float("nan")}, "max_slope_deg"),
    ({"risk": 0.2}, "risk"),
    ({"risk": 1.0}, "risk"),
])
def test_bad_values_are_refused_when_the_spec_is_made(kwargs, name):
    with pytest.raises(InvalidParameterError, match=name) as err:
        CostSpec(**kwargs)
    assert err.value.parameter == name


def test_a_spec_is_immutable_and_errors_of_the_pricers_pass_through(flat_map):
    spec = CostSpec()
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.speed_mps = 1.0  # type: ignore[misc]
    with pytest.raises(UnknownNameError, match="lava"):
        CostSpec(unknown_ground="lava").build(flat_map)


def test_given_is_the_default_for_none_the_spec_itself_else_an_error_naming_pricing():
    spec = CostSpec(speed_mps=0.5)
    assert CostSpec.given(None) == CostSpec() and CostSpec.given(spec) is spec
    with pytest.raises(InvalidParameterError, match="pricing must be a CostSpec") as info:
        CostSpec.given({"speed_mps": 0.5})
    assert info.value.parameter == "pricing"
