"""Tests of planner.missions.forecast: segment energies of a power profile, a route's forecast energy."""

from __future__ import annotations

import numpy as np
from planner import EnergyCost
from planner.missions.forecast import route_forecast_j, segment_forecasts_j
from planner.route import evaluate_route
from terrain import flat_map


def test_segment_energies_integrate_the_power_between_the_planned_marks():
    t = np.linspace(10.0, 16.0, 601)  # the profile's clock need not start at 0
    power = t - 10.0  # W: a ramp, so each part is a difference of squares / 2
    turn, straight = segment_forecasts_j(t, power, np.array([1.0, 1.0]), np.array([2.0, 2.0]))
    np.testing.assert_allclose(turn, [0.5, (16.0 - 9.0) / 2], rtol=1e-9)
    np.testing.assert_allclose(straight, [(9.0 - 1.0) / 2, (36.0 - 16.0) / 2], rtol=1e-9)


def test_a_longer_route_and_a_turn_cost_more():
    cost = EnergyCost.from_presets(flat_map((20, 40), 1.0, ground="asphalt"), speed_mps=0.5)
    short = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [12.5, 5.5]]))
    long = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [32.5, 5.5]]))
    assert 0.0 < short < long
    straight_25 = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [27.5, 5.5]]))
    bent_25 = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [17.5, 5.5], [17.5, 15.5]]))
    assert bent_25 > straight_25  # the same 25 m with a stop-turn-go corner
