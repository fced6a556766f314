"""Tests of planner.ompl.planners: the planner registry and a seeded, work-bounded solve."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("ompl", reason="the OMPL planners need OMPL's Python bindings")

from planner import PlannerSettings  # noqa: E402
from planner.ompl import OMPL_PLANNER_SPECS, OMPL_PLANNERS, solve  # noqa: E402

from ompl_samples import flat_cost  # noqa: E402


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
