"""planner.problem: a query checked once — the points on free cells of the map, distinct — and what trusts it."""

from __future__ import annotations

import numpy as np
import pytest

from planner import PlannerSettings, PlanningProblem, plan_route
from planner.cost_spec import CostSpec
from planner.planning import PLANNER_SEARCHES, PLANNERS
from terrain import BlockedPositionError, InvalidParameterError, OutOfBoundsError, flat_map, wall_map


@pytest.fixture(scope="module")
def cost():
    return CostSpec().build(wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34), ground="asphalt"))


def test_a_problem_holds_checked_read_only_points_and_knows_if_they_connect(cost):
    p = PlanningProblem(cost, [2.5, 2.5], np.array([37.5, 5.5]))
    assert p.start_xy_m == (2.5, 2.5) and p.goal_xy_m == (37.5, 5.5) and p.key == ((2.5, 2.5), (37.5, 5.5))
    assert p.terrain is cost.terrain and p.connected  # through the gap in the wall
    with pytest.raises(ValueError):
        p.start[0] = 0.0  # read-only
    walled = CostSpec().build(wall_map((20, 20), 1.0, wall_col=10, gap_rows=(0, 0), ground="asphalt"))
    assert not PlanningProblem(walled, (2.5, 2.5), (17.5, 2.5)).connected


@pytest.mark.parametrize(("start", "goal", "error", "match"), [
    ((2.5, 2.5), (2.5, 2.5), InvalidParameterError, r"start equals goal \(2\.5, 2\.5\) m"),
    ((2.5, np.nan), (5.5, 5.5), InvalidParameterError, "start_xy_m must be finite coordinates"),
    ("here", (5.5, 5.5), InvalidParameterError, r"start_xy_m must be \(x_m, y_m\)"),
    ((2.5, 2.5), (50.0, 5.0), OutOfBoundsError, "goal_xy_m .* outside the map bounds"),
    ((20.5, 5.5), (5.5, 5.5), BlockedPositionError, r"start_xy_m \(20\.5, 5\.5\) m lies on an obstacle"),
])
def test_bad_queries_are_refused_once_with_the_point_named(cost, start, goal, error, match):
    with pytest.raises(error, match=match):
        PlanningProblem(cost, start, goal)
    with pytest.raises(error, match=match):  # plan_route checks through the same problem
        plan_route(cost.terrain, start, goal, cost=cost, planner="lattice")


def test_a_problem_needs_an_energy_cost():
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost, got 'TerrainMap'"):
        PlanningProblem(flat_map((5, 5), 1.0), (0.5, 0.5), (3.5, 3.5))


def test_every_planner_name_has_one_search_in_the_registry(cost):
    assert tuple(PLANNER_SEARCHES) == PLANNERS
    p = PlanningProblem(cost, (2.5, 2.5), (37.5, 5.5))
    status, waypoints, seconds = PLANNER_SEARCHES["lattice"](p, None, None, 0, PlannerSettings())
    assert status == "exact" and np.allclose(waypoints[[0, -1]], [[2.5, 2.5], [37.5, 5.5]]) and seconds >= 0.0
    route = plan_route(cost.terrain, (2.5, 2.5), (37.5, 5.5), cost=cost, planner="lattice", refine=False)
    assert route.found and route.energy_j > 0  # the same search, priced by evaluate_route
