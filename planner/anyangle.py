"""Any-angle planner on the energy objective: Theta* in a corridor around a lattice route, then a compiled polish.

:func:`anyangle_path` finds a route whose segments may point in any direction:

1. a *guide*: the minimum-drive-energy route of a coarse lattice (:class:`~planner.Lattice`
   at ``guide_stride_cells``, cached on the cost like every lattice graph; a passage too
   narrow for it falls back to the 1-cell lattice);
2. a *corridor*: the free cells within ``corridor_cells`` of the guide;
3. *Theta**: an A* over the corridor cells' centres (the start and goal cells stand for
   the exact start and goal points) with the 16 lattice moves, where each node reached
   from node ``u`` also tries the straight segment from ``u``'s parent and keeps the
   cheaper — so vertices stay where the route must bend and straight stretches are single
   segments. Every segment is priced by the library's cell walk (the kernel behind
   :meth:`EnergyCost.segment_energy_j`), directed (uphill ``!=`` downhill) and ``inf``
   across a blocked cell, so a node's cost is the exact drive energy of its polyline. The
   heuristic is the lattice A*'s, ``min_energy_per_metre_j * |node - goal|``, which never
   overestimates (every route to the goal is at least that long and every metre of it
   costs at least that much).

The answer is the cheaper (drive energy) of the Theta* route and the guide, so with
``guide_stride_cells=1`` it never costs more than the 1-cell lattice optimum. A coarser guide
(default 2 cells: the query is about 1.6 times as fast on 512 x 512 maps) is not bound to the
1-cell optimum's corridor: it matched or beat that optimum in 200 seeded queries on 96 x 96
maps with rocks and walls, where a stride of 4 sometimes went round a wall the worse way (up
to 15 % more energy). Like the lattice, the search minimises drive energy; turn energies are
added when the route is evaluated.

:func:`polish_path` is the any-angle planner's refinement (``plan_route(...,
planner="anyangle")`` with ``refine=True``): the route is cut into pieces of a few cells and
a compiled pattern search moves each vertex with a step of its own (halved where a move
fails, grown back where a neighbour moved), minimising drive + turn energy; vertices that do
not pay for themselves are dropped. The result is kept only if its true energy
(:meth:`EnergyCost.path_energy_j`) went down.

Theta* is not an exact any-angle search (it keeps one parent per cell), and the corridor
limits it to the guide's neighbourhood; on the 512 x 512 benchmark maps the polished routes
come within 0.2 % of the best found by much heavier searches (a full-map Theta*, a node grid
of a half and a third of a cell, neighbourhoods of up to 8 cells, long polishing), which all
end in the same local optima. Its one parent per cell can still commit to a worse way than
the lattice's: over 12 queries on four seeded 512 x 512 maps the polished route beat the
lattice + refinement in 11 and lost in one (0.9896 against 0.9867 of the lattice optimum).
``benchmarks/plan_bench.py`` measures quality against time.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base.checks import check_int, check_real
from terrawatt_base.errors import InvalidParameterError

from .edge_cost import EnergyCost
from .kernels import KEEP_RTOL
from .kernels.anyangle import NEIGHBOURS_16, corridor_index, polish_polyline, theta_star
from .lattice import Lattice
from .points import as_points
from .tables import CostTables

__all__ = [
    "AnyAnglePath",
    "anyangle_path",
    "polish_path",
    "warm_up_anyangle",
    "DEFAULT_POLISH_SPACINGS_CELLS",
]

#: Piece lengths (cells) of the successive polishing passes: coarse pieces move long
#: stretches cheaply, short ones let the route bend where the ground changes.
DEFAULT_POLISH_SPACINGS_CELLS = (8.0, 3.0, 1.5)


@dataclass(frozen=True)
class AnyAnglePath:
    """An any-angle query's answer.

    Attributes
    ----------
    found : bool
        Whether a route joins start and goal.
    waypoints_m : ndarray, shape (K, 2)
        ``start, ..., goal``; empty (0, 2) when not found.
    drive_energy_j : float
        Drive energy (J) of the route's segments (turns not included); ``inf`` when not found.
    guide_energy_j : float
        Drive energy (J) of the guide lattice route; ``inf`` when there is none.
    guide_stride_cells : int
        Stride of the lattice that gave the guide (1 after a fallback).
    corridor_nodes : int
        Number of cells the Theta* search could use.
    solve_time_s : float
        Seconds spent in the query (building lattice graphs excluded: map preparation).
    """

    found: bool
    waypoints_m: np.ndarray
    drive_energy_j: float
    guide_energy_j: float
    guide_stride_cells: int
    corridor_nodes: int
    solve_time_s: float

    def __post_init__(self) -> None:
        wp = np.asarray(self.waypoints_m, dtype=float)
        if wp.ndim != 2 or wp.shape[1] != 2:
            raise InvalidParameterError(f"waypoints_m must have shape (K, 2), got {wp.shape!r}")
        if self.found != (wp.shape[0] >= 2):
            raise InvalidParameterError(f"found={self.found!r} but waypoints_m has {wp.shape[0]} points")
        wp.setflags(write=False)
        object.__setattr__(self, "waypoints_m", wp)


def anyangle_path(
    cost: EnergyCost,
    start_xy_m: Any,
    goal_xy_m: Any,
    *,
    guide_stride_cells: int = 2,
    corridor_cells: int = 12,
) -> AnyAnglePath:
    """Minimum-drive-energy any-angle route: Theta* in a corridor around a coarse lattice route.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs and blocked cells.
    start_xy_m, goal_xy_m : (float, float)
        Points on the map (m).
    guide_stride_cells : int
        Node spacing (cells, >= 1) of the lattice that gives the guide route. Its graph is
        built once per cost and stride (:meth:`Lattice.for_cost`), outside the timed query.
    corridor_cells : int
        Half-width (cells, >= 1) of the corridor around the guide that the Theta* search may use.

    Returns
    -------
    AnyAnglePath
        ``found=False`` when neither the guide lattice nor the 1-cell lattice joins the points.

    Raises
    ------
    InvalidParameterError
        Bad points or settings, ``cost`` not an EnergyCost.
    OutOfBoundsError
        A point outside the map.

    Examples
    --------
    >>> from planner import EnergyCost
    >>> from terrain import flat_map
    >>> from planner import CostSpec
    >>> cost = CostSpec().build(flat_map((30, 40), 1.0))
    >>> path = anyangle_path(cost, (2.0, 3.0), (37.0, 21.0))
    >>> path.waypoints_m.tolist()  # level ground: the straight line, at any angle
    [[2.0, 3.0], [37.0, 21.0]]
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    stride = check_int("guide_stride_cells", guide_stride_cells, low=1)
    width = check_int("corridor_cells", corridor_cells, low=1)
    pts = as_points([start_xy_m, goal_xy_m], "start/goal")
    cost.check_inside(pts, "start/goal")
    start, goal = pts
    rows, cols = cost.shape
    stride = min(stride, max(1, min(rows, cols) // 2))  # a map too small for the coarse node grid
    guide_lattice = Lattice.for_cost(cost, stride)  # map preparation: not timed
    t0 = time.perf_counter()
    guide = guide_lattice.shortest_path(start, goal, weight="energy")
    if not guide.found and stride > 1:  # a passage too narrow for the coarse lattice
        stride = 1
        t_build = time.perf_counter()
        fine = Lattice.for_cost(cost, 1)
        t0 += time.perf_counter() - t_build  # building the 1-cell graph is map preparation
        guide = fine.shortest_path(start, goal, weight="energy")
    if not guide.found:
        return AnyAnglePath(False, np.empty((0, 2)), math.inf, math.inf, stride, 0, time.perf_counter() - t0)
    arr = cost.arrays
    wp = guide.waypoints_m
    index, node_r, node_c = corridor_index(
        arr.cells, arr.geo, np.ascontiguousarray(wp[:, 0]), np.ascontiguousarray(wp[:, 1]), width
    )
    energy, xs, ys = theta_star(
        arr.cells, arr.grade_table, arr.geo, index, node_r, node_c, NEIGHBOURS_16,
        float(start[0]), float(start[1]), float(goal[0]), float(goal[1]),
        float(cost.min_energy_per_metre_j), float(guide.objective),
    )
    if energy < guide.objective:
        waypoints, drive = np.column_stack([xs, ys]), float(energy)
    else:
        waypoints, drive = wp, float(guide.objective)
    return AnyAnglePath(True, waypoints, drive, float(guide.objective), stride, int(node_r.size),
                        time.perf_counter() - t0)


def _densify(pts: np.ndarray, gap_m: float) -> np.ndarray:
    """The polyline with every segment cut into equal pieces of at most ``gap_m``."""
    seg = np.diff(pts, axis=0)
    pieces = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / gap_m).astype(np.int64))
    frac = np.concatenate([np.arange(k) / k for k in pieces])
    base = np.repeat(np.arange(pts.shape[0] - 1), pieces)
    return np.vstack([pts[base] + frac[:, None] * seg[base], pts[-1:]])


