"""Coarse-to-fine planning for big maps: a lattice route on a downsampled cost, then the 1-cell lattice in a corridor.

:class:`CoarseOptions` says how (factor, corridor, the windows of a GeoTIFF read by windows),
:class:`CoarseToFine` what was found. The door is :func:`planner.plan_coarse_to_fine` (a
map in memory or a GeoTIFF read by windows, :mod:`planner.coarse_geotiff`) or
``plan_route(planner="coarse")``. On a map in memory, :func:`coarse_to_fine_in_memory` (1)
downsamples the cost by ``factor`` (elevation averaged over
each block of ``factor x factor`` cells, a block blocked when most of its cells are, its
ground the most common one; the energy tables are the fine cost's), (2) finds the
minimum-energy route on that coarse map's 16-connected lattice, (3) marks a corridor of
``corridor_m`` around it and (4) searches the directed 16-connected 1-cell lattice of the
full-resolution cost restricted to the corridor's free cells (:mod:`planner.kernels.corridor`).
The corridor graph is a subgraph of the full 1-cell lattice (:class:`~planner.Lattice`),
start and goal are joined the same way, so the route's drive energy is never below the
full-resolution lattice optimum; ``compare=True`` computes that optimum and the ratio.
When the corridor holds no route (a passage the coarse map could not see) the corridor is
widened four times, then the whole map is searched (``fallback`` says which) unless start
and goal lie in different free regions (then the route is ``infeasible`` at once).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from terrain import Grid, TerrainMap
from terrawatt_base.checks import check_bool, check_instance, check_int, check_optional_real
from terrawatt_base.errors import BlockedPositionError, InvalidParameterError

from .edge_cost import EnergyCost
from .kernels import astar
from .kernels.corridor import corridor_weights
from .lattice import LATTICE_OFFSETS, Lattice
from .points import as_points
from .route import Route, empty_route, evaluate_route
from .tables import CostTables

__all__ = [
    "CoarseOptions",
    "CoarseToFine",
    "coarse_to_fine_in_memory",
    "downsample_cost",
    "COARSE_FALLBACKS",
    "coarse_layers",
    "coarse_cost",
    "corridor_mask",
    "search_corridor",
    "check_free_point",
    "merge_straight",
]

#: What a coarse-to-fine plan fell back to: nothing, a corridor four times wider, the whole map.
COARSE_FALLBACKS = ("none", "wider corridor", "whole map")
_HALF = LATTICE_OFFSETS[:8]
#: Tile side (cells) of the coarse stage read by windows, rounded down to a multiple of the factor.
DEFAULT_WINDOW_CELLS = 1024
#: Most cells (halo included) of one fine window read from a GeoTIFF before the fine stage chains windows along
#: the route: 8192^2, about 7 GiB once priced (some 110 bytes per cell, measured).
DEFAULT_FINE_WINDOW_BUDGET_CELLS = 8192 * 8192


@dataclass(frozen=True)
class CoarseOptions:
    """How to plan coarse-to-fine: one value, checked when made.

    Attributes
    ----------
    factor : int
        Downsampling factor (>= 2): the coarse lattice has ``factor**2`` times fewer nodes.
    corridor_m : float, optional
        Half-width (m, > 0) of the corridor searched at full resolution; default three coarse
        cells (``3 * factor * cell_size_m``). A corridor that holds no route is widened four
        times, then the whole map is searched (:data:`COARSE_FALLBACKS`).
    window_cells : int, optional
        A GeoTIFF read by windows: the tile side (cells) of the coarse stage, a multiple of
        ``factor``; default :data:`DEFAULT_WINDOW_CELLS` rounded down to a multiple of ``factor``.
    fine_window_budget_cells : int, optional
        A GeoTIFF read by windows: the most full-resolution cells (halo included, >= 16) one
        fine window may hold; a bigger corridor is followed in chained windows. Default
        :data:`DEFAULT_FINE_WINDOW_BUDGET_CELLS` (8192^2).
    band : int, optional
        A GeoTIFF read by windows: its 1-based elevation band (default: the only one).

    Raises
    ------
    InvalidParameterError
        A bad value (the message names it), or ``window_cells`` not a multiple of ``factor``.

    Examples
    --------
    >>> CoarseOptions(factor=8).tile_side
    1024
    >>> CoarseOptions(factor=3, corridor_m=12.0).tile_side
    1023
    """

    factor: int = 4
    corridor_m: float | None = None
    window_cells: int | None = None
    fine_window_budget_cells: int | None = None
    band: int | None = None

    def __post_init__(self) -> None:
        owner = "CoarseOptions"
        f = check_int("factor", self.factor, low=2, owner=owner)
        check_optional_real("corridor_m", self.corridor_m, low=0.0, low_inclusive=False, owner=owner)
        if self.window_cells is not None:
            w = check_int("window_cells", self.window_cells, low=2, owner=owner)
            if w % f:
                raise InvalidParameterError(
                    f"window_cells={w} is not a multiple of factor={f}: a coarse block would straddle two windows; "
                    f"use e.g. window_cells={f * max(1, round(w / f))}", parameter=("window_cells", "factor"))
        if self.fine_window_budget_cells is not None:
            check_int("fine_window_budget_cells", self.fine_window_budget_cells, low=16, owner=owner)
        if self.band is not None:
            check_int("band", self.band, low=1, owner=owner)

    @property
    def tile_side(self) -> int:
        """Tile side (cells) of the coarse stage read by windows."""
        if self.window_cells is None:
            return self.factor * max(1, DEFAULT_WINDOW_CELLS // self.factor)
        return int(self.window_cells)

    @property
    def budget_cells(self) -> int:
        """Most cells (halo included) of one fine window read by windows."""
        if self.fine_window_budget_cells is None:
            return DEFAULT_FINE_WINDOW_BUDGET_CELLS
        return int(self.fine_window_budget_cells)

    def corridor_for(self, cell_size_m: float) -> float:
        """The corridor half-width (m) on a map of ``cell_size_m`` cells: ``corridor_m``, or three coarse cells."""
        return 3.0 * self.factor * cell_size_m if self.corridor_m is None else float(self.corridor_m)


@dataclass(frozen=True)
class CoarseToFine:
    """A coarse-to-fine plan and how it was found.

    Attributes
    ----------
    route : Route
        The full-resolution route (``planner="coarse-to-fine"``), evaluated on the fine cost.
    coarse_waypoints_m : ndarray, shape (K, 2)
        The coarse lattice route (empty when the coarse map joins no route).
    factor : int
        Downsampling factor.
    corridor_m : float
        Corridor half-width (m) actually searched (after any widening).
    corridor_cells : int
        Free fine cells in the corridor (the searched graph's nodes).
    objective_j : float
        Drive energy (J) of the corridor lattice route (``inf`` when none).
    optimum_j : float
        Drive energy (J) of the full-resolution 1-cell lattice optimum; NaN unless compared.
    fallback : str
        One of :data:`COARSE_FALLBACKS`.
    coarse_time_s, fine_time_s, optimum_time_s : float
        Seconds spent downsampling and planning on the coarse map; building and searching
        the corridor graph; computing the optimum (0 unless compared).
    fine_window_cells : int
        Full-resolution cells the fine stage read from the file, summed over the windows it
        read (0: the whole map was given in memory).
    fine_windows : tuple of (int, int, int, int)
        The windows the fine stage read, in order, as map ``(row_start, row_stop, col_start,
        col_stop)`` with their halo cells (empty for a map in memory).
    grid : Grid or None
        The whole map's full-resolution grid.
    coarse_map : TerrainMap or None
        The downsampled map the coarse route was planned on (elevation, blocked blocks as
        obstacles): a view of the whole map even when only windows of it were read.
    fine_map : TerrainMap or None
        The full-resolution map the route was searched and evaluated on: the cost's map, or
        the window of the map read from a GeoTIFF by windows (in the
        map's coordinates); None when no fine search ran, or when it ran in chained windows
        (no one window holds the route; ``fine_windows`` lists them).
    """

    route: Route
    coarse_waypoints_m: np.ndarray
    factor: int
    corridor_m: float
    corridor_cells: int
    objective_j: float
    optimum_j: float
    fallback: str
    coarse_time_s: float
    fine_time_s: float
    optimum_time_s: float
    fine_window_cells: int = 0
    fine_windows: tuple[tuple[int, int, int, int], ...] = ()
    grid: Grid | None = None
    coarse_map: TerrainMap | None = field(default=None, repr=False, compare=False)
    fine_map: TerrainMap | None = field(default=None, repr=False, compare=False)

    @property
    def ratio_to_optimum(self) -> float:
        """Corridor route energy over the full-resolution optimum (>= 1); NaN when not computed."""
        if not (math.isfinite(self.optimum_j) and self.optimum_j > 0 and math.isfinite(self.objective_j)):
            return math.nan
        return self.objective_j / self.optimum_j

    def summary(self) -> dict:
        """Scalars as a flat dict of JSON-friendly values."""
        return {
            **self.route.summary(), "factor": self.factor, "corridor_m": self.corridor_m,
            "corridor_cells": self.corridor_cells, "objective_j": self.objective_j, "optimum_j": self.optimum_j,
            "ratio_to_optimum": self.ratio_to_optimum, "fallback": self.fallback,
            "coarse_time_s": self.coarse_time_s, "fine_time_s": self.fine_time_s,
            "optimum_time_s": self.optimum_time_s, "fine_window_cells": self.fine_window_cells,
            "fine_windows": len(self.fine_windows),
            "fine_window_max_cells": max(((r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in self.fine_windows), default=0),
        }


def _blocks(arr: np.ndarray, f: int) -> np.ndarray:
    """``arr`` as a (R/f, f, C/f, f) view, edge-padded to multiples of ``f`` when needed."""
    rows, cols = arr.shape
    pr, pc = -rows % f, -cols % f
    if pr or pc:
        arr = np.pad(arr, ((0, pr), (0, pc)), mode="edge")
    return arr.reshape(arr.shape[0] // f, f, arr.shape[1] // f, f)


def downsample_cost(cost: EnergyCost, factor: int) -> EnergyCost:
    """The cost on a grid ``factor`` times coarser, with the fine cost's energy tables.

    Each coarse cell averages the elevation of its ``factor x factor`` block, takes the
    block's most common table row, and is an obstacle when more than half of the block is
    blocked; the coarse slope limit is the fine one.

    Raises
    ------
    InvalidParameterError
        ``cost`` not an EnergyCost, ``factor`` not an integer >= 2, or a coarse grid under 2 x 2.
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    f = check_int("factor", factor, low=2)
    rows, cols = cost.shape
    if -(-rows // f) < 2 or -(-cols // f) < 2:
        raise InvalidParameterError(f"factor={f} leaves fewer than 2 x 2 coarse cells on a {rows} x {cols} map")
    elevation, blocked, best = coarse_layers(cost.terrain.elevation_m, cost.blocked, cost.ground_rows, f)
    return coarse_cost(cost, elevation, blocked, best, cost.terrain.cell_size_m * f, cost.terrain.origin_xy_m,
                       cost.terrain.crs)


def coarse_layers(elevation_m: np.ndarray, blocked: np.ndarray, ground_rows: np.ndarray, factor: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Block reductions of :func:`downsample_cost`: mean elevation, majority blocked, most common table row.

    Blocks are ``factor x factor`` cells from cell (0, 0); a partial last block is edge-padded
    (its last row / column repeated). Blocks are independent, so a map cut into parts whose
    sides are multiples of ``factor`` (the last parts excepted) gives, part by part, the
    same numbers as the whole map.

    Returns
    -------
    (ndarray, ndarray, ndarray)
        Coarse elevation (float64), blocked (bool, more than half the block) and table row
        (int64, the most common; ties to the lowest row).
    """
    f = int(factor)
    elevation = _blocks(elevation_m, f).mean(axis=(1, 3))
    coarse_blocked = _blocks(blocked, f).mean(axis=(1, 3)) > 0.5
    ground = _blocks(ground_rows, f)
    best = np.full(elevation.shape, -1, dtype=np.int64)
    count = np.zeros(elevation.shape, dtype=np.int64)
    for row in np.unique(ground_rows).tolist():
        n = (ground == row).sum(axis=(1, 3))
        better = n > count
        best[better], count[better] = row, n[better]
    return elevation, coarse_blocked, best


def coarse_cost(fine: EnergyCost, elevation_m: np.ndarray, blocked: np.ndarray, ground_rows: np.ndarray,
                cell_size_m: float, origin_xy_m: tuple[float, float], crs: str | None) -> EnergyCost:
    """The coarse map of :func:`coarse_layers` priced with the mean energy tables and settings of ``fine``."""
    coarse = TerrainMap(elevation_m, cell_size_m, origin_xy_m, obstacle=blocked, crs=crs)
    tables = fine.tables
    return EnergyCost(coarse, ground_rows, CostTables(tables.grade_table_j_per_m, tables.turn_table_j,
                                                      tables.ground_labels),
                      speed_mps=fine.speed_mps, max_slope_rad=fine.max_slope_rad,
                      battery_voltage_v=fine.battery_voltage_v, turn_rate_radps=fine.turn_rate_radps)


def corridor_mask(coarse: EnergyCost, waypoints_m: np.ndarray, width_m: float) -> np.ndarray:
    """Coarse cells within about ``width_m`` of the coarse route (plus the coarse cell the route crosses)."""
    grid = coarse.terrain.grid
    on_route = np.zeros(grid.shape, dtype=bool)
    for a, b in zip(waypoints_m[:-1], waypoints_m[1:], strict=True):
        r, c, _ = grid.segment_cells(tuple(a), tuple(b))
        on_route[r, c] = True
    reach = width_m / grid.cell_size_m + 1.0  # + the coarse cell the route crosses
    return ndimage.distance_transform_edt(~on_route) <= reach


def _corridor(coarse: EnergyCost, waypoints: np.ndarray, width_m: float, f: int, shape: tuple[int, int]) -> np.ndarray:
    """Fine cells within about ``width_m`` of the coarse route (dilated on the coarse grid)."""
    near = corridor_mask(coarse, waypoints, width_m)
    return np.repeat(np.repeat(near, f, axis=0), f, axis=1)[: shape[0], : shape[1]]


def merge_straight(pts: np.ndarray) -> np.ndarray:
    """Drop interior vertices where the polyline goes straight on (lattice moves in a row), ends kept."""
    if pts.shape[0] < 3:
        return pts
    seg = np.diff(pts, axis=0)
    cross = seg[:-1, 0] * seg[1:, 1] - seg[:-1, 1] * seg[1:, 0]
    dot = np.einsum("ij,ij->i", seg[:-1], seg[1:])
    scale = np.hypot(*seg[:-1].T) * np.hypot(*seg[1:].T)
    straight = (np.abs(cross) <= 1e-12 * scale) & (dot > 0)
    return pts[np.concatenate([[True], ~straight, [True]])]


def search_corridor(cost: EnergyCost, start: np.ndarray, goal: np.ndarray, inside: np.ndarray, *,
                    merge: bool = True) -> tuple[float, np.ndarray, int]:
    """Best 1-cell lattice route inside ``inside`` cells: (drive energy, waypoints, number of nodes).

    Start and goal join the free nodes within 1.5 cells; the straight segment start -> goal
    is the route when no lattice route is cheaper (``inf`` energy: none at all). The
    waypoints are start, every node of the route (a node may sit on start) and goal; with
    ``merge`` (default) the nodes where the route goes straight on are dropped
    (:func:`merge_straight`)."""
    free = inside & ~cost.blocked
    node_rows, node_cols = (a.astype(np.int64) for a in np.nonzero(free))
    n = node_rows.size
    index = np.full(cost.shape, -1, dtype=np.int32)
    index[node_rows, node_cols] = np.arange(n, dtype=np.int32)
    arr = cost.arrays
    w = corridor_weights(arr.cells, arr.grade_table, arr.geo, node_rows, node_cols, index, _HALF)
    mask = np.isfinite(w)
    # the target of move k of node u: the node of cell (row + dr, col + dc); a finite move stays inside
    targets = index[(node_rows[:, None] + LATTICE_OFFSETS[None, :, 0])[mask],
                    (node_cols[:, None] + LATTICE_OFFSETS[None, :, 1])[mask]]
    del index
    indptr = np.zeros(n + 1, dtype=np.int32)
    np.cumsum(mask.sum(axis=1), out=indptr[1:])
    data = w[mask]
    d = cost.terrain.cell_size_m
    xs = cost.terrain.origin_xy_m[0] + (node_cols + 0.5) * d
    ys = cost.terrain.origin_xy_m[1] + (node_rows + 0.5) * d

    def joined(p: np.ndarray) -> np.ndarray:
        return np.flatnonzero((np.abs(xs - p[0]) <= 1.5 * d) & (np.abs(ys - p[1]) <= 1.5 * d)
                              & (np.hypot(xs - p[0], ys - p[1]) <= 1.5 * d))

    src, dst = joined(start), joined(goal)
    src_xy, dst_xy = np.column_stack([xs[src], ys[src]]), np.column_stack([xs[dst], ys[dst]])
    e_src = cost.segment_energy_j(np.broadcast_to(start, src_xy.shape), src_xy)
    e_dst = cost.segment_energy_j(dst_xy, np.broadcast_to(goal, dst_xy.shape))
    best = float(cost.segment_energy_j(start, goal)[0])
    ok_s, ok_d = np.isfinite(e_src), np.isfinite(e_dst)
    chain: list[int] = []
    if ok_s.any() and ok_d.any():
        total, last, pred = astar(indptr, targets, data, np.zeros(1), np.zeros(n), 1,
                                  src[ok_s].astype(np.int64), e_src[ok_s], dst[ok_d].astype(np.int64), e_dst[ok_d],
                                  float(goal[0]), float(goal[1]), 0.0, best)
        if last >= 0 and total < best:
            best = float(total)
            node = int(last)
            while node >= 0:
                chain.append(node)
                node = int(pred[node])
    mid = np.column_stack([xs[chain[::-1]], ys[chain[::-1]]]) if chain else np.empty((0, 2))
    pts = np.vstack([start, mid, goal])
    return best, merge_straight(pts) if merge else pts, n


def check_free_point(cost: EnergyCost, name: str, point_xy_m: np.ndarray, row_col: tuple[int, int] | None = None
                     ) -> None:
    """Raise :class:`BlockedPositionError` naming ``name`` when the point lies on a blocked cell of ``cost``.

    ``row_col`` names the cell in the messages (default: its cell in ``cost``; a window's
    caller gives the whole map's)."""
    r, c = cost.terrain.rowcol(point_xy_m[0], point_xy_m[1])
    if cost.blocked[r, c]:
        rr, cc = (r, c) if row_col is None else row_col
        raise BlockedPositionError(
            f"{name} {tuple(point_xy_m.tolist())!r} m lies on a blocked cell (obstacle, or steeper than "
            f"max_slope_rad) at row {rr}, col {cc}; expected a free cell"
        )


def coarse_to_fine_in_memory(
    cost: EnergyCost,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    options: CoarseOptions,
    *,
    compare: bool = False,
) -> CoarseToFine:
    """:func:`planner.plan_coarse_to_fine` on a map in memory (its full-resolution ``cost``): module docstring.

    ``options`` gives the factor and corridor; ``compare`` also computes the full-resolution
    1-cell lattice optimum (the whole lattice: the expensive step this avoids) and the ratio.
    Raises as :func:`planner.plan_coarse_to_fine`.
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    options = check_instance("options", options, CoarseOptions)
    f = options.factor
    compare = check_bool("compare", compare)
    pts = as_points([start_xy_m, goal_xy_m], "start/goal")
    cost.check_inside(pts, "start/goal")
    start, goal = pts
    if np.array_equal(start, goal):
        raise InvalidParameterError(f"start equals goal {tuple(start.tolist())!r} m; expected two different points")
    for name, p in (("start_xy_m", start), ("goal_xy_m", goal)):
        check_free_point(cost, name, p)
    width = options.corridor_for(cost.terrain.cell_size_m)

    t0 = time.perf_counter()
    coarse = downsample_cost(cost, f)
    coarse_path = Lattice(coarse, 1).shortest_path(start, goal)
    coarse_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    objective, waypoints, n_nodes, fallback = math.inf, np.empty((0, 2)), 0, COARSE_FALLBACKS[0]
    if coarse_path.found:
        for label, scale in zip(COARSE_FALLBACKS[:2], (1.0, 4.0), strict=True):
            inside = _corridor(coarse, coarse_path.waypoints_m, width * scale, f, cost.shape)
            objective, waypoints, n_nodes = search_corridor(cost, start, goal, inside)
            if math.isfinite(objective):
                width, fallback = width * scale, label
                break
    if not math.isfinite(objective):
        fallback = COARSE_FALLBACKS[2]
        labels = cost.components()
        if labels[cost.terrain.rowcol(*start)] == labels[cost.terrain.rowcol(*goal)]:  # else: no route anywhere
            objective, waypoints, n_nodes = search_corridor(cost, start, goal, np.ones(cost.shape, dtype=bool))
    fine_s = time.perf_counter() - t0
    if math.isfinite(objective):
        route = evaluate_route(cost, waypoints, planner="coarse-to-fine", planning_time_s=coarse_s + fine_s)
    else:
        route = empty_route("infeasible", "coarse-to-fine", coarse_s + fine_s, cost.battery_voltage_v)
    optimum, optimum_s = math.nan, 0.0
    if compare:
        t0 = time.perf_counter()
        best = Lattice.for_cost(cost, 1).shortest_path(start, goal)
        optimum = best.objective if best.found else math.nan
        optimum_s = time.perf_counter() - t0
    return CoarseToFine(route, coarse_path.waypoints_m, f, width, n_nodes, objective, optimum, fallback,
                        coarse_s, fine_s, optimum_s, grid=cost.terrain.grid, coarse_map=coarse.terrain,
                        fine_map=cost.terrain)
