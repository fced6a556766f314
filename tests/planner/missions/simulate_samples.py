"""A flat map priced by the physics model, a noise-free truth and one mission on an L route, shared by the mission tests."""

from __future__ import annotations

import pytest

from energy import Battery, NoiseModel, TruthSimulator, ground_preset, robot_preset
from planner import CostSpec, simulate_mission
from planner.missions import MissionAccounting
from planner.route import evaluate_route
from terrain import flat_map

ROBOT = robot_preset("husky")
GROUNDS = {"asphalt": ground_preset("asphalt")}
L_ROUTE = [[2.5, 2.5], [35.5, 2.5], [35.5, 25.5]]


@pytest.fixture(scope="module")
def flat():
    tmap = flat_map((30, 40), 1.0)
    cost = CostSpec(robot=ROBOT, grounds=GROUNDS, speed_mps=0.5).build(tmap)
    return tmap, cost


@pytest.fixture(scope="module")
def clean_sim():
    # Noise off and parameters equal to the planner's model: the apples-to-apples truth.
    return TruthSimulator(ROBOT, GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=0.0,
                          current_rate_hz=50.0, seed=0)


@pytest.fixture(scope="module")
def flat_mission(flat, clean_sim):
    tmap, cost = flat
    route = evaluate_route(cost, L_ROUTE)
    return route, simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                                   accounting=MissionAccounting(forecast="edges"))
