"""The OMPL problem of one solve: state space over the map, validity from the cell walk, start/goal, termination."""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from ..kernels import CostArrays, point_free, walk_forward
from .objective import EnergyObjective

__all__ = [
    "EnergyProblem",
    "FreeCellChecker",
    "WalkMotionValidator",
    "seed_ompl",
    "ompl_session",
    "ompl_log_level",
    "ompl_seed",
    "STALL_CHECKS",
]

#: A work-bounded solve also stops after this many consecutive termination checks without an
#: objective call: a planner that stopped calling the objective (BIT* once no sample can
#: improve its route) would otherwise poll forever. Working planners were measured at most
#: ~70 checks between two objective calls.
STALL_CHECKS = 100_000


def ompl_seed(seed: int) -> int:
    """OMPL's seed for a library seed in ``[0, 2**32)``: ``seed + 1`` (OMPL treats 0 as "no
    seed"), wrapped so that it stays a 32-bit value (``2**32 - 1`` maps to 1, as seed 0 does)."""
    return int(seed) % (2**32 - 1) + 1


def seed_ompl(seed: int | None) -> None:
    """Seed OMPL's RNG for every RNG created afterwards (nothing for ``None``).

    OMPL logs an error when RNGs already exist in the process, yet the new seed does take
    effect for every RNG created afterwards (tested, whatever ran before), so that message is
    muted."""
    if seed is None:
        return
    with ompl_log_level(ou.LOG_NONE):
        ou.RNG.setSeed(ompl_seed(seed))


#: OMPL's seed is process-wide: a seed set in one thread while another thread's planner creates
#: its RNGs changes that planner's samples (dask workers of one process are threads). Every solve
#: and refinement holds this lock from its seed to its end (:func:`ompl_session`), so threads of
#: one process run OMPL one at a time and a seeded result is the one it gives alone.
_OMPL_LOCK = threading.RLock()


@contextlib.contextmanager
def ompl_session(seed: int | None) -> Iterator[None]:
    """One OMPL solve or refinement: OMPL's lock held, its log at errors only, its RNG seeded
    (:func:`seed_ompl`). Reproducible from the seed whatever other threads of the process do."""
    with _OMPL_LOCK, ompl_log_level():
        seed_ompl(seed)
        yield


@contextlib.contextmanager
def ompl_log_level(level: Any = ou.LOG_ERROR) -> Iterator[None]:
    """OMPL's log level set to ``level`` inside the block (default: errors only), restored after.

    WARN would print RejectionInfSampler's note on each informed solve: Python objectives
    cannot install a C++ cost-to-go function, so informed sampling uses the cost-to-come
    heuristic alone."""
    previous = ou.getLogLevel()
    ou.setLogLevel(level)
    try:
        yield
    finally:
        ou.setLogLevel(previous)


class FreeCellChecker(ob.StateValidityChecker):
    """A state is valid on a free cell of the map (inside, no obstacle, not too steep)."""

    def __init__(self, si: ob.SpaceInformation, arrays: CostArrays) -> None:
        super().__init__(si)
        self._cells = arrays.cells
        self._geo = arrays.geo

    def isValid(self, s):  # noqa: N802 - OMPL API
        return bool(point_free(self._cells, self._geo, s[0], s[1]))


class WalkMotionValidator(ob.MotionValidator):
    """A motion is valid when its exact cell walk crosses no blocked cell and meets no
    undrivable grade: the same compiled walk as the cost, so validity and cost never disagree."""

    def __init__(self, si: ob.SpaceInformation, arrays: CostArrays) -> None:
        super().__init__(si)
        self._cells = arrays.cells
        self._table = arrays.grade_table
        self._geo = arrays.geo

    def checkMotion(self, a, b):  # noqa: N802 - OMPL API
        return math.isfinite(walk_forward(self._cells, self._table, self._geo, a[0], a[1], b[0], b[1]))


