"""Route refinement on the true energy: pattern-search relaxation, OMPL energy shortcuts, line-of-sight pulls.

Each function takes an :class:`~planner.EnergyCost` (read through its public queries and
:attr:`~planner.EnergyCost.arrays`) and a valid polyline, and returns one whose true energy
(segments plus turns, :meth:`~planner.EnergyCost.path_energy_j`) is not higher —
:func:`string_pull` excepted, which shortens (shortest-distance routes).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from ompl import geometric as og

from terrawatt_base.checks import check_bool, check_int, check_real, check_seed, real_array
from terrawatt_base.errors import InvalidParameterError

from .kernels import KEEP_RTOL, relax_polyline, string_pull_indices
from .ompl.problem import EnergyProblem, ompl_session
from .points import as_points

__all__ = ["relax_path", "refine_route", "string_pull"]


def relax_path(
    cost: Any,
    waypoints_m: Any,
    *,
    spacing_m: float | None = None,
    levels: int = 3,
    min_gain: float = 1e-3,
    step_m: float | None = None,
    max_sweeps: int = 300,
) -> np.ndarray:
    """Locally optimise a valid polyline's true energy (drive + turns), ends fixed.

    Coarse to fine, over ``levels`` passes: each pass cuts the segments into pieces of
    at most its spacing (``spacing_m``, default 8 cells, halved at every further pass:
    8, 4, 2 cells by default), so the route can bend where the ground changes; a
    compiled pattern search then moves each interior vertex in 8 directions while the
    energy drops, starting with a step of ``min(step_m, spacing / 4)`` (``step_m``
    default one cell) and halving it down to 1 % of a cell; finally vertices whose
    removal does not raise the energy are dropped. Every accepted move keeps the route
    valid (an invalid move costs inf). Coarse passes move long stretches at little cost;
    fine ones let the route follow ground and slope boundaries. A finer pass runs only
    while the previous one lowered the energy by at least ``min_gain`` (relative): on
    512 x 512 procedural maps the first pass does most of the work and the finer ones
    add 0.05–0.6 %, at two to four times its cost.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs.
    waypoints_m : array_like, shape (K, 2)
        A valid route (finite energy).

    Returns
    -------
    ndarray, shape (K', 2)
        A route whose :meth:`EnergyCost.path_energy_j` is at most the input's (up to a relative
        1e-9 of rounding, which lets exactly collinear vertices go).

    Raises
    ------
    InvalidParameterError
        Bad shape or NaN, a route that crosses a blocked cell, bad settings.
    OutOfBoundsError
        A waypoint outside the map.
    """
    pts = as_points(waypoints_m, "waypoints_m")
    before = cost.path_energy_j(pts)
    if not math.isfinite(before):
        raise InvalidParameterError("waypoints_m crosses a blocked cell; relax_path needs a valid route")
    d = cost.terrain.cell_size_m
    spacing = 8.0 * d if spacing_m is None else check_real("spacing_m", spacing_m, low=0.0, low_inclusive=False)
    step = d if step_m is None else check_real("step_m", step_m, low=0.0, low_inclusive=False)
    levels = check_int("levels", levels, low=1)
    max_sweeps = check_int("max_sweeps", max_sweeps, low=1)
    if pts.shape[0] < 2:
        return pts.copy()
    min_gain = check_real("min_gain", min_gain, low=0.0)
    arr = cost.arrays
    out = pts
    energy = before
    for level in range(int(levels)):
        gap = spacing / 2**level
        seg = np.diff(out, axis=0)
        pieces = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / gap).astype(np.int64))
        frac = np.concatenate([np.arange(k) / k for k in pieces])
        base = np.repeat(np.arange(out.shape[0] - 1), pieces)
        dense = np.vstack([out[base] + frac[:, None] * seg[base], out[-1:]])
        xs = np.ascontiguousarray(dense[:, 0])
        ys = np.ascontiguousarray(dense[:, 1])
        m = relax_polyline(
            arr.cells, arr.grade_table, arr.turn_table, arr.geo, xs, ys,
            min(step, gap / 4.0), 0.01 * d, int(max_sweeps),
        )
        out = np.column_stack([xs[:m], ys[:m]])
        previous, energy = energy, cost.path_energy_j(out)
        if energy > previous * (1.0 - min_gain):
            break
    return out if cost.path_energy_j(out) <= before * (1.0 + KEEP_RTOL) else pts.copy()


def string_pull(cost: Any, waypoints_m: Any) -> np.ndarray:
    """Shorten a valid polyline by greedy line-of-sight shortcuts (never longer, stays valid).

    From each kept vertex, jump to the farthest later vertex reachable by one free segment
    before the first blocked one. Ignores energy: it is for shortest-distance routes.
    """
    pts = as_points(waypoints_m, "waypoints_m")
    if pts.shape[0] < 3:
        return pts.copy()
    arr = cost.arrays
    idx = string_pull_indices(arr.cells, arr.grade_table, arr.geo, np.array(pts[:, 0]), np.array(pts[:, 1]))
    return pts[idx].copy()


def refine_route(
    cost: Any,
    waypoints_m: Any,
    *,
    seed: int | None = None,
    max_steps: int = 300,
    rounds: int = 2,
    relax: bool = True,
) -> np.ndarray:
    """Improve a valid route with OMPL's energy-aware shortcuts; keep only true improvements.

    Each round runs ``PathSimplifier.partialShortcutPath`` and ``perturbPath`` with the energy
    objective; after each step the candidate's *true* energy (exact segments plus turns,
    :meth:`EnergyCost.path_energy_j`) is compared with the best so far and kept only if it
    went down (OMPL_NOTES trap 4: OMPL's own estimate can disagree). With ``relax``, the
    result is then polished by :func:`relax_path` (compiled vertex-wise pattern
    search on the true energy, turns included), again kept only if it lowers the energy.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs.
    waypoints_m : array_like, shape (K, 2)
        A valid route (finite energy).
    seed : int, optional
        Seeds OMPL's RNG (the refinement is random); ``None`` leaves it unseeded.
    max_steps : int
        Attempts per pass (>= 1).
    rounds : int
        Number of (shortcut, perturb) rounds (>= 1).
    relax : bool
        Finish with :func:`relax_path`.

    Returns
    -------
    ndarray, shape (K', 2)
        A route with the same ends and true energy <= the input's.

    Raises
    ------
    InvalidParameterError
        An invalid input route, or bad ``max_steps`` / ``rounds``.
    """
    pts = real_array("waypoints_m", waypoints_m, ndim=2)
    best_e = cost.path_energy_j(pts)
    if not math.isfinite(best_e):
        raise InvalidParameterError("waypoints_m crosses a blocked cell; refine_route needs a valid route")
    max_steps = check_int("max_steps", max_steps, low=1)
    rounds = check_int("rounds", rounds, low=1)
    seed = check_seed(seed)
    relax = check_bool("relax", relax)
    if pts.shape[0] < 3:
        return relax_path(cost, pts) if relax else pts.copy()
    with ompl_session(seed):
        problem = EnergyProblem(cost.arrays, cost.min_energy_per_metre_j, pts[0], pts[-1])
        simplifier = og.PathSimplifier(problem.si, problem.pdef.getGoal(), problem.objective)
        best = pts.copy()
        step_m = 2.0 * cost.terrain.cell_size_m
        for _ in range(int(rounds)):
            for op in ("shortcut", "perturb"):
                path = problem.path(best)
                if op == "shortcut":
                    simplifier.partialShortcutPath(path, int(max_steps), 0, 0.33, 0.005)
                else:
                    simplifier.perturbPath(path, step_m, int(max_steps), 0, 0.005)
                cand = EnergyProblem.coords(path)
                del path
                e = cost.path_energy_j(cand)
                if e < best_e:
                    best, best_e = cand, e
            step_m *= 0.5
        del simplifier, problem
    if relax:
        best = relax_path(cost, best)
    return drop_repeats(best)


def drop_repeats(pts: np.ndarray) -> np.ndarray:
    """``pts`` without consecutive repeated points (a zero-length segment costs nothing and its turn is
    priced across it: the price is unchanged, and a robot's command profile refuses repeated waypoints)."""
    keep = np.concatenate([[True], np.any(np.diff(pts, axis=0) != 0, axis=1)])
    if not keep[-1]:  # keep the goal itself, dropping the copy before it
        keep[np.flatnonzero(keep)[-1]] = False
        keep[-1] = True
    return pts[keep] if not keep.all() else pts