def polish_path(
    cost: EnergyCost,
    waypoints_m: Any,
    *,
    spacings_m: tuple[float, ...] | None = None,
    step_min_m: float | None = None,
    max_sweeps: int = 200,
) -> np.ndarray:
    """Locally optimise a valid polyline's true energy (drive + turns), ends fixed.

    One pass per entry of ``spacings_m`` (default :data:`DEFAULT_POLISH_SPACINGS_CELLS`
    cells): the segments are cut into pieces of at most that length, then a compiled pattern
    search moves every interior vertex by a step of its own (a quarter of the spacing, at
    most one cell, at first) in 8 directions, keeping the best strict improvement; a vertex
    that cannot improve halves its step, one that moved grows its neighbours' steps back to
    its own, until every step is below ``step_min_m`` (default 5 % of a cell) or after
    ``max_sweeps`` sweeps. Vertices whose removal does not raise the energy are then dropped.
    Every accepted move keeps the route valid (an invalid position costs ``inf``).

    Parameters
    ----------
    cost : EnergyCost
        Edge costs.
    waypoints_m : array_like, shape (K, 2)
        A valid route (finite energy).
    spacings_m : tuple of float, optional
        Piece lengths (m, > 0) of the passes.
    step_min_m : float, optional
        Smallest step (m, > 0).
    max_sweeps : int
        Most sweeps per pass (>= 1).

    Returns
    -------
    ndarray, shape (K', 2)
        A route whose :meth:`EnergyCost.path_energy_j` is at most the input's (the input
        itself when no pass lowered it).

    Raises
    ------
    InvalidParameterError
        Bad shape or NaN, a route that crosses a blocked cell, bad settings.
    OutOfBoundsError
        A waypoint outside the map.
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    pts = as_points(waypoints_m, "waypoints_m")
    before = cost.path_energy_j(pts)
    if not math.isfinite(before):
        raise InvalidParameterError("waypoints_m crosses a blocked cell; polish_path needs a valid route")
    d = cost.terrain.cell_size_m
    if spacings_m is None:
        spacings = tuple(s * d for s in DEFAULT_POLISH_SPACINGS_CELLS)
    else:
        spacings = tuple(check_real("spacings_m", s, low=0.0, low_inclusive=False) for s in spacings_m)
        if not spacings:
            raise InvalidParameterError("spacings_m must name at least one piece length, got ()")
    step_min = 0.05 * d if step_min_m is None else check_real("step_min_m", step_min_m, low=0.0, low_inclusive=False)
    max_sweeps = check_int("max_sweeps", max_sweeps, low=1)
    if pts.shape[0] < 2:
        return pts.copy()
    arr = cost.arrays
    out = pts
    for gap in spacings:
        dense = _densify(out, gap)
        xs = np.ascontiguousarray(dense[:, 0])
        ys = np.ascontiguousarray(dense[:, 1])
        m = polish_polyline(arr.cells, arr.grade_table, arr.turn_table, arr.geo, xs, ys,
                            min(d, gap / 4.0), step_min, max_sweeps, KEEP_RTOL)
        out = np.column_stack([xs[:m], ys[:m]])
    return out if cost.path_energy_j(out) <= before * (1.0 + KEEP_RTOL) else pts.copy()


def warm_up_anyangle() -> float:
    """Compile (or load from numba's on-disk cache) the any-angle kernels; returns the seconds spent."""
    t0 = time.perf_counter()
    cost = EnergyCost(TerrainMap(np.zeros((8, 8)), 1.0), np.zeros((8, 8), np.int32),
                      CostTables(np.ones((1, 3)), np.ones((1, 2))), speed_mps=1.0, battery_voltage_v=1.0,
                      turn_rate_radps=1.0)
    path = anyangle_path(cost, (0.5, 0.5), (7.5, 6.5), guide_stride_cells=1)
    polish_path(cost, np.vstack([path.waypoints_m[:1], [[2.0, 5.0]], path.waypoints_m[-1:]]))
    return time.perf_counter() - t0
