"""diagnose -> corrected model -> replan: the corrected model is a normal current model for the planner."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from diagnosis_scenarios import scenario

from energy import diagnose, ground_preset, robot_preset
from energy.diagnosis import FitSettings
from planner import LearnedEnergyModel, plan_route
from planner.registry import CellModelRegistry
from terrain import flat_map


@pytest.fixture(scope="module")
def diagnosed():
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    logs, model = sc.make_logs(0), sc.make_model(0)
    return model, diagnose(model, logs, settings=FitSettings(seed=0, n_bootstrap=50))


def _cost(tmap, model):
    registry = CellModelRegistry.from_terrain(tmap, model, prior_name="model")
    return LearnedEnergyModel(registry, robot_preset("husky"), ground_preset("asphalt")).energy_cost(tmap, speed_mps=0.5)


def test_the_corrected_model_prices_turns_the_given_model_missed(diagnosed) -> None:
    given, diagnosis = diagnosed
    assert diagnosis.current.chosen[:1] == ("turning_resistance",)
    tmap = flat_map((40, 40), 1.0)
    before, after = _cost(tmap, given), _cost(tmap, diagnosis.corrected_model)
    # a model without turning resistance prices every turn (columns: turn angle 0..pi) far
    # below the corrected one; a zero turn costs nothing in both
    assert np.all(before.tables.turn_table_j[..., 0] == 0.0) and np.all(after.tables.turn_table_j[..., 0] == 0.0)
    assert np.all(after.tables.turn_table_j[..., 1:] > 1.5 * before.tables.turn_table_j[..., 1:])
    # and the corrected costs plan: an L-shaped route around a wall now pays for its corner
    wall = np.zeros((40, 40), bool)
    wall[0:30, 20] = True
    walled = flat_map((40, 40), 1.0)
    walled["obstacle"] = wall
    r_before = plan_route(walled, (5.0, 5.0), (35.0, 5.0), cost=_cost(walled, given), planner="lattice")
    r_after = plan_route(walled, (5.0, 5.0), (35.0, 5.0), cost=_cost(walled, diagnosis.corrected_model),
                         planner="lattice")
    assert r_before.status == r_after.status == "exact"
    assert r_after.turn_energy_j.sum() > 1.5 * r_before.turn_energy_j.sum() > 0.0
