"""Tests of planner.missions.simulate: apples-to-apples energy, replay, reserve crossing, outputs, bad input."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from simulate_samples import GROUNDS, ROBOT, clean_sim, flat, flat_mission  # noqa: F401  (fixtures)

from energy import Battery, TruthSimulator, ground_preset
from planner import simulate_mission
from planner.cost_spec import CostSpec
from planner.missions import MissionAccounting, MissionDrive
from planner.route import evaluate_route
from terrain import (
    DataError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    UnknownNameError,
    flat_map,
    ramp_map,
)


def test_flat_mission_matches_planner_prediction(flat_mission):
    route, res = flat_mission
    b = res.budget
    assert res.status == "completed" and res.source == "truth" and b.feasible and res.forecast == "edges"
    assert b.predicted_energy_j == pytest.approx(route.energy_j, rel=1e-12)
    # The edges price the stop-turn-go drive (its ramps, the electronics' extra seconds, the control start-up)
    assert abs(b.error_pct) < 0.5
    expected = route.segment_energy_j + route.turn_energy_j[:-1]
    expected[-1] += route.turn_energy_j[-1]  # the stop at the last waypoint
    np.testing.assert_allclose(b.segment_predicted_j, expected)
    assert np.all(np.abs(b.segment_error_pct) < 2.0)
    assert b.segment_actual_j.sum() == pytest.approx(b.actual_energy_j, rel=1e-12)
    # the log's currents, turned into battery power, reproduce the simulator's own battery energy
    assert res.budget.actual_energy_j == pytest.approx(res.truth_energy_j, rel=2e-3)
    # series bookkeeping
    assert np.all(np.diff(res.soc) <= 0) and res.soc[0] == 1.0
    assert res.energy_wh[-1] * 3600.0 == pytest.approx(b.actual_energy_j)
    assert res.charge_mah[-1] == pytest.approx(b.actual_energy_j / 24.0 / 3.6)
    assert res.predicted_energy_wh[-1] * 3600.0 == pytest.approx(b.predicted_energy_j)
    assert np.all(np.diff(res.predicted_energy_wh) >= 0)
    assert np.all(np.diff(res.segment_index) >= 0) and set(np.unique(res.segment_index)) == {0, 1}
    assert res.x_m[-1] == pytest.approx(35.5) and res.y_m[-1] == pytest.approx(25.5)
    assert b.arrival_soc == pytest.approx(1.0 - b.actual_energy_j / (20.0 * 24.0 * 3600.0))


def test_the_default_forecast_prices_the_driven_profile(flat, flat_mission, clean_sim):
    # The physics model that priced the cost, over the whole stop-turn-go profile: the noise-free
    # truth (same physics, velocity lag aside) is met within 0.5 %, segment by segment within 1 %; the
    # edge forecast prices the same drive (the ramps, the pivots' yaw ramps, the electronics' extra seconds).
    tmap, cost = flat
    route, edges = flat_mission
    res = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost)
    b = res.budget
    assert res.forecast == "profile" and res.to_dict()["forecast"] == "profile"
    assert abs(b.error_pct) < 0.5 and abs(edges.budget.error_pct) < 0.5
    assert np.all(np.abs(b.segment_error_pct) < 1.0)
    assert b.predicted_energy_j == pytest.approx(route.energy_j, rel=0.005)  # the edges price the profile
    assert b.actual_energy_j == edges.budget.actual_energy_j  # the same drive
    # without a cost there is no physics model to price the profile with
    alone = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim)
    assert alone.forecast == "edges" and alone.budget.predicted_energy_j == pytest.approx(route.energy_j)
    with pytest.raises(InvalidParameterError, match="forecast='profile' needs a cost"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim,
                         accounting=MissionAccounting(forecast="profile"))
    with pytest.raises(UnknownNameError, match="forecast"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                         accounting=MissionAccounting(forecast="magic"))


def test_a_noise_free_mission_books_the_physics_energy_of_its_driven_profile(flat, flat_mission):
    # The bookkeeping rule: the simulator's noise changes what is logged, never what the battery pays.
    # Noise-free, the logged currents give back the truth's battery energy; with the default noise
    # (rest offset 0.59 A per side, gains, white noise, quantisation, clipping) the energy moves by
    # under 1 %, not by the offset's back-EMF power.
    tmap, cost = flat
    route, clean = flat_mission
    assert clean.budget.actual_energy_j == pytest.approx(clean.truth_energy_j, rel=2e-3)
    noisy_sim = TruthSimulator(ROBOT, GROUNDS, velocity_time_constant_s=0.0, current_rate_hz=50.0, seed=0)
    assert noisy_sim.noise.current_offset_a == 0.59
    noisy = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=noisy_sim, cost=cost)
    assert noisy.budget.actual_energy_j == pytest.approx(clean.budget.actual_energy_j, rel=0.01)
    assert noisy.truth_energy_j == pytest.approx(clean.truth_energy_j, rel=1e-12)
    # booked as drawn current, the offset would cost several per cent more
    paid = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=noisy_sim, cost=cost,
                            accounting=MissionAccounting(current_offset_a=0.0))
    assert paid.budget.actual_energy_j > 1.03 * clean.budget.actual_energy_j


def test_ramp_up_and_down_match_prediction(clean_sim):
    tmap = ramp_map((12, 30), 1.0, grade=0.1)
    cost = CostSpec(robot=ROBOT, grounds=GROUNDS, speed_mps=0.5).build(tmap)
    up = simulate_mission(tmap, evaluate_route(cost, [[2.5, 5.5], [27.5, 5.5]]), ROBOT, Battery(20.0, 24.0),
                          truth=clean_sim, cost=cost)
    down = simulate_mission(tmap, evaluate_route(cost, [[27.5, 5.5], [2.5, 5.5]]), ROBOT, Battery(20.0, 24.0),
                            truth=clean_sim, cost=cost)
    assert up.budget.actual_energy_j > 1.5 * down.budget.actual_energy_j
    assert abs(up.budget.error_pct) < 3.0 and abs(down.budget.error_pct) < 3.0


def test_speed_recovered_from_route_without_cost(flat, flat_mission, clean_sim):
    tmap, cost = flat
    route, res = flat_mission
    alone = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim)
    assert alone.speed_mps == pytest.approx(cost.speed_mps, rel=1e-9)
    assert alone.budget.actual_energy_j == pytest.approx(res.budget.actual_energy_j, rel=1e-9)


def test_replay_of_log_gives_same_budget(flat, flat_mission):
    tmap, cost = flat
    route, res = flat_mission
    # the clean simulator's sensor has no rest offset; a replayed log is booked with the one given
    replay = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=res.log, cost=cost,
                              accounting=MissionAccounting(current_offset_a=0.0))
    assert replay.source == "replay" and math.isnan(replay.truth_energy_j)
    np.testing.assert_array_equal(replay.segment_index, res.segment_index)
    assert replay.budget.actual_energy_j == res.budget.actual_energy_j
    np.testing.assert_allclose(replay.budget.segment_actual_j, res.budget.segment_actual_j)
    # without a pose the log is mapped by the velocity profile's timing
    blind = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0),
                             truth=dataclasses.replace(res.log, pose_xyh=None), cost=cost,
                             accounting=MissionAccounting(current_offset_a=0.0))
    np.testing.assert_array_equal(blind.segment_index, res.segment_index)
    np.testing.assert_allclose(blind.x_m, res.x_m, atol=1e-9)
    assert blind.budget.actual_energy_j == pytest.approx(res.budget.actual_energy_j)


def test_repeated_waypoint_segment_is_empty(flat, clean_sim):
    tmap, cost = flat
    route = evaluate_route(cost, [[2.5, 2.5], [10.5, 2.5], [10.5, 2.5], [10.5, 12.5]])
    res = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                           accounting=MissionAccounting(forecast="edges"))
    assert res.budget.segment_predicted_j[1] == 0.0 and res.budget.segment_actual_j[1] == 0.0
    assert set(np.unique(res.segment_index)) == {0, 2}
    assert res.budget.segment_predicted_j[2] == pytest.approx(route.segment_energy_j[2] + route.turn_energy_j[2]
                                                              + route.turn_energy_j[3])  # the last: the stop too


def test_a_collinear_waypoint_is_driven_through_and_booked_with_the_segment_before_it(flat, clean_sim):
    tmap, cost = flat
    route = evaluate_route(cost, [[2.5, 2.5], [10.5, 2.5], [20.5, 2.5], [20.5, 12.5]])
    res = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                           accounting=MissionAccounting(forecast="edges"))
    assert route.turn_energy_j[1] == 0.0 and set(np.unique(res.segment_index)) == {0, 2}  # no stop at (10.5, 2.5)
    assert res.budget.segment_predicted_j[1] == 0.0 and res.budget.segment_actual_j[1] == 0.0
    assert res.budget.segment_predicted_j[0] == pytest.approx(route.segment_energy_j[:2].sum() + route.turn_energy_j[0])
    assert abs(res.budget.error_pct) < 0.5
    straight = simulate_mission(tmap, evaluate_route(cost, [[2.5, 2.5], [20.5, 2.5], [20.5, 12.5]]), ROBOT,
                                Battery(20.0, 24.0), truth=clean_sim, cost=cost)
    assert res.budget.actual_energy_j == pytest.approx(straight.budget.actual_energy_j, rel=1e-9)  # the same drive


def test_a_waypoint_of_drive_stops_is_stopped_at_though_collinear(flat, clean_sim):
    """A stop the drive names (a tour's site) survives the collinear rule: the robot stops and goes again there, the
    drive takes the stop-and-go's time longer, the profile forecast prices it and the segments split there."""
    tmap, cost = flat
    route = evaluate_route(cost, [[2.5, 2.5], [10.5, 2.5], [20.5, 2.5], [20.5, 12.5]])
    through = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost)
    stopped = simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                               drive=MissionDrive(stops=(1,)))
    assert set(np.unique(through.segment_index)) == {0, 2} and set(np.unique(stopped.segment_index)) == {0, 1, 2}
    v = np.interp(10.5, stopped.x_m[stopped.y_m < 3.0], stopped.v_mps[stopped.y_m < 3.0])
    assert v == pytest.approx(0.0, abs=0.05)  # at rest at (10.5, 2.5)
    ramp_s = stopped.speed_mps / stopped.accel_mps2  # a stop-and-go adds speed / accel to a straight
    assert stopped.budget.duration_s - through.budget.duration_s == pytest.approx(ramp_s, abs=0.1)
    extra = stopped.budget.actual_energy_j - through.budget.actual_energy_j
    assert extra > 0 and stopped.budget.predicted_energy_j - through.budget.predicted_energy_j == pytest.approx(extra, rel=0.1)
    with pytest.raises(InvalidParameterError, match="drive.stops must be indices of the route's 4 waypoints"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, drive=MissionDrive(stops=(4,)))
    with pytest.raises(InvalidParameterError, match="stops must be >= 0"):
        MissionDrive(stops=(-1,))
    with pytest.raises(InvalidParameterError, match="stops must be waypoint indices"):
        MissionDrive(stops=3)


