"""The OMPL planners the energy objective works with, by name: factory and tuning of each, and one solve."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import geometric as og

from terrawatt_base.errors import PlanningError

from ..kernels import CostArrays
from ..settings import PlannerSettings
from .problem import EnergyProblem, ompl_session

__all__ = ["OmplPlannerSpec", "OMPL_PLANNER_SPECS", "OMPL_PLANNERS", "make_planner", "solve"]


@dataclass(frozen=True)
class OmplPlannerSpec:
    """How to make one OMPL planner: ``factory(si)`` builds it, ``tune(planner, settings)`` sets it up."""

    factory: Callable[[Any], Any]
    tune: Callable[[Any, PlannerSettings], None]


def _tune_rrt_star(planner: Any, settings: PlannerSettings) -> None:
    planner.setRewireFactor(settings.rewire_factor)
    planner.setGoalBias(settings.goal_bias)
    if settings.range_m is not None:
        planner.setRange(settings.range_m)


def _tune_bit_star(planner: Any, settings: PlannerSettings) -> None:
    planner.setSamplesPerBatch(settings.bit_samples_per_batch)


def _tune_fmt(planner: Any, settings: PlannerSettings) -> None:
    planner.setNumSamples(settings.fmt_samples)


#: Optimising OMPL planners that work with the Python energy objective (OMPL_NOTES: PRM and
#: PRM* deadlock with a Python objective, AORRTC ignores it). Add a planner here.
OMPL_PLANNER_SPECS: dict[str, OmplPlannerSpec] = {
    "RRTstar": OmplPlannerSpec(og.RRTstar, _tune_rrt_star),
    "InformedRRTstar": OmplPlannerSpec(og.InformedRRTstar, _tune_rrt_star),
    "SORRTstar": OmplPlannerSpec(og.SORRTstar, _tune_rrt_star),
    "BITstar": OmplPlannerSpec(og.BITstar, _tune_bit_star),
    "FMT": OmplPlannerSpec(og.FMT, _tune_fmt),
}
#: Names of :data:`OMPL_PLANNER_SPECS`.
OMPL_PLANNERS = tuple(OMPL_PLANNER_SPECS)


def make_planner(name: str, problem: EnergyProblem, settings: PlannerSettings) -> Any:
    """The planner ``name`` of :data:`OMPL_PLANNER_SPECS`, tuned, on ``problem``, set up."""
    spec = OMPL_PLANNER_SPECS[name]
    planner = spec.factory(problem.si)
    spec.tune(planner, settings)
    planner.setProblemDefinition(problem.pdef)
    planner.setup()
    return planner


def solve(
    arrays: CostArrays,
    min_energy_per_metre_j: float,
    start: np.ndarray,
    goal: np.ndarray,
    name: str,
    time_limit_s: float | None,
    max_evaluations: int | None,
    seed: int | None,
    settings: PlannerSettings,
) -> tuple[str, np.ndarray | None, float, int]:
    """Run one OMPL planner on a fresh problem.

    Returns
    -------
    status : str
        ``"exact"``, ``"approximate"``, ``"timeout"`` or ``"infeasible"``.
    waypoints : ndarray or None
        The solution path's vertices (None without one).
    planning_time_s : float
    evaluations : int
        Objective ``motionCost`` calls.

    Raises
    ------
    PlanningError
        OMPL returned another status (e.g. a crash or an invalid setup).
    """
    with ompl_session(seed):
        t0 = time.perf_counter()
        problem = EnergyProblem(arrays, min_energy_per_metre_j, start, goal, max_evaluations)
        planner = make_planner(name, problem, settings)
        deadline = None if time_limit_s is None else t0 + time_limit_s
        status = planner.solve(problem.termination(deadline))
        kind = status.getStatus()
        ps = ob.PlannerStatus
        waypoints = None
        if kind in (ps.EXACT_SOLUTION, ps.APPROXIMATE_SOLUTION) and problem.pdef.hasSolution():
            waypoints = EnergyProblem.coords(problem.pdef.getSolutionPath())
            exact = kind == ps.EXACT_SOLUTION and problem.pdef.hasExactSolution()
            result = "exact" if exact else "approximate"
        elif kind == ps.TIMEOUT:
            result = "timeout"
        elif kind == ps.INFEASIBLE:
            result = "infeasible"
        else:
            raise PlanningError(f"OMPL planner {name!r} returned status {status.asString()!r}")
        elapsed = time.perf_counter() - t0
        evaluations = problem.evaluations
        planner.clear()
        del planner, problem
        return result, waypoints, elapsed, evaluations
