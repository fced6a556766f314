"""Tests of planner.route: Route validation, derived quantities and evaluate_route."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from planner import CostSpec, Route
from planner.route import ROUTE_STATUSES, RouteComparison, evaluate_route
from terrain import InvalidParameterError, OutOfBoundsError, PlanningError, TerrainMap


class _Robot:
    battery_voltage_v = 24.0
    turn_rate_radps = 0.5


class LinearModel:
    """Stand-in: e(s) = 50 + 400 max(s, 0) J per metre travelled; turns 30 J/rad."""

    robot = _Robot()

    def energy_per_metre_j(self, speed_mps, grade, ground):
        return 50.0 + 400.0 * np.maximum(np.asarray(grade, dtype=float), 0.0)

    def turn_energy_j(self, heading_change_rad, ground):
        return 30.0 * np.abs(np.asarray(heading_change_rad, dtype=float))


def _cost(elevation=None, obstacle=None):
    z = np.zeros((20, 30)) if elevation is None else np.asarray(elevation, dtype=float)
    tmap = TerrainMap(z, 1.0, ground=np.zeros(z.shape, int), ground_names={0: "g"}, obstacle=obstacle)
    return CostSpec(energy_model=LinearModel(), grounds={"g": None}, speed_mps=0.5).build(tmap)


def test_evaluate_route_on_flat_map():
    cost = _cost()
    route = evaluate_route(cost, [[1.0, 1.0], [11.0, 1.0], [11.0, 6.0]], planner="manual", planning_time_s=0.25)
    assert route.status == "exact" and route.found and route.planner == "manual"
    assert route.length_m == pytest.approx(15.0)
    np.testing.assert_allclose(route.segment_energy_j, [500.0, 250.0])
    np.testing.assert_allclose(route.turn_energy_j, [0.0, 30.0 * math.pi / 2, 0.0])
    assert route.drive_energy_j == pytest.approx(750.0)
    assert route.energy_j == pytest.approx(750.0 + 15.0 * math.pi)
    assert route.energy_wh == pytest.approx(route.energy_j / 3600.0)
    assert route.charge_mah == pytest.approx(route.energy_j / 24.0 / 3.6)
    # stop-turn-go: 10 m and 5 m at 0.5 m/s, each ramped from and to rest at 0.5 m/s^2 (+1 s), and a quarter turn
    # at 0.5 rad/s ramped at 1 rad/s^2 (+0.5 s)
    assert route.duration_s == pytest.approx(30.0 + 2 * 1.0 + (math.pi / 2) / 0.5 + 0.5)
    assert route.planning_time_s == 0.25
    assert math.isnan(route.energy_saved_pct) and math.isnan(route.optimality_ratio)


def test_duration_on_slopes_is_the_profiles_on_the_horizontal_length():
    # the stop-turn-go profile (what the simulator drives) advances at the planning speed over the map's plane
    grade = 0.3
    z = np.broadcast_to(grade * (np.arange(30) + 0.5), (20, 30))
    route = evaluate_route(_cost(z), [[2.0, 5.0], [12.0, 5.0], [22.0, 5.0]])
    assert route.length_m == pytest.approx(20.0)
    assert route.duration_s == pytest.approx(20.0 / 0.5 + 1.0)  # driven through (12, 5): one ramp up, one down


def test_comparisons_against_baselines():
    plain = evaluate_route(_cost(), [[1.0, 1.0], [21.0, 1.0]])
    assert plain.comparison is None and math.isnan(plain.energy_saved_pct) and math.isnan(plain.optimality_ratio)
    shortest = plain.replace(energy_j=1250.0, segment_energy_j=[1250.0], planner="shortest")
    route = plain.replace(comparison=RouteComparison(shortest=shortest, lattice_optimum_j=800.0))
    assert route.shortest_energy_j == 1250.0 and route.lattice_energy_j == 800.0
    assert route.energy_saved_pct == pytest.approx(100.0 * (1250.0 - 1000.0) / 1250.0)
    assert route.optimality_ratio == pytest.approx(1000.0 / 800.0)
    summary = route.summary()
    assert summary["energy_saved_pct"] == pytest.approx(20.0)
    assert {"status", "planner", "energy_j", "energy_wh", "charge_mah", "duration_s", "planning_time_s"} <= set(summary)


def test_route_comparison_is_validated():
    plain = evaluate_route(_cost(), [[1.0, 1.0], [21.0, 1.0]])
    with pytest.raises(InvalidParameterError, match="shortest must be a Route"):
        RouteComparison(shortest=1250.0, lattice_optimum_j=800.0)
    with pytest.raises(InvalidParameterError, match="lattice_optimum_j"):
        RouteComparison(shortest=plain, lattice_optimum_j=-1.0)
    with pytest.raises(InvalidParameterError, match="comparison must be a RouteComparison"):
        plain.replace(comparison={"shortest_energy_j": 1.0})
    assert math.isnan(RouteComparison(shortest=plain, lattice_optimum_j=math.nan).lattice_optimum_j)


def test_route_is_frozen_with_readonly_arrays():
    route = evaluate_route(_cost(), [[1.0, 1.0], [21.0, 1.0]])
    with pytest.raises(dataclasses.FrozenInstanceError):
        route.energy_j = 0.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        route.waypoints_m[0, 0] = 3.0
    assert route.raise_for_status() is route


def test_evaluate_route_rejects_invalid_routes():
    obstacle = np.zeros((20, 30), bool)
    obstacle[:, 15] = True
    cost = _cost(obstacle=obstacle)
    with pytest.raises(InvalidParameterError, match="segment 0 .* blocked"):
        evaluate_route(cost, [[1.0, 1.0], [25.0, 1.0]])
    with pytest.raises(InvalidParameterError, match="at least 2"):
        evaluate_route(cost, [[1.0, 1.0]])
    with pytest.raises(InvalidParameterError, match="finite"):
        evaluate_route(cost, [[1.0, 1.0], [math.nan, 2.0]])
    with pytest.raises(OutOfBoundsError):
        evaluate_route(cost, [[1.0, 1.0], [2.0, 40.0]])


def _fields(**changes):
    base = {
        "status": "exact",
        "waypoints_m": np.array([[0.0, 0.0], [1.0, 0.0]]),
        "segment_energy_j": np.array([10.0]),
        "turn_energy_j": np.zeros(2),
        "length_m": 1.0,
        "duration_s": 2.0,
        "energy_j": 10.0,
        "battery_voltage_v": 24.0,
        "planner": "x",
        "planning_time_s": 0.0,
    }
    base.update(changes)
    return base


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"status": "done"}, "status"),
        ({"waypoints_m": np.zeros((1, 2))}, "needs >= 2 waypoints"),
        ({"segment_energy_j": np.array([1.0, 2.0])}, "segment energies"),
        ({"segment_energy_j": np.array([np.inf])}, "finite"),
        ({"energy_j": -1.0}, "energy_j"),
        ({"battery_voltage_v": 0.0}, "battery_voltage_v"),
        ({"planning_time_s": math.nan}, "planning_time_s"),
        ({"planner": ""}, "planner"),
        ({"status": "timeout"}, "no waypoints"),
        ({"waypoints_m": np.zeros((3,))}, "shape"),
    ],
)
def test_route_validation(changes, match):
    with pytest.raises(InvalidParameterError, match=match):
        Route(**_fields(**changes))


def test_not_found_routes():
    for status in ("timeout", "infeasible"):
        route = Route(
            **_fields(
                status=status, waypoints_m=np.empty((0, 2)), segment_energy_j=np.empty(0), turn_energy_j=np.empty(0),
                length_m=math.nan, duration_s=math.nan, energy_j=math.nan,
            )
        )
        assert not route.found and math.isnan(route.drive_energy_j) and math.isnan(route.charge_mah)
        with pytest.raises(PlanningError, match=status):
            route.raise_for_status()
    assert ROUTE_STATUSES == ("exact", "approximate", "timeout", "infeasible")