class EnergyProblem:
    """Space, validity, objective and start/goal of one solve (build a fresh one per solve: OMPL trap 7).

    Parameters
    ----------
    arrays : CostArrays
        The edge cost's packed arrays (``EnergyCost.arrays``).
    min_energy_per_metre_j : float
        The objective's admissible per-metre bound.
    start, goal : ndarray, shape (2,)
        Checked start and goal points (m).
    max_evaluations : int or None
        Work bound of :meth:`termination` in objective ``motionCost`` calls.

    Attributes
    ----------
    space, si, pdef, objective
        The OMPL objects (``objective`` is an :class:`EnergyObjective`).
    """

    def __init__(
        self,
        arrays: CostArrays,
        min_energy_per_metre_j: float,
        start: np.ndarray,
        goal: np.ndarray,
        max_evaluations: int | None = None,
    ) -> None:
        space = ob.RealVectorStateSpace(2)
        xmin, ymin, xmax, ymax = arrays.grid.bounds
        bounds = ob.RealVectorBounds(2)
        bounds.setLow(0, xmin)
        bounds.setLow(1, ymin)
        bounds.setHigh(0, xmax)
        bounds.setHigh(1, ymax)
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        self.checker = FreeCellChecker(si, arrays)
        si.setStateValidityChecker(self.checker)
        self.validator = WalkMotionValidator(si, arrays)
        si.setMotionValidator(self.validator)
        si.setup()
        self.space, self.si = space, si
        self.objective = EnergyObjective(si, arrays, min_energy_per_metre_j)
        # A route at the admissible lower bound is optimal: planners stop there ("satisfied").
        bound = float(min_energy_per_metre_j) * math.hypot(goal[0] - start[0], goal[1] - start[1])
        self.objective.setCostThreshold(ob.Cost(bound * (1.0 + 1e-9)))
        self.start_state = self.state(start)
        self.goal_state = self.state(goal)
        pdef = ob.ProblemDefinition(si)
        # A GoalState (sampleable, as BIT* needs; OMPL trap 9); threshold well below a cell.
        pdef.setStartAndGoalStates(self.start_state, self.goal_state, 1e-6 * arrays.grid.cell_size_m)
        pdef.setOptimizationObjective(self.objective)
        self.pdef = pdef
        self.max_evaluations = max_evaluations

    @property
    def evaluations(self) -> int:
        """Objective ``motionCost`` calls so far."""
        return self.objective.evaluations

    def state(self, xy: np.ndarray):
        """A new OMPL state at ``xy`` (m)."""
        s = self.space.allocState()
        s[0] = float(xy[0])
        s[1] = float(xy[1])
        return s

    def path(self, waypoints: np.ndarray):
        """An OMPL geometric path through ``waypoints``."""
        path = og.PathGeometric(self.si)
        for p in waypoints:
            path.append(self.state(p))
        return path

    @staticmethod
    def coords(path) -> np.ndarray:
        """Copy a path's coordinates out at once (states are views, OMPL trap 5)."""
        n = path.getStateCount()
        out = np.empty((n, 2))
        for i in range(n):
            s = path.getState(i)
            out[i, 0] = s[0]
            out[i, 1] = s[1]
        return out

    def termination(self, deadline: float | None):
        """A termination condition: the work bound reached (``max_evaluations`` objective calls),
        the planner stalled (:data:`STALL_CHECKS` checks in a row without an objective call), or
        ``time.perf_counter() >= deadline``. The work counts are deterministic."""
        objective, max_evals = self.objective, self.max_evaluations
        state = [0, -1]  # checks since the last new objective call, evaluations seen then

        def done() -> bool:
            if max_evals is not None:
                evaluations = objective.evaluations
                if evaluations >= max_evals:
                    return True
                if evaluations == state[1]:
                    state[0] += 1
                    if state[0] >= STALL_CHECKS:
                        return True
                else:
                    state[0], state[1] = 0, evaluations
            return deadline is not None and time.perf_counter() >= deadline

        return ob.PlannerTerminationCondition(done)