def test_infeasible_mission_reports_crossing(flat, flat_mission, clean_sim):
    tmap, cost = flat
    route, full = flat_mission
    # A battery whose reserve is reached 70 % of the way through the energy.
    actual_ah = full.budget.actual_energy_j / 24.0 / 3600.0
    battery = Battery(capacity_ah=actual_ah * 0.7 / 0.75, voltage_v=24.0, min_reserve_pct=25.0)
    res = simulate_mission(tmap, route, ROBOT, battery, truth=clean_sim, cost=cost)
    assert res.status == "reserve_violated" and not res.feasible
    k = res.budget.reserve_crossed_index
    assert res.soc[k] < 0.25 <= res.soc[k - 1]
    tc = res.reserve_crossed_time_s
    assert res.time_s[k - 1] <= tc <= res.time_s[k]
    # the crossing is where 70 % of the actual energy has been used
    assert np.interp(tc, res.time_s, res.energy_wh) == pytest.approx(0.7 * res.energy_wh[-1], rel=1e-3)
    x, y = res.reserve_crossed_xy_m
    seg = res.reserve_crossed_segment
    assert seg == res.segment_index[k - 1]
    a, b = route.waypoints_m[seg], route.waypoints_m[seg + 1]
    assert abs((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) < 1e-6  # on the segment's line
    assert res.budget.reserve_margin_pct < 0

    stopped = simulate_mission(tmap, route, ROBOT, battery, truth=clean_sim, cost=cost,
                               drive=MissionDrive(stop_at_reserve=True))
    assert stopped.status == "reserve_violated" and stopped.n_samples == k + 1
    assert stopped.soc[-1] < 0.25 and stopped.reserve_crossed_time_s == pytest.approx(tc)
    # the aborted budget covers the part driven, so its error stays small
    assert stopped.budget.predicted_energy_j < full.budget.predicted_energy_j
    assert abs(stopped.budget.error_pct) < 4.0
    assert stopped.log.time_s[-1] == pytest.approx(stopped.time_s[-1] + full.log.time_s[0])


def test_a_battery_that_runs_out_says_where_and_never_goes_below_zero(flat, flat_mission, clean_sim):
    tmap, cost = flat
    route, full = flat_mission
    tiny = Battery(capacity_ah=0.0001, voltage_v=24.0)  # 0.1 mAh: empty within seconds
    res = simulate_mission(tmap, route, ROBOT, tiny, truth=clean_sim, cost=cost)
    assert res.status == "reserve_violated" and not res.feasible
    assert res.soc.min() >= 0.0 and res.budget.arrival_soc == 0.0
    assert res.depleted_time_s is not None and res.depleted_time_s == res.budget.depleted_time_s
    assert res.time_s[0] <= res.depleted_time_s < res.time_s[-1]
    x, y = res.depleted_xy_m
    assert (x, y) == pytest.approx((np.interp(res.depleted_time_s, res.time_s, res.x_m),
                                    np.interp(res.depleted_time_s, res.time_s, res.y_m)))
    data = res.to_dict(series_every=50)
    assert data["depletion"] == {"time_s": res.depleted_time_s, "xy_m": [x, y]}
    assert "depleted_time_s=" in repr(res)
    printed = res.summary()
    assert printed.startswith("mission reserve_violated (truth)") and "below the reserve" in printed
    assert f"the battery ran out {res.depleted_time_s:.1f} s in" in printed and "ran out" not in full.summary()
    assert full.depleted_time_s is None and full.to_dict(series_every=50)["depletion"] is None


def test_a_route_whose_start_equals_its_goal_is_refused(flat, clean_sim):
    tmap, cost = flat
    route = evaluate_route(cost, [[5.5, 5.5], [5.5, 5.5]])
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost)


