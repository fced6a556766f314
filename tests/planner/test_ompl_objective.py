"""Tests of planner.ompl.objective: EnergyObjective prices a motion by the cell walk, directed, with an admissible heuristic."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("ompl", reason="the OMPL planners need OMPL's Python bindings")

from ompl_samples import ramp_cost  # noqa: E402

from planner.ompl import EnergyProblem  # noqa: E402


def _problem(cost):
    return EnergyProblem(cost.arrays, cost.min_energy_per_metre_j, np.array([2.5, 10.5]), np.array([27.5, 10.5]))


def test_a_motion_costs_its_segment_energy_and_is_counted():
    cost = ramp_cost()
    problem = _problem(cost)
    objective = problem.objective
    a, b = problem.state((2.5, 10.5)), problem.state((27.5, 12.5))
    assert objective.motionCost(a, b).value() == pytest.approx(cost.segment_energy_one_j(2.5, 10.5, 27.5, 12.5),
                                                               rel=1e-12)
    assert objective.evaluations == 1 and problem.evaluations == 1


def test_uphill_costs_more_than_downhill_and_the_objective_says_it_is_not_symmetric():
    problem = _problem(ramp_cost())
    objective = problem.objective
    low, high = problem.state((2.5, 10.5)), problem.state((27.5, 10.5))
    assert objective.motionCost(low, high).value() > objective.motionCost(high, low).value()
    assert not objective.isSymmetric() and objective.stateCost(low).value() == 0.0


def test_the_heuristic_never_overestimates():
    problem = _problem(ramp_cost())
    rng = np.random.default_rng(0)
    for _ in range(50):
        (xa, xb), (ya, yb) = rng.uniform(0.5, 29.5, 2), rng.uniform(0.5, 19.5, 2)
        a, b = problem.state((xa, ya)), problem.state((xb, yb))
        h = problem.objective.motionCostHeuristic(a, b).value()
        assert h <= problem.objective.motionCost(a, b).value() * (1 + 1e-12)
