"""The shortest route, and a search's route refined — or the shortest refined, when that is cheaper.

Every planner's exact route is refined (:func:`planner.refine.refine_route`, an any-angle route
by its polish) and compared with the shortest-distance route refined the same way; a
minimum-energy planner returns the cheaper of the two, so its answer never costs more than the
baseline it is compared with. :func:`planner.plan_route` and the incremental replanner
(:class:`planner.replan.IncrementalPlanner`) share this step.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .anyangle import polish_path
from .edge_cost import EnergyCost
from .lattice import Lattice
from .problem import PlanningProblem
from .refine import refine_route, string_pull
from .route import Route, empty_route, evaluate_route
from .settings import PlannerSettings

__all__ = ["shortest_route", "shortest_of", "refine_planned", "REFINE_DEFAULT_SEED"]

#: Seed of the refinement when :func:`planner.plan_route` gets ``seed=None``.
REFINE_DEFAULT_SEED = 0


def shortest_route(cost: EnergyCost, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float]) -> Route:
    """The shortest-distance route between two points, costed in energy.

    The straight line when it is free; otherwise the shortest route on the 1-cell lattice
    (edge weights = lengths) straightened by greedy line-of-sight shortcuts
    (:func:`string_pull`). It is the baseline of ``Route.energy_saved_pct``.

    Returns
    -------
    Route
        ``planner="shortest"``; status ``"exact"``, or ``"infeasible"`` when start and goal
        lie in different free regions.

    Raises
    ------
    InvalidParameterError, OutOfBoundsError, BlockedPositionError
        As :func:`plan_route` for bad start / goal points.
    """
    return shortest_of(PlanningProblem(cost, start_xy_m, goal_xy_m))


def shortest_of(problem: PlanningProblem) -> Route:
    """:func:`shortest_route` of a checked problem (cached on the cost, as the comparisons)."""
    return problem.cost.results.get_or_make(("shortest", *problem.key), lambda: _shortest_search(problem))


def _shortest_search(problem: PlanningProblem) -> Route:
    cost, start, goal = problem.cost, problem.start, problem.goal
    t0 = time.perf_counter()
    if math.isfinite(cost.segment_energy_one_j(start[0], start[1], goal[0], goal[1])):
        pts = np.array([start, goal])
    else:
        lp = Lattice.for_cost(cost, 1).shortest_path(start, goal, weight="length")
        if not lp.found:
            return empty_route("infeasible", "shortest", time.perf_counter() - t0, cost.battery_voltage_v)
        pts = string_pull(cost, lp.waypoints_m)
    return evaluate_route(cost, pts, status="exact", planner="shortest", planning_time_s=time.perf_counter() - t0)


def refine_planned(problem: PlanningProblem, planner: str, waypoints: np.ndarray, seed: int | None,
                   settings: PlannerSettings) -> tuple[np.ndarray, str]:
    """A search's exact route refined (an any-angle route by its polish, any other by :func:`refine_route`),
    or the shortest route refined when that is cheaper (:func:`_refined_or_shortest`); and the
    route's planner name (``"lattice+refine"``, ``"... (from the shortest route)"``)."""
    cost = problem.cost
    if planner == "anyangle":
        waypoints = polish_path(cost, waypoints)
    else:
        waypoints = refine_route(cost, waypoints, seed=REFINE_DEFAULT_SEED if seed is None else seed,
                                 max_steps=settings.refine_max_steps, rounds=settings.refine_rounds)
    waypoints, from_shortest = _refined_or_shortest(problem, waypoints, seed, settings)
    return waypoints, f"{planner}+refine (from the shortest route)" if from_shortest else f"{planner}+refine"


def _refined_or_shortest(problem: PlanningProblem, waypoints: np.ndarray, seed: int | None,
                         settings: PlannerSettings) -> tuple[np.ndarray, bool]:
    """``waypoints`` (a refined route), or the shortest-distance route refined the same way when it is cheaper;
    and whether it was.

    A search over a lattice's 16 directions, or a sampling planner within its budget, can end above
    a route it never saw: on level ground in an off-lattice direction the straight line, whose
    zig-zag lattice copy pays for its turns (a slow-turning robot: up to 8 % more). The shortest
    route is a feasible candidate every query has; a minimum-energy planner returns the cheaper of
    the two, so its answer never costs more than the baseline it is compared with.
    """
    shortest = shortest_of(problem)
    cost = problem.cost
    if shortest.status != "exact" or not shortest.energy_j < cost.path_energy_j(waypoints):
        return waypoints, False
    pts = refine_route(cost, shortest.waypoints_m, seed=REFINE_DEFAULT_SEED if seed is None else seed,
                       max_steps=settings.refine_max_steps, rounds=settings.refine_rounds)
    return pts, True