def test_a_string_where_a_number_is_expected_names_the_parameter(flat, flat_mission, clean_sim):
    tmap, cost = flat
    route, _ = flat_mission
    with pytest.raises(InvalidParameterError, match="speed_mps must be a real number, got 'fast'"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                         drive=MissionDrive(speed_mps="fast"))
    with pytest.raises(InvalidParameterError, match="stop_at_reserve must be True or False"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=cost,
                         drive=MissionDrive(stop_at_reserve="no"))


def test_log_shorter_than_route_raises(flat, flat_mission):
    tmap, cost = flat
    route, res = flat_mission
    half = res.log.slice(res.log.time_s[0], res.log.time_s[len(res.log) // 2])
    with pytest.raises(DataError, match="from the route's goal"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=half, cost=cost)
    with pytest.raises(DataError, match="expected a log of the whole route"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0),
                         truth=dataclasses.replace(half, pose_xyh=None), cost=cost)


def test_bad_inputs(flat, flat_mission, clean_sim):
    tmap, cost = flat
    route, res = flat_mission
    small = flat_map((10, 10), 1.0)
    with pytest.raises(OutOfBoundsError, match="outside the map bounds"):
        simulate_mission(small, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim)
    with pytest.raises(InvalidParameterError, match="capacity_ah must be > 0"):
        simulate_mission(tmap, route, ROBOT, Battery(0.0, 24.0), truth=clean_sim)
    with pytest.raises(InvalidParameterError, match="battery must be a Battery"):
        simulate_mission(tmap, route, ROBOT, 20.0, truth=clean_sim)
    with pytest.raises(InvalidParameterError, match="truth must be a TruthSimulator or an InteractionLog"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth="log.csv")
    with pytest.raises(UnknownNameError, match="current_convention must be one of"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=res.log,
                         accounting=MissionAccounting(current_convention="duty"))
    with pytest.raises(InvalidParameterError, match="accel_mps2 must be > 0"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, drive=MissionDrive(accel_mps2=0.0))
    other = CostSpec(robot=ROBOT, grounds=GROUNDS, speed_mps=0.5).build(flat_map((30, 41), 1.0))
    with pytest.raises(GridMismatchError, match="cost was built on a grid"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, cost=other)


def test_diagnosing_mission_logs_names_what_the_truth_does_differently():
    # Missions on one ground, driven by the default truth (noise, the sensor's rest offset, and a 0.1 s
    # velocity lag behind the commanded speeds the log records), diagnosed against the planning physics
    # as given: the lag is named first and fitted near 0.1 s; the flat map's slope is credited nothing.
    from energy import PhysicsCurrentModel, diagnose
    from energy.diagnosis import FitSettings

    tmap = flat_map((60, 60), 1.0, ground="grass")
    grass = {"grass": ground_preset("grass")}
    cost = CostSpec(speed_mps=0.5).build(tmap)
    logs = []
    for k, wp in enumerate(([[5.5, 5.5], [30.5, 5.5], [45.5, 30.5]], [[50.5, 8.5], [10.5, 40.5], [40.5, 55.5]],
                            [[8.5, 30.5], [30.5, 30.5], [55.5, 55.5]])):
        sim = TruthSimulator(ROBOT, grass, current_rate_hz=50.0, seed=k)
        logs.append(simulate_mission(tmap, evaluate_route(cost, wp), ROBOT, Battery(20.0, 24.0), truth=sim,
                                     cost=cost).log)
    model = PhysicsCurrentModel("husky", "grass", fit_parameters=()).fit(logs)
    d = diagnose(model, logs, terrain=tmap, settings=FitSettings(seed=0, n_bootstrap=50))
    assert d.current.chosen[0] == "time_lag"
    assert d.current.score("time_lag").parameters["lag_s"] == pytest.approx(0.1, abs=0.03)
    assert "slope" not in d.current.chosen


def test_diagnosing_example_map_missions_against_the_planning_physics_names_the_lag():
    # Missions on the bundled example map (grass and asphalt, hills), driven by the default truth,
    # diagnosed against the physics the planner priced them with: the presets of each cell's ground
    # (a ground per label) and the slope under the poses (the map). What the truth does differently
    # is its 0.1 s velocity lag (and the sensor's rest offset, which both carry): the lag is named,
    # alone, near 0.1 s. A lag shows in transients: the missions drive the heading-free lattice's routes,
    # which pivot at many waypoints (the turn-aware planner's routes are nearly straight here and leave
    # too few transients to size the lag: 0.027 s from six of them).
    from energy import PhysicsCurrentModel, diagnose
    from energy.diagnosis import FitSettings
    from planner import Lattice
    from terrain import example_map

    tmap = example_map()
    cost = CostSpec(speed_mps=0.5).build(tmap)
    grounds = {g: ground_preset(g) for g in tmap.ground_names.values()}
    logs = []
    for k, (start, goal) in enumerate((((10, 10), (40, 70)), ((30, 20), (80, 60)), ((5, 60), (62, 36))) * 2):
        route = evaluate_route(cost, Lattice.for_cost(cost, 1).shortest_path(start, goal).waypoints_m)
        sim = TruthSimulator(ROBOT, grounds, current_rate_hz=50.0, seed=k)
        logs.append(simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=sim, cost=cost).log)
    driven = sorted({str(g) for log in logs for g in np.unique(log.ground)})
    assert driven == ["asphalt", "grass"]
    planning = PhysicsCurrentModel(ROBOT, {g: g for g in driven}, fit_parameters=(), terrain=tmap).fit(logs)
    d = diagnose(planning, logs, terrain=tmap, settings=FitSettings(seed=0, n_bootstrap=50))
    assert d.current.chosen == ("time_lag",)
    assert d.current.score("time_lag").parameters["lag_s"] == pytest.approx(0.1, abs=0.03)


def test_drive_and_accounting_are_checked_values(flat, flat_mission, clean_sim):
    tmap, cost = flat
    route, _ = flat_mission
    with pytest.raises(InvalidParameterError, match="drive must be a MissionDrive"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, drive={"speed_mps": 0.5})
    with pytest.raises(InvalidParameterError, match="accounting must be a MissionAccounting"):
        simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=clean_sim, accounting="edges")
    with pytest.raises(InvalidParameterError, match="current_offset_a must be >= 0"):
        MissionAccounting(current_offset_a=-0.1)
    with pytest.raises(InvalidParameterError, match="waypoint_tolerance_m must be >= 0"):
        MissionDrive(waypoint_tolerance_m=-1.0)
