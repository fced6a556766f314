"""Tests of planner.route_price: price_route, the one door to a route's price; segment energies of a power profile,
a route's forecast energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import drive_profile
from energy.models.forecast import predictive_quantile
from planner import CostTables, RouteEnergyInterval, price_route
from planner.cost_spec import CostSpec
from planner.learned_table import TableProbe
from planner.route import evaluate_route
from planner.route_price import FORECAST_DT_S, profile_forecast_w, segment_forecasts_j
from terrain import InvalidParameterError, UnknownNameError, flat_map


def test_segment_energies_integrate_the_power_between_the_planned_marks():
    t = np.linspace(10.0, 16.0, 601)  # the profile's clock need not start at 0
    power = t - 10.0  # W: a ramp, so each part is a difference of squares / 2
    turn, straight = segment_forecasts_j(t, power, np.array([1.0, 1.0]), np.array([2.0, 2.0]))
    np.testing.assert_allclose(turn, [0.5, (16.0 - 9.0) / 2], rtol=1e-9)
    np.testing.assert_allclose(straight, [(9.0 - 1.0) / 2, (36.0 - 16.0) / 2], rtol=1e-9)


def route_forecast_j(cost, route, speed_mps=None):
    """The route's stop-turn-go drive priced by the cost's physics model."""
    return price_route(cost, route, how="profile", speed_mps=speed_mps).mean_j


def test_a_longer_route_and_a_turn_cost_more():
    cost = CostSpec(speed_mps=0.5).build(flat_map((20, 40), 1.0, ground="asphalt"))
    short = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [12.5, 5.5]]))
    long = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [32.5, 5.5]]))
    assert 0.0 < short < long
    straight_25 = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [27.5, 5.5]]))
    bent_25 = route_forecast_j(cost, evaluate_route(cost, [[2.5, 5.5], [17.5, 5.5], [17.5, 15.5]]))
    assert bent_25 > straight_25  # the same 25 m with a stop-turn-go corner


def _learned_cost():
    """A map priced by a learned model (constant currents per cell model) and the model itself."""
    from energy import ground_preset, robot_preset
    from planner import LearnedEnergyModel
    from planner.registry import CellModelRegistry
    from tests.planner.test_learned_cost import ConstModel

    tmap = flat_map((12, 16), 1.0, ground="asphalt")
    reg = CellModelRegistry.from_terrain(tmap, ConstModel(2.0, 5.0), prior_name="a")
    lem = LearnedEnergyModel(reg, robot_preset("husky"), ground_preset("asphalt"),
                             probe=TableProbe((0.25, 0.5, 1.0), (0.5, 1.0)))
    return tmap, lem, lem.energy_cost(tmap, 0.5)


WAYPOINTS = [[1.5, 1.5], [10.5, 1.5], [10.5, 8.5]]


def test_price_route_reads_the_edges_or_the_profile_of_the_model_that_priced_the_map():
    cost = CostSpec(speed_mps=0.5).build(flat_map((12, 16), 1.0, ground="asphalt"))
    edges = price_route(cost, WAYPOINTS)
    assert edges.mean_j == cost.path_energy_j(np.array(WAYPOINTS)) and edges.sd_j == 0.0
    assert edges.mean_j == price_route(cost, evaluate_route(cost, WAYPOINTS)).mean_j  # a Route or its waypoints
    profile = price_route(cost, WAYPOINTS, how="profile")
    driven = drive_profile(np.array(WAYPOINTS), 0.8, turn_rate_radps=cost.turn_rate_radps, dt_s=FORECAST_DT_S)
    power, t = profile_forecast_w(cost, driven), np.asarray(driven.time_s)
    assert profile.mean_j == pytest.approx(edges.mean_j, rel=0.005)  # the edges price the stop-turn-go drive
    assert price_route(cost, WAYPOINTS, how="profile", speed_mps=0.8).mean_j == pytest.approx(
        float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(t))), rel=1e-12)  # the drive at 0.8 m/s, integrated
    tmap, lem, learned = _learned_cost()
    assert learned.learned_model is lem
    assert price_route(learned, WAYPOINTS, how="profile").mean_j == lem.predict_route_energy_j(tmap, WAYPOINTS, 0.5)


@pytest.mark.parametrize("ground", ["asphalt", "sand"])
def test_the_edges_price_the_stop_turn_go_drive_the_profile_prices(ground):
    """Each stop and start, each pivot's ramps: the edges price what the profile drives (before: 2-5 % below it)."""
    cost = CostSpec(speed_mps=0.5).build(flat_map((14, 40), 1.0, ground=ground))
    for wp in ([[2.5, 5.5], [30.5, 5.5]],  # one segment: a start and a stop
               [[2.5, 1.5], [20.5, 1.5], [20.5, 10.5]],  # a right angle
               [[2.5, 5.5], [20.5, 5.5], [2.5, 5.5]],  # a U-turn
               [[2.5, 1.5], [6.5, 1.5], [6.5, 5.5], [10.5, 5.5], [10.5, 9.5], [14.5, 12.5]]):  # five short legs
        edges, profile = price_route(cost, wp).mean_j, price_route(cost, wp, how="profile").mean_j
        assert edges == pytest.approx(profile, rel=0.01), wp  # the profile price samples every 0.05 s
        driven = drive_profile(np.array(wp), 0.5, turn_rate_radps=cost.turn_rate_radps, dt_s=0.001)
        power, t = profile_forecast_w(cost, driven), np.asarray(driven.time_s)
        assert edges == pytest.approx(float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(t))), rel=1e-3), wp
        steady = cost.segment_energy_j(np.array(wp[:-1]), np.array(wp[1:])).sum()
        assert edges > steady + 40.0 * (len(wp) - 1)  # at least a stop-and-go a segment beyond steady driving


