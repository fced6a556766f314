"""Tests of planner.ompl.planners: the planner registry and a seeded, work-bounded solve."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("ompl", reason="the OMPL planners need OMPL's Python bindings")

from ompl_samples import flat_cost  # noqa: E402

from planner import PlannerSettings  # noqa: E402
from planner.ompl import OMPL_PLANNER_SPECS, OMPL_PLANNERS, solve  # noqa: E402


def test_the_registry_names_the_five_planners():
    assert OMPL_PLANNERS == ("RRTstar", "InformedRRTstar", "SORRTstar", "BITstar", "FMT")
    assert set(OMPL_PLANNER_SPECS) == set(OMPL_PLANNERS)


def test_on_open_ground_a_seeded_solve_joins_start_and_goal_and_repeats():
    cost = flat_cost()
    start, goal = np.array([2.5, 2.5]), np.array([27.5, 17.5])
    args = (cost.arrays, cost.min_energy_per_metre_j, start, goal, "RRTstar", None, 2000, 3, PlannerSettings())
    status, waypoints, planning_time_s, evaluations = solve(*args)
    assert status in ("exact", "approximate") and waypoints is not None
    np.testing.assert_allclose(waypoints[[0, -1]], [start, goal], atol=1e-6)
    assert 0 < evaluations and planning_time_s >= 0.0
    again = solve(*args)
    assert again[0] == status and np.array_equal(again[1], waypoints)


def test_seeded_solves_in_threads_of_one_process_repeat_the_solves_made_one_by_one():
    """OMPL's seed is process-wide: a solve seeded in one thread while another thread's solve
    creates its RNGs used to change that solve's samples (dask workers of one process are
    threads). Each seeded solve must give what it gives alone."""
    from concurrent.futures import ThreadPoolExecutor

    cost = flat_cost()
    start, goal = np.array([2.5, 2.5]), np.array([27.5, 17.5])

    def run(seed: int):
        status, waypoints, _, evaluations = solve(cost.arrays, cost.min_energy_per_metre_j, start, goal,
                                                  "RRTstar", None, 600, seed, PlannerSettings())
        return status, waypoints.tobytes(), evaluations

    seeds = [s % 4 for s in range(16)]
    alone = {s: run(s) for s in set(seeds)}
    assert len({a[1] for a in alone.values()}) == 4  # the seeds do give different routes
    with ThreadPoolExecutor(max_workers=4) as pool:
        together = list(pool.map(run, seeds))
    assert together == [alone[s] for s in seeds]
