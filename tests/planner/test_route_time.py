"""A route's time as the robot drives it (planner.route_time): the stop-turn-go profile's, what the simulator lasts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import Battery, NoiseModel, TruthSimulator, ground_preset, robot_preset
from planner import CostSpec, simulate_mission
from planner.missions import MissionAccounting
from planner.route import evaluate_route
from planner.route_time import route_duration_s, waypoint_times_s
from terrain import flat_map
from terrawatt_base.errors import InvalidParameterError

ROBOT = robot_preset("husky")
GROUNDS = {"asphalt": ground_preset("asphalt")}
ROUTES = {
    "L": [[2.5, 2.5], [35.5, 2.5], [35.5, 25.5]],
    # collinear vertices (driven through), a slant, a 0.3 m hop too short to reach the cruise speed, a U-turn-ish
    "zigzag": [[2.5, 2.5], [10.5, 2.5], [20.5, 2.5], [20.5, 12.5], [30.5, 22.5], [30.5, 22.8], [5.5, 22.8]],
    "hops": [[2.5, 2.5], [3.0, 2.5], [3.0, 3.0], [3.3, 3.4], [10.5, 3.4], [10.5, 20.5], [2.5, 20.5]],
}


@pytest.mark.parametrize("name", sorted(ROUTES))
def test_a_routes_duration_is_the_simulators_driven_time(name):
    tmap = flat_map((30, 40), 1.0)
    cost = CostSpec(robot=ROBOT, grounds=GROUNDS, speed_mps=0.5).build(tmap)
    truth = TruthSimulator(ROBOT, GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=0.0,
                           current_rate_hz=50.0, seed=0)
    route = evaluate_route(cost, ROUTES[name])
    mission = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=truth, cost=cost,
                               accounting=MissionAccounting(forecast="edges"))
    t = np.asarray(mission.time_s)
    # the log ends at the first sample at or after the profile's end: within one sample (1 / 50 Hz)
    assert 0.0 <= (t[-1] - t[0]) - route.duration_s <= 0.02 + 1e-9


def test_ramps_and_pivots_are_counted_in_closed_form():
    # 4 m at 1 m/s with 0.5 m/s^2: 4 s cruising + 2 s of ramps; a triangular 0.5 m hop: 2 sqrt(0.5 / 0.5) = 2 s
    assert route_duration_s([[0, 0], [4, 0]], 1.0, 0.5) == pytest.approx(6.0)
    assert route_duration_s([[0, 0], [0.5, 0]], 1.0, 0.5) == pytest.approx(2.0)
    # a U-turn pivot at 0.5 rad/s with 1 rad/s^2: pi / 0.5 + 0.5 s; the straights' ramps as above
    assert route_duration_s([[0, 0], [4, 0], [0, 0]], 1.0, 0.5) == pytest.approx(12.0 + 2 * math.pi + 0.5)
    # a start heading turns first
    assert route_duration_s([[0, 0], [4, 0]], 1.0, 0.5, start_heading_rad=math.pi / 2) == pytest.approx(
        6.0 + math.pi + 0.5)


def test_waypoint_times_leave_after_the_pivot_and_pass_through_collinear_ones():
    times = waypoint_times_s([[0, 0], [2, 0], [4, 0], [4, 4]], 1.0, 0.5)
    # ramp 1 m in 2 s, then 1 m at 1 m/s: passes (2, 0) at 3 s; arrives at (4, 0) at 6 s, pivots a quarter turn
    np.testing.assert_allclose(times, [0.0, 3.0, 6.0 + math.pi + 0.5, 12.0 + math.pi + 0.5])
    assert times[-1] == route_duration_s([[0, 0], [2, 0], [4, 0], [4, 4]], 1.0, 0.5)


def test_bad_speeds_and_routes_raise():
    with pytest.raises(InvalidParameterError, match="speed_mps"):
        route_duration_s([[0, 0], [1, 0]], 0.0, 0.5)
    with pytest.raises(InvalidParameterError, match="turn_rate_radps"):
        waypoint_times_s([[0, 0], [1, 0]], 1.0, -1.0)
    with pytest.raises(InvalidParameterError, match="shape"):
        route_duration_s([[1, 1]], 1.0, 0.5)
    assert route_duration_s([[1, 1], [1, 1]], 1.0, 0.5) == 0.0  # start equals goal: it does not move