def test_collinear_waypoints_are_driven_through_by_the_edges_and_the_profile():
    cost = CostSpec(speed_mps=0.5).build(flat_map((12, 40), 1.0, ground="asphalt"))
    straight = [[2.5, 5.5], [30.5, 5.5]]
    through = [[2.5, 5.5], [9.5, 5.5], [16.5, 5.5], [16.5, 5.5], [30.5, 5.5]]  # collinear and repeated waypoints
    for how in ("edges", "profile"):
        assert price_route(cost, through, how=how).mean_j == pytest.approx(price_route(cost, straight, how=how).mean_j,
                                                                           rel=1e-9, abs=1e-6), how
    kinked = [[2.5, 5.5], [16.5, 5.5], [30.5, 5.6]]  # a heading change of 0.4 degrees: a stop and a pivot
    assert price_route(cost, kinked).mean_j > price_route(cost, straight).mean_j + 40.0
    assert price_route(cost, kinked).mean_j == pytest.approx(price_route(cost, kinked, how="profile").mean_j, rel=0.005)


def test_price_route_carries_the_interval_where_the_map_has_one(corridor_map, known_model):
    cost = CostSpec(model=known_model()).build(corridor_map)
    wp = [[2.5, 7.5], [2.5, 11.5], [27.5, 11.5]]  # up the hub, along the loam corridor
    assert price_route(cost, wp) == price_route(cost, wp, interval=True) and price_route(cost, wp).sd_j > 0
    point = price_route(cost, wp, interval=False)
    assert point.mean_j == price_route(cost, wp).mean_j and point.sd_j == 0.0


def test_price_route_refuses_what_it_cannot_price(wall_map):
    from planner.route import empty_route

    cost = CostSpec().build(wall_map)
    with pytest.raises(InvalidParameterError, match="no standard-deviation tables"):
        price_route(cost, [[2.5, 2.5], [8.5, 2.5]], interval=True)
    with pytest.raises(UnknownNameError, match="how must be one of"):
        price_route(cost, [[2.5, 2.5], [8.5, 2.5]], how="vibes")
    with pytest.raises(InvalidParameterError, match="found Route"):
        price_route(cost, empty_route("infeasible", "lattice", 0.0, 24.0))
    with pytest.raises(InvalidParameterError, match="blocked"):
        price_route(cost, [[2.5, 2.5], [38.5, 2.5]])  # through the wall
    with pytest.raises(InvalidParameterError, match="no physics model"):
        price_route(cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, cost.tables.turn_table_j)), [[2.5, 2.5], [8.5, 2.5]],
                    how="profile")


@pytest.mark.parametrize("dof", [math.inf, 2.0])
def test_a_route_energy_is_read_censored_at_zero_its_upper_quantiles_unchanged(dof):
    wide = RouteEnergyInterval(1000.0, 2000.0, {"sand": 2000.0}, dof=dof)
    z90 = predictive_quantile(0.9, dof)
    assert wide.interval_j(0.8) == (0.0, pytest.approx(1000.0 + z90 * 2000.0))  # the symmetric P10 is below 0
    assert wide.quantile_j(0.3) == 0.0 and wide.quantile_j(0.6) > wide.mean_j
    narrow = RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0}, dof=dof)  # far from 0: the predictive's own
    assert narrow.quantile_j(0.1) == pytest.approx(1000.0 - z90 * 100.0)
    assert narrow.to_dict()["central_interval_j"][0] > 0 and wide.to_dict()["central_interval_j"][0] == 0.0
