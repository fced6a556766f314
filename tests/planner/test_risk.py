"""Tests of the risk ideas: route energy intervals (price_route) and risk-aware planning (CostTables.at_quantile) on a cheap-but-uncertain vs dear-but-certain map."""

import math

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, robot_preset
from energy.budget import log_battery_power_w
from planner import CostTables, EnergyCost, RouteEnergyInterval, plan_route, price_route
from planner.cost_spec import CostSpec
from planner.model_cost import model_energy_cost
from terrain import InvalidParameterError, TerrainMap

START, GOAL = (2.5, 7.5), (27.5, 7.5)


def risk_cost(cost, q):
    """The cost a risk level ``q`` plans on (as CostSpec.at_risk lays it)."""
    return cost.with_tables(cost.tables.at_quantile(q))


def route_energy_interval(cost, waypoints):
    return price_route(cost, waypoints, interval=True)
Z90 = 1.2815515655446004


def _cells_crossed(tmap, waypoints, step_m=0.01):
    """Ground class of points every ``step_m`` along the polyline (an independent walk)."""
    pts = []
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        n = max(2, int(math.hypot(*(b - a)) / step_m))
        s = (np.arange(n) + 0.5) / n
        pts.append(a + s[:, None] * (b - a))
    pts = np.concatenate(pts)
    r, c = tmap.rowcol(pts[:, 0], pts[:, 1])
    return np.asarray(tmap.ground)[r, c], step_m


@pytest.fixture
def cost(corridor_map, known_model):
    return model_energy_cost(corridor_map, known_model(), robot_preset("husky"), 0.5)


def _plan(tmap, cost, q=None):
    route = plan_route(tmap, START, GOAL, cost=cost if q is None else risk_cost(cost, q), planner="lattice")
    assert route.status == "exact"
    return route


def _on_loam(tmap, route):
    ground = np.asarray(tmap.ground)[tmap.rowcol(route.waypoints_m[:, 0], route.waypoints_m[:, 1])]
    cls, _ = _cells_crossed(tmap, route.waypoints_m)
    return bool(np.any(cls == 0)), ground


def test_the_spread_tables_are_the_battery_power_of_mean_plus_minus_run_sd(cost):
    # loam: 2 A per side driving, run-level sd 1 A; gravel has no spread
    robot = robot_preset("husky")
    n = 100
    t = np.arange(n) / 100
    power = []
    for cur in (3.0, 1.0):
        log = InteractionLog(t, np.full(n, 0.5), np.zeros(n), np.full(n, cur), np.full(n, cur), t, np.full(n, 9.0),
                             meta=LogMeta())
        power.append(log_battery_power_w(log, robot, electronics=False).mean())
    sd_per_m = 0.5 * (power[0] - power[1]) / 0.5
    mid = cost.tables.grade_sd_table_j_per_m.shape[1] // 2
    assert cost.tables.ground_labels == ("loam", "gravel")
    assert cost.tables.grade_sd_table_j_per_m[0, mid] == pytest.approx(sd_per_m, rel=1e-9)
    assert np.all(cost.tables.grade_sd_table_j_per_m[1] == 0) and np.all(cost.tables.turn_sd_table_j[1] == 0)
    assert cost.tables.turn_sd_table_j[0, 0] == 0 and cost.tables.turn_sd_table_j[0, -1] > 0
    assert cost.has_interval


def test_high_risk_level_takes_the_certain_corridor_and_low_or_mean_the_cheap_one(corridor_map, cost):
    loam_mean, _ = _on_loam(corridor_map, _plan(corridor_map, cost))
    loam_low, _ = _on_loam(corridor_map, _plan(corridor_map, cost, 0.1))
    loam_high, _ = _on_loam(corridor_map, _plan(corridor_map, cost, 0.9))
    assert loam_mean and loam_low  # the cheap, uncertain loam corridor
    assert not loam_high  # the dearer, certain gravel corridor
    # and the choice is right: P90 of the certain route is below P90 of the cheap one
    cheap = route_energy_interval(cost, _plan(corridor_map, cost).waypoints_m)
    certain = route_energy_interval(cost, _plan(corridor_map, cost, 0.9).waypoints_m)
    assert cheap.mean_j < certain.mean_j and certain.p90_j < cheap.p90_j
    assert certain.sd_j == 0.0 and certain.sd_by_ground_j == {}


