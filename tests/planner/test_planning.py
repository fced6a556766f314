"""Tests of planner.planning (and planner.ompl): plan_route with every planner, statuses, errors, determinism, comparisons."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import PhysicsEnergyModel, ground_preset, robot_preset
from planner import PLANNERS, CostSpec, PlannerSettings, plan_route
from planner.ompl import OMPL_PLANNERS
from planner.planning import compare_route, shortest_route
from planner.refine import refine_route
from planner.route import RouteComparison
from terrain import (
    BlockedPositionError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    PlanningError,
    TerrainMap,
    UnknownNameError,
)

GRAVITY_MPS2 = 9.80665
# Small budgets keep every solve well under a second; FMT's work is its sample count.
FAST = PlannerSettings(fmt_samples=300, bit_samples_per_batch=100)


def _model():
    return PhysicsEnergyModel(robot_preset("husky"))


def _cost(tmap):
    return CostSpec(energy_model=_model(), grounds={"asphalt": ground_preset("asphalt")}, speed_mps=0.5).build(tmap)


def _map(elevation, obstacle=None):
    elevation = np.asarray(elevation, dtype=float)
    return TerrainMap(
        elevation, 1.0, ground=np.zeros(elevation.shape, int), ground_names={0: "asphalt"}, obstacle=obstacle
    )


def _hill_map():
    """80 x 50 m, a 3 m Gaussian hill (sigma 8 m, at most ~13 deg) on the line y = 25."""
    x = np.arange(80) + 0.5
    y = np.arange(50) + 0.5
    z = 3.0 * np.exp(-0.5 * ((x[None, :] - 40) ** 2 + (y[:, None] - 25) ** 2) / 8.0**2)
    return _map(z)


def _wall_map(gap=True):
    obstacle = np.zeros((50, 80), bool)
    obstacle[:, 40] = True
    if gap:
        obstacle[40:45, 40] = False
    return _map(np.zeros((50, 80)), obstacle)


def _budget(planner, evaluations=30000):
    """Deterministic work bounds (RRT* family), or a short time (BIT*, FMT)."""
    if planner in ("RRTstar", "InformedRRTstar", "SORRTstar"):
        return {"time_limit_s": None, "max_cost_evaluations": evaluations}
    return {"time_limit_s": 0.5}


def _crosses_wall_at(route, col_x=40.0):
    """y coordinates where the route crosses the vertical line x = col_x."""
    ys = []
    for (x0, y0), (x1, y1) in zip(route.waypoints_m[:-1], route.waypoints_m[1:]):
        if (x0 - col_x) * (x1 - col_x) <= 0 and x0 != x1:
            ys.append(y0 + (col_x - x0) / (x1 - x0) * (y1 - y0))
    return ys


# --------------------------------------------------------------------------- flat: straight is optimal
@pytest.mark.parametrize("planner", ["lattice", "RRTstar", "BITstar"])
def test_flat_map_straight_route_is_optimal(planner):
    tmap = _map(np.zeros((40, 60)))
    cost = _cost(tmap)
    start, goal = (3.0, 4.0), (55.0, 31.0)  # an off-lattice direction
    route = plan_route(tmap, start, goal, cost=cost, planner=planner, seed=1, settings=FAST, compare=True,
                       **_budget(planner))
    straight = cost.path_energy_j([start, goal])
    assert route.status == "exact"
    assert route.energy_j == pytest.approx(straight, rel=1e-6)
    np.testing.assert_allclose(route.waypoints_m, [start, goal], atol=1e-6)
    # energy proportional to length on a uniform flat map
    e0 = float(_model().energy_per_metre_j(0.5, 0.0, ground_preset("asphalt")))
    assert route.drive_energy_j == pytest.approx(e0 * math.dist(start, goal), rel=1e-9)
    assert route.energy_saved_pct == pytest.approx(0.0, abs=1e-6)
    # the lattice reference includes the direct start-goal segment: here it is the optimum
    assert route.optimality_ratio == pytest.approx(1.0, rel=1e-9)


# --------------------------------------------------------------------------- hill: gentler detour
@pytest.mark.parametrize("planner", PLANNERS)
def test_every_planner_prefers_the_gentler_detour_around_a_hill(planner):
    tmap = _hill_map()
    cost = _cost(tmap)
    start, goal = (5.0, 25.0), (75.0, 25.0)
    route = plan_route(tmap, start, goal, cost=cost, planner=planner, seed=2, settings=FAST, compare=True,
                       **_budget(planner))
    assert route.status == "exact"
    np.testing.assert_allclose(route.waypoints_m[[0, -1]], [start, goal])
    straight = cost.path_energy_j([start, goal])
    assert route.shortest_energy_j == pytest.approx(straight)
    if planner == "lattice":
        # start and goal lie off the lattice's nodes: a lattice detour joins them with two more turns, each a stop,
        # a pivot and a start, and costs more than the straight route over the crest, which it keeps
        assert route.energy_j <= straight * (1 + 1e-9) and route.optimality_ratio < 1.0 + 1e-9
        return
    assert route.energy_j < 0.97 * straight  # two turns (two stops and starts) and a gentler climb
    assert np.abs(route.waypoints_m[:, 1] - 25.0).max() > 8.0  # it left the hill's crest line
    assert route.energy_saved_pct > 3.0
    # against the heading lattice's optimum (drive and turns): a refined lattice route never worse, an any-angle
    # route often better (fewer turns than 16 directions allow)
    assert route.optimality_ratio < (1.0 + 1e-9 if planner == "lattice" else 1.02)


def test_unrefined_route_reports_the_raw_planner():
    tmap = _hill_map()
    route = plan_route(
        tmap, (5.0, 25.0), (75.0, 25.0), cost=_cost(tmap), planner="RRTstar", seed=2, refine=False,
        time_limit_s=None, max_cost_evaluations=20000,
    )
    assert route.planner == "RRTstar"
    assert route.status == "exact"


# --------------------------------------------------------------------------- direction matters
def test_uphill_route_costs_more_than_the_way_back():
    grade = 0.1
    x = np.arange(60) + 0.5
    tmap = _map(np.broadcast_to(grade * x, (20, 60)))
    cost = _cost(tmap)
    a, b = (3.0, 10.0), (57.0, 10.0)
    up = plan_route(tmap, a, b, cost=cost, planner="lattice")
    down = plan_route(tmap, b, a, cost=cost, planner="lattice")
    potential_j = robot_preset("husky").mass_kg * GRAVITY_MPS2 * grade * (b[0] - a[0])
    assert up.energy_j - down.energy_j >= potential_j


# --------------------------------------------------------------------------- walls, blocked ends, infeasible
@pytest.mark.parametrize("planner", ["lattice", "RRTstar", "BITstar", "FMT"])
def test_route_goes_around_the_wall_through_its_gap(planner):
    tmap = _wall_map()
    cost = _cost(tmap)
    route = plan_route(
        tmap, (5.0, 10.0), (75.0, 10.0), cost=cost, planner=planner, seed=3, settings=FAST, **_budget(planner, 200000)
    )
    assert route.status == "exact"
    assert np.all(np.isfinite(route.segment_energy_j))
    crossings = _crosses_wall_at(route)
    assert crossings and all(40.0 <= y <= 45.0 for y in crossings)


def test_closed_wall_is_infeasible():
    tmap = _wall_map(gap=False)
    route = plan_route(tmap, (5.0, 10.0), (75.0, 10.0), cost=_cost(tmap), planner="RRTstar", time_limit_s=0.2)
    assert route.status == "infeasible"
    assert not route.found and route.waypoints_m.shape == (0, 2) and math.isnan(route.energy_j)
    with pytest.raises(PlanningError, match="infeasible"):
        route.raise_for_status()


def test_tiny_budget_gives_an_approximate_route():
    tmap = _wall_map()
    goal = (75.0, 40.0)
    route = plan_route(
        tmap, (5.0, 40.0), goal, cost=_cost(tmap), planner="RRTstar", seed=0, time_limit_s=None, max_cost_evaluations=50,
        compare=True,
    )
    assert route.status == "approximate"
    assert route.found and math.dist(route.waypoints_m[-1], goal) > 1.0
    # a route that stops short is not compared with routes that arrive
    assert math.isfinite(route.shortest_energy_j) and math.isfinite(route.lattice_energy_j)
    assert math.isnan(route.energy_saved_pct) and math.isnan(route.optimality_ratio)
    with pytest.raises(PlanningError, match="approximate"):
        route.raise_for_status()


def test_start_or_goal_in_an_obstacle_raises():
    tmap = _wall_map()
    cost = _cost(tmap)
    with pytest.raises(BlockedPositionError, match="start_xy_m .* obstacle"):
        plan_route(tmap, (40.5, 10.0), (75.0, 10.0), cost=cost)
    with pytest.raises(BlockedPositionError, match="goal_xy_m .* obstacle"):
        plan_route(tmap, (5.0, 10.0), (40.2, 3.0), cost=cost)


def test_start_on_too_steep_ground_raises():
    x = np.arange(30) + 0.5
    z = np.where(x < 15, 0.0, 0.6 * (x - 15))  # 31 deg beyond x = 15
    tmap = _map(np.broadcast_to(z, (10, 30)))
    with pytest.raises(BlockedPositionError, match="steeper"):
        plan_route(tmap, (25.0, 5.0), (2.0, 5.0), cost=_cost(tmap))


@pytest.mark.parametrize("point", [(-1.0, 5.0), (5.0, 50.5), (80.01, 3.0)])
def test_start_outside_the_map_raises(point):
    tmap = _wall_map()
    with pytest.raises(OutOfBoundsError, match="outside the map"):
        plan_route(tmap, point, (75.0, 10.0), cost=_cost(tmap))


@pytest.mark.parametrize("point", [(math.nan, 5.0), (5.0, math.inf)])
def test_nan_coordinates_raise(point):
    tmap = _wall_map()
    with pytest.raises(InvalidParameterError, match="finite"):
        plan_route(tmap, (5.0, 10.0), point, cost=_cost(tmap))


def test_unknown_planner_name_lists_valid_names():
    tmap = _wall_map()
    with pytest.raises(UnknownNameError, match=r"planner must be one of \[.*'RRTstar'.*'BITstar'.*'FMT'.*'lattice'\], got 'PRM'"):
        plan_route(tmap, (5.0, 10.0), (75.0, 10.0), cost=_cost(tmap), planner="PRM")
    with pytest.raises(UnknownNameError, match="RRTstar"):
        plan_route(tmap, (5.0, 10.0), (75.0, 10.0), cost=_cost(tmap), planner="rrtstar")


def test_bad_budget_seed_settings_and_grid():
    tmap = _wall_map()
    cost = _cost(tmap)
    args = (tmap, (5.0, 10.0), (75.0, 10.0))
    with pytest.raises(InvalidParameterError, match="both None"):
        plan_route(*args, cost=cost, time_limit_s=None)
    with pytest.raises(InvalidParameterError, match="time_limit_s"):
        plan_route(*args, cost=cost, time_limit_s=-1.0)
    with pytest.raises(InvalidParameterError, match="max_cost_evaluations"):
        plan_route(*args, cost=cost, max_cost_evaluations=0)
    with pytest.raises(InvalidParameterError, match="seed"):
        plan_route(*args, cost=cost, seed=-3)
    with pytest.raises(InvalidParameterError, match="rewire_factor"):
        PlannerSettings(rewire_factor=0.0)
    other = _map(np.zeros((50, 81)))
    with pytest.raises(GridMismatchError):
        plan_route(other, (5.0, 10.0), (75.0, 10.0), cost=cost)


# --------------------------------------------------------------------------- determinism
@pytest.mark.parametrize(("planner", "seed"), [("RRTstar", 0), ("RRTstar", 7), ("BITstar", 7)])
def test_seed_and_work_bound_make_planning_deterministic(planner, seed):
    tmap = _hill_map()
    cost = _cost(tmap)
    kw = {"cost": cost, "planner": planner, "time_limit_s": None, "max_cost_evaluations": 4000, "refine": False}
    a = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), seed=seed, **kw)
    # Whatever ran in between (other planners, other seeds), the same seed repeats the route.
    plan_route(tmap, (5.0, 25.0), (75.0, 25.0), cost=cost, planner="InformedRRTstar", seed=seed + 3,
               time_limit_s=None, max_cost_evaluations=3000)
    b = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), seed=seed, **kw)
    np.testing.assert_array_equal(a.waypoints_m, b.waypoints_m)
    c = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), seed=seed + 1, **kw)
    assert not np.array_equal(a.waypoints_m, c.waypoints_m)


# --------------------------------------------------------------------------- refinement and baselines
def test_refine_route_never_raises_the_true_energy():
    tmap = _hill_map()
    cost = _cost(tmap)
    rough = np.array([[5.0, 25.0], [20.0, 5.0], [30.0, 45.0], [50.0, 3.0], [60.0, 40.0], [75.0, 25.0]])
    out = refine_route(cost, rough, seed=0)
    assert cost.path_energy_j(out) < cost.path_energy_j(rough)
    np.testing.assert_array_equal(out[[0, -1]], rough[[0, -1]])
    with pytest.raises(InvalidParameterError, match="blocked"):
        refine_route(_cost(_wall_map()), [[5.0, 10.0], [75.0, 10.0]])


def test_shortest_route_goes_round_the_wall_end():
    tmap = _wall_map()
    cost = _cost(tmap)
    route = shortest_route(cost, (5.0, 10.0), (75.0, 10.0))
    assert route.status == "exact" and route.planner == "shortest"
    taut = math.dist((5.0, 10.0), (40.0, 40.0)) + 1.0 + math.dist((41.0, 40.0), (75.0, 10.0))
    assert taut <= route.length_m <= 1.02 * taut
    assert all(40.0 <= y <= 45.0 for y in _crosses_wall_at(route))


def test_ompl_planner_names_are_all_plannable():
    assert set(OMPL_PLANNERS) <= set(PLANNERS) and "lattice" in PLANNERS
    assert "PRM" not in PLANNERS and "PRMstar" not in PLANNERS  # deadlock with Python objectives


@pytest.mark.parametrize("planner", PLANNERS)
def test_every_planner_name_plans_a_route_on_a_tiny_map(planner):
    """Each registered name builds, tunes and solves (seeded, a work bound only), then refines.

    BIT* converges on this map (the straight line meets its lower bound) and stops calling the
    objective: its solve must still end (the objective is satisfied at its lower bound; it used
    to poll forever under a work bound)."""
    tmap = _map(np.zeros((12, 16)))
    cost = _cost(tmap)
    settings = PlannerSettings(fmt_samples=60, bit_samples_per_batch=20, refine_max_steps=20, refine_rounds=1)
    start, goal = (1.5, 1.5), (14.5, 10.5)
    evaluations = 20000 if planner == "FMT" else 3000  # FMT's work is its sample count
    route = plan_route(tmap, start, goal, cost=cost, planner=planner, seed=5, time_limit_s=None,
                       max_cost_evaluations=evaluations, settings=settings)
    assert route.status == "exact", route
    assert route.planner == f"{planner}+refine"
    np.testing.assert_allclose(route.waypoints_m[[0, -1]], [start, goal])
    # level uniform ground: the straight line is optimal, and the refinement finds it
    assert route.energy_j == pytest.approx(cost.path_energy_j([start, goal]), rel=1e-6)


# --------------------------------------------------------------------------- start = goal, seeds, comparisons
@pytest.mark.parametrize("planner", ["lattice", "RRTstar"])
def test_start_equal_to_goal_is_refused(planner):
    tmap = _hill_map()
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        plan_route(tmap, (5.0, 25.0), (5.0, 25.0), cost=_cost(tmap), planner=planner)


def test_unseeded_lattice_plans_are_identical():
    tmap = _hill_map()
    cost = _cost(tmap)
    a = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), cost=cost, planner="lattice")
    b = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), cost=cost, planner="lattice")
    c = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), cost=_cost(tmap), planner="lattice")
    assert a.planner == "lattice+refine"
    np.testing.assert_array_equal(a.waypoints_m, b.waypoints_m)
    np.testing.assert_array_equal(a.waypoints_m, c.waypoints_m)
    # seed=None refines with seed 0
    d = plan_route(tmap, (5.0, 25.0), (75.0, 25.0), cost=cost, planner="lattice", seed=0)
    np.testing.assert_array_equal(a.waypoints_m, d.waypoints_m)


@pytest.mark.parametrize("seed", [2**32 - 1, 2**32, 1.5, True])
def test_seeds_follow_the_library_rule(seed):
    tmap = _wall_map()
    args = (tmap, (5.0, 10.0), (75.0, 10.0))
    if seed == 2**32 - 1 and not isinstance(seed, bool):
        route = plan_route(*args, cost=_cost(tmap), planner="lattice", seed=seed)
        assert route.status == "exact"
    else:
        with pytest.raises(InvalidParameterError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
            plan_route(*args, cost=_cost(tmap), planner="lattice", seed=seed)


def test_comparisons_only_when_asked_and_once_per_query():
    tmap = _hill_map()
    cost = _cost(tmap)
    start, goal = (5.0, 25.0), (75.0, 25.0)
    plain = plan_route(tmap, start, goal, cost=cost, planner="lattice")
    assert plain.comparison is None and math.isnan(plain.energy_saved_pct) and math.isnan(plain.optimality_ratio)
    assert not any(key[0] == "comparison" for key in cost.results)
    route = plan_route(tmap, start, goal, cost=cost, planner="lattice", compare=True)
    assert isinstance(route.comparison, RouteComparison)
    shortest = route.comparison.shortest
    assert shortest.planner == "shortest" and shortest.status == "exact"
    assert route.shortest_energy_j == shortest.energy_j == pytest.approx(cost.path_energy_j([start, goal]))
    assert route.lattice_energy_j == route.comparison.lattice_optimum_j > 0
    assert route.energy_saved_pct >= 0.0 and route.optimality_ratio <= 1.0 + 1e-9  # refined from the lattice optimum
    again = plan_route(tmap, start, goal, cost=cost, planner="RRTstar", seed=1, time_limit_s=None,
                       max_cost_evaluations=3000, compare=True)
    assert again.comparison is route.comparison  # computed once, cached on the cost
    assert compare_route(cost, start, goal) is route.comparison


def test_the_comparison_cache_is_bounded():
    tmap = _map(np.zeros((10, 12)))
    cost = _cost(tmap)
    cost.results.maxsize = 6
    for k in range(10):
        compare_route(cost, (0.5 + k, 0.5), (11.5, 9.5 - 0.5 * k))
    assert len(cost.results) <= 6
    kept = compare_route(cost, (9.5, 0.5), (11.5, 5.0))  # the most recent query is still cached
    assert compare_route(cost, (9.5, 0.5), (11.5, 5.0)) is kept


def test_bad_flags_are_refused():
    tmap = _wall_map()
    args = (tmap, (5.0, 10.0), (75.0, 10.0))
    with pytest.raises(InvalidParameterError, match="compare must be True or False"):
        plan_route(*args, cost=_cost(tmap), planner="lattice", compare="yes")
    with pytest.raises(InvalidParameterError, match="refine must be True or False"):
        plan_route(*args, cost=_cost(tmap), planner="lattice", refine=1)
    with pytest.raises(InvalidParameterError, match="time_limit_s must be a real number"):
        plan_route(*args, cost=_cost(tmap), time_limit_s="1 s")
    with pytest.raises(InvalidParameterError, match="PlannerSettings.fmt_samples must be an integer"):
        PlannerSettings(fmt_samples=500.0)


def test_coarse_to_fine_is_a_planner_by_name_tuned_by_the_settings():
    # plan_route(planner="coarse") is plan_coarse_to_fine at the settings' factor and corridor, then refined
    from planner import CoarseOptions, plan_coarse_to_fine

    tmap = _hill_map()
    cost = _cost(tmap)
    start, goal = (5.0, 25.0), (75.0, 25.0)
    for factor, corridor in ((4, None), (8, 6.0)):
        settings = PlannerSettings(coarse_factor=factor, coarse_corridor_m=corridor)
        raw = plan_route(tmap, start, goal, cost=cost, planner="coarse", settings=settings, refine=False)
        direct = plan_coarse_to_fine(cost, start, goal, CoarseOptions(factor=factor, corridor_m=corridor)).route
        assert raw.planner == "coarse" and raw.status == "exact"
        np.testing.assert_array_equal(raw.waypoints_m, direct.waypoints_m)
        assert raw.energy_j == pytest.approx(direct.energy_j, rel=1e-12)
        refined = plan_route(tmap, start, goal, cost=cost, planner="coarse", settings=settings, seed=0)
        assert refined.planner == "coarse+refine" and refined.energy_j <= raw.energy_j + 1e-9
