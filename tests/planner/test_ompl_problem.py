"""Tests of planner.ompl.problem: the OMPL space, validity, motion checks and paths of one solve."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("ompl", reason="the OMPL planners need OMPL's Python bindings")

from planner.cost_spec import CostSpec
from planner.ompl import EnergyProblem  # noqa: E402


@pytest.fixture
def problem(wall_map):
    cost = CostSpec().build(wall_map)
    return EnergyProblem(cost.arrays, cost.min_energy_per_metre_j, np.array([5.5, 10.5]), np.array([35.5, 10.5]),
                         max_evaluations=100)


def test_free_cells_are_valid_and_the_wall_is_not(problem):
    assert problem.checker.isValid(problem.state((5.5, 10.5)))
    assert not problem.checker.isValid(problem.state((20.5, 10.5)))


def test_a_motion_through_the_wall_is_invalid_and_one_beside_it_valid(problem):
    west, east = problem.state((5.5, 10.5)), problem.state((35.5, 10.5))
    assert not problem.validator.checkMotion(west, east)
    assert problem.validator.checkMotion(west, problem.state((10.5, 15.5)))


def test_a_path_keeps_its_waypoints(problem):
    waypoints = np.array([[5.5, 10.5], [10.5, 15.5], [12.5, 3.5]])
    np.testing.assert_array_equal(EnergyProblem.coords(problem.path(waypoints)), waypoints)
    assert problem.max_evaluations == 100 and problem.evaluations == 0