def test_reported_p90_matches_a_direct_computation(corridor_map, cost):
    route = _plan(corridor_map, cost)
    iv = route_energy_interval(cost, route.waypoints_m)
    # direct: loam metres (sampled every cm) times loam's J/m spread, plus loam's turn spread at loam waypoints
    cls, step = _cells_crossed(corridor_map, route.waypoints_m)
    loam_m = step * np.count_nonzero(cls == 0)
    mid = cost.tables.grade_sd_table_j_per_m.shape[1] // 2
    angles, _ = cost.turn_energies_j(route.waypoints_m)
    wp_cls = np.asarray(corridor_map.ground)[corridor_map.rowcol(route.waypoints_m[:, 0], route.waypoints_m[:, 1])]
    grid = np.linspace(0, math.pi, cost.tables.turn_sd_table_j.shape[1])
    turns = sum(np.interp(a, grid, cost.tables.turn_sd_table_j[0]) for a, g in zip(angles, wp_cls) if g == 0)
    sd = loam_m * cost.tables.grade_sd_table_j_per_m[0, mid] + turns
    assert iv.sd_j == pytest.approx(sd, rel=2e-3)
    assert iv.mean_j == pytest.approx(route.energy_j, rel=1e-12)
    assert iv.p90_j == pytest.approx(route.energy_j + Z90 * sd, rel=1e-3)
    assert iv.p50_j == iv.mean_j and iv.interval_j(0.8) == pytest.approx((iv.quantile_j(0.1), iv.p90_j))


def test_spreads_add_linearly_within_a_ground_and_in_quadrature_across_grounds():
    g = np.zeros((4, 20), dtype=int)
    g[:, 10:] = 1
    tmap = TerrainMap(np.zeros((4, 20)), 1.0, ground=g, ground_names={0: "a", 1: "b"})
    grade = np.full((2, 5), 10.0)
    turn = np.zeros((2, 3))
    cost = EnergyCost(tmap, g, CostTables(grade, turn, ground_labels=("a", "b"), grade_sd_table_j_per_m=np.array([[3.0] * 5, [4.0] * 5]), turn_sd_table_j=np.zeros((2, 3))), speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=1.0)
    # 8 m on a (over two segments: linear, 24 J) and 8 m on b (32 J): sqrt(24^2 + 32^2) = 40
    iv = route_energy_interval(cost, [[2.0, 2.0], [6.0, 2.0], [18.0, 2.0]])
    assert iv.sd_by_ground_j == pytest.approx({"a": 8 * 3.0, "b": 8 * 4.0})
    assert iv.sd_j == pytest.approx(40.0)
    assert iv.mean_j == pytest.approx(160.0)
    # the risk objective adds the spreads linearly: an upper bound of the route's P90 across grounds
    assert risk_cost(cost, 0.9).path_energy_j([[2.0, 2.0], [18.0, 2.0]]) == pytest.approx(160 + Z90 * 56.0)
    assert iv.p90_j == pytest.approx(160 + Z90 * 40.0) and iv.p90_j < 160 + Z90 * 56.0


def test_risk_and_interval_need_a_cost_with_spreads_and_a_level_in_the_open_unit_interval(flat_map, cost):
    plain = CostSpec().build(flat_map)
    assert not plain.has_interval
    with pytest.raises(InvalidParameterError, match="no standard deviations"):
        risk_cost(plain, 0.9)
    with pytest.raises(InvalidParameterError, match="no standard-deviation tables"):
        route_energy_interval(plain, [[1.0, 1.0], [5.0, 1.0]])
    for q in (0.0, 1.0, 1.5, float("nan")):
        with pytest.raises(InvalidParameterError, match="q"):
            risk_cost(cost, q)
    with pytest.raises(InvalidParameterError, match="both or neither"):
        EnergyCost(flat_map, np.zeros(flat_map.shape, int), CostTables(np.ones((1, 3)), np.zeros((1, 2)), grade_sd_table_j_per_m=np.ones((1, 3))), speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=1.0)
    with pytest.raises(InvalidParameterError, match="shape"):
        EnergyCost(flat_map, np.zeros(flat_map.shape, int), CostTables(np.ones((1, 3)), np.zeros((1, 2)), grade_sd_table_j_per_m=np.ones((1, 5)), turn_sd_table_j=np.zeros((1, 2))), speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=1.0)
    with pytest.raises(InvalidParameterError, match="RouteEnergyInterval.sd_j"):
        RouteEnergyInterval(1.0, -1.0, {})
