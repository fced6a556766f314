"""Coarse-to-fine planning straight from a GeoTIFF DEM larger than memory: the coarse map tile by tile, the fine stage in windows.

:func:`coarse_to_fine_windowed` is the branch of :func:`planner.plan_coarse_to_fine` that
never holds the whole raster (:class:`terrain.DemWindows`):

1. **coarse stage** — the DEM is read in block-aligned tiles (side a multiple of ``factor``,
   with one halo cell so that slopes equal the whole map's); each tile is priced with
   ``cost_from`` and reduced to coarse cells (:func:`planner.coarse.coarse_layers`: block-mean
   elevation, majority blocked, most common table row), so memory holds one tile plus the
   coarse grid; a coarse block never straddles two tiles, so the coarse cost equals
   :func:`planner.coarse.downsample_cost` of the whole-map cost. The coarse lattice route follows.
2. **fine stage** — the full-resolution window holding the corridor's bounding box (plus two
   cells for the lattice's moves and one halo cell for slopes) is read, priced with
   ``cost_from`` (a georeferenced TerrainMap: coordinates stay the map's) and searched as
   :func:`planner.coarse.search_corridor` does on the whole map. When the corridor holds no
   route it is widened four times, and a bigger window read if the wider one leaves the
   window; the last fallback reads the whole map (``fallback == "whole map"``; then memory
   holds the whole map, as a map in memory would).

The fine window is a rectangle: a corridor along the map's diagonal has a bounding box of
most of the map. When that window (halo included) would hold more than
``options.fine_window_budget_cells`` the fine stage runs in **chained windows** instead
(:func:`planner.coarse_chain.chain_corridor`): stretches of the coarse route of a few
thousand fine cells, each read as the window around its part of the corridor (never above
the budget), the route searched from the point reached to the stretch's far end and only its
first two thirds kept, so memory is bounded by the budget whatever the route's extent.
``fine_windows`` lists the windows read. The whole-map fallback then runs only if the whole
map fits the budget (else :class:`PlanningError`).

With the physics presets (``cost_from`` None, or a :class:`~planner.CostSpec` without a model,
an energy model or ground parameters of its own) the coarse stage does not build an EnergyCost per tile: such a cost
of a window (no obstacles, ground unknown) blocks exactly the cells whose slope
(:func:`terrain.surface.surface_layers`, the formula TerrainMap uses) exceeds its
slope limit and gives every cell the unknown ground's table row, so the tile's blocked
cells and rows are computed from those two facts of the cost priced on the first window —
the same numbers, 1.6 times faster (41 vs 66 ms per 1024^2 tile, measured).

With one window, the route, its energy and the coarse route equal those of
``plan_coarse_to_fine(cost_from(read_geotiff(path)), ...)`` (the map in memory): the same numbers go through the
same operations, with cell coordinates counted from the window's corner instead of the map's
(``origin + k * cell`` sums): bit for bit when the origin and cell size are exact binary
fractions (whole metres, as DEMs usually are), else within rounding (about 1e-12 relative).
Chained windows give another route (junctions where the windows meet), a few tenths of a
percent from it either way: a window's search may join its start and target by one straight
segment, which the lattice does not have.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from terrain import DemWindows, ElevationWindow, TerrainMap
from terrain.surface import surface_layers
from terrawatt_base.checks import check_instance
from terrawatt_base.errors import InvalidParameterError, OutOfBoundsError, PlanningError

from .coarse import (
    COARSE_FALLBACKS,
    CoarseOptions,
    CoarseToFine,
    check_free_point,
    coarse_cost,
    coarse_layers,
    corridor_mask,
    search_corridor,
)
from .coarse_chain import FINE_MARGIN_CELLS, chain_corridor, haloed_cells, min_window_cells
from .cost_spec import CostSpec
from .edge_cost import EnergyCost
from .lattice import Lattice
from .points import as_points
from .route import empty_route, evaluate_route

__all__ = ["coarse_to_fine_windowed", "CostBuilder"]

logger = logging.getLogger(__name__)

CostBuilder = CostSpec | Callable[[TerrainMap], EnergyCost]


@dataclass
class _FineWindow:
    """A priced full-resolution window: map rows / cols of its haloed array, and the cost on it."""

    window: ElevationWindow
    cost: EnergyCost

    def holds(self, rows: slice, cols: slice) -> bool:
        return (self.window.rows.start <= rows.start and rows.stop <= self.window.rows.stop
                and self.window.cols.start <= cols.start and cols.stop <= self.window.cols.stop)

    def inside(self, near: np.ndarray, f: int) -> np.ndarray:
        """The fine corridor (coarse ``near`` cells repeated ``f`` times) on this window's cells."""
        w = self.window
        rows = np.arange(w.halo_rows.start, w.halo_rows.stop) // f
        cols = np.arange(w.halo_cols.start, w.halo_cols.stop) // f
        return near[np.ix_(rows, cols)]


def _same_tables(ref: EnergyCost, cost: EnergyCost) -> bool:
    return (np.array_equal(ref.tables.grade_table_j_per_m, cost.tables.grade_table_j_per_m)
            and np.array_equal(ref.tables.turn_table_j, cost.tables.turn_table_j) and ref.tables.ground_labels == cost.tables.ground_labels
            and (ref.speed_mps, ref.max_slope_rad, ref.battery_voltage_v, ref.turn_rate_radps)
            == (cost.speed_mps, cost.max_slope_rad, cost.battery_voltage_v, cost.turn_rate_radps))


class _Pricer:
    """``cost_from`` applied to windows, checked: an EnergyCost on the window, the same tables everywhere."""

    def __init__(self, cost_from: CostBuilder | None) -> None:
        spec = CostSpec() if cost_from is None else cost_from
        if not isinstance(spec, CostSpec) and not callable(spec):
            raise InvalidParameterError(
                f"cost_from must be a CostSpec or a callable TerrainMap -> EnergyCost, got {type(spec).__name__!r}",
                parameter="cost_from")
        self.build = spec.build if isinstance(spec, CostSpec) else spec
        self.ref: EnergyCost | None = None
        #: A preset pricer: a window's blocked cells and table rows follow from the first cost (module docstring).
        self.presets = isinstance(spec, CostSpec) and spec.model is None and spec.energy_model is None \
            and spec.grounds is None

    def __call__(self, window: ElevationWindow) -> EnergyCost:
        tmap = window.terrain_map()
        cost = self.build(tmap)
        if not isinstance(cost, EnergyCost) or cost.terrain.grid != tmap.grid:
            got = type(cost).__name__ if not isinstance(cost, EnergyCost) else f"a cost on grid {cost.terrain.grid!r}"
            raise InvalidParameterError(f"cost_from must return an EnergyCost on the TerrainMap it is given "
                                        f"(grid {tmap.grid!r}), got {got}")
        if self.ref is None:
            self.ref = cost
        elif not _same_tables(self.ref, cost):
            raise InvalidParameterError(
                "cost_from priced two windows of the map with different energy tables or settings (ground rows "
                f"{self.ref.tables.ground_labels!r} vs {cost.tables.ground_labels!r}); windowed planning needs one set of tables "
                "for the whole map: price every window alike (e.g. with one CostSpec)")
        return cost

    def tile(self, window: ElevationWindow) -> tuple[np.ndarray, np.ndarray]:
        """Blocked cells and table rows of the window's block (halo cropped), as ``self(window)`` gives them."""
        crop = window.crop
        if self.presets and self.ref is not None:
            slope = surface_layers(window.elevation_m, window.cell_size_m)["slope"][crop]
            rows = np.broadcast_to(self.ref.ground_rows.flat[0], slope.shape)
            return slope > self.ref.max_slope_rad, rows
        cost = self(window)
        return cost.blocked[crop], cost.ground_rows[crop]


def _coarse_stage(dem: DemWindows, price: _Pricer, f: int, side: int) -> EnergyCost:
    """The coarse cost of :func:`downsample_cost`, reduced tile by tile."""
    rows, cols = dem.shape
    shape = (-(-rows // f), -(-cols // f))
    elevation = np.empty(shape, dtype=np.float64)
    blocked = np.empty(shape, dtype=bool)
    ground = np.empty(shape, dtype=np.int64)
    for win in dem.iter_blocks(side, halo=1):
        tile_blocked, tile_rows = price.tile(win)
        e, b, g = coarse_layers(win.elevation_m[win.crop], tile_blocked, tile_rows, f)
        at = (slice(win.rows.start // f, win.rows.start // f + e.shape[0]),
              slice(win.cols.start // f, win.cols.start // f + e.shape[1]))
        elevation[at], blocked[at], ground[at] = e, b, g
        del tile_blocked, tile_rows, win
    ref = price.ref if price.ref is not None else price(dem.read(slice(0, 2), slice(0, 2)))
    return coarse_cost(ref, elevation, blocked, ground, dem.grid.cell_size_m * f, dem.grid.origin_xy_m, dem.crs)


def _box(near: np.ndarray, f: int, shape: tuple[int, int]) -> tuple[slice, slice]:
    """Map rows / cols of the corridor's bounding box in fine cells, grown by :data:`FINE_MARGIN_CELLS`."""
    rr, cc = np.nonzero(near.any(axis=1))[0], np.nonzero(near.any(axis=0))[0]
    m = FINE_MARGIN_CELLS
    return (slice(max(0, int(rr[0]) * f - m), min(shape[0], (int(rr[-1]) + 1) * f + m)),
            slice(max(0, int(cc[0]) * f - m), min(shape[1], (int(cc[-1]) + 1) * f + m)))


def _check_points(dem: DemWindows, price: _Pricer, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float]
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Start and goal checked as a map in memory checks them, each from a 3 x 3 window."""
    pts = as_points([start_xy_m, goal_xy_m], "start/goal")
    grid = dem.grid
    inside = np.asarray(grid.contains(pts[:, 0], pts[:, 1]))
    if not np.all(inside):
        bad = pts[~inside][0]
        raise OutOfBoundsError(f"start/goal point {tuple(bad.tolist())!r} m lies outside the map bounds {grid.bounds!r}")
    start, goal = pts
    if np.array_equal(start, goal):
        raise InvalidParameterError(f"start equals goal {tuple(start.tolist())!r} m; expected two different points")
    for name, p in (("start_xy_m", start), ("goal_xy_m", goal)):
        r, c = (int(v) for v in grid.rowcol(p[0], p[1]))
        check_free_point(price(dem.read(slice(r, r + 1), slice(c, c + 1), halo=1)), name, p, (r, c))
    return start, goal


def coarse_to_fine_windowed(
    path: str | os.PathLike[str],
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    options: CoarseOptions,
    *,
    cost_from: CostBuilder | None = None,
) -> CoarseToFine:
    """:func:`planner.plan_coarse_to_fine` on a GeoTIFF DEM read by windows, never whole (module docstring).

    ``path``: a DEM in metres (one band, or ``options.band``) without nodata cells (windows fill
    nothing). ``options``: factor, corridor, the coarse stage's tile side (``window_cells``:
    memory holds one tile, about 100 bytes per cell priced, plus the coarse grid) and the fine
    windows' budget (``fine_window_budget_cells``). ``cost_from``: ``TerrainMap -> EnergyCost``
    applied to each window, pricing every window alike: a :class:`~planner.CostSpec` (e.g.
    ``CostSpec(robot="jackal")``; default ``CostSpec()``, the Husky on the presets) or a callable.

    Returns a :class:`CoarseToFine` (``optimum_j`` NaN: no comparison without the whole map)
    whose ``fine_window_cells`` / ``fine_windows`` say what the fine stage read (its times
    include reading and pricing) and whose ``fine_map`` is the window searched (None when the
    windows were chained). Raises as :func:`planner.plan_coarse_to_fine`: FileFormatError /
    UnitError / NodataError for the file, InvalidParameterError for ``cost_from`` (not
    callable, not an EnergyCost on the window, tables that differ between windows) or a budget
    too small for a window of the corridor, PlanningError when the corridor holds no route and
    the whole map exceeds the budget.
    """
    options = check_instance("options", options, CoarseOptions)
    f, side, budget = options.factor, options.tile_side, options.budget_cells
    price = _Pricer(cost_from)
    with DemWindows(path, options.band) as dem:
        rows, cols = dem.shape
        grid = dem.grid
        if -(-rows // f) < 2 or -(-cols // f) < 2:
            raise InvalidParameterError(f"factor={f} leaves fewer than 2 x 2 coarse cells on a {rows} x {cols} map")
        start, goal = _check_points(dem, price, start_xy_m, goal_xy_m)
        width = options.corridor_for(dem.grid.cell_size_m)
        need = min_window_cells(width, f * dem.grid.cell_size_m, f, FINE_MARGIN_CELLS)
        if need > budget and rows * cols > budget:  # the map fits: one window whatever the route
            raise InvalidParameterError(
                f"fine_window_budget_cells={budget} cannot hold a window of the corridor (half-width {width:g} m at "
                f"factor {f}: {need} cells around one diagonal coarse step); expected at least {need}, or a smaller "
                "factor / corridor_m", parameter="fine_window_budget_cells")

        t0 = time.perf_counter()
        coarse = _coarse_stage(dem, price, f, side)
        coarse_path = Lattice(coarse, 1).shortest_path(start, goal)
        coarse_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        objective, waypoints, n_nodes, fallback = math.inf, np.empty((0, 2)), 0, COARSE_FALLBACKS[0]
        fine: _FineWindow | None = None
        windows: list[tuple[int, int, int, int]] = []
        chained = None

        def read(box_rows: slice, box_cols: slice) -> ElevationWindow:
            win = dem.read(box_rows, box_cols, halo=1)
            windows.append((win.halo_rows.start, win.halo_rows.stop, win.halo_cols.start, win.halo_cols.stop))
            logger.info("fine stage: map rows %d..%d, cols %d..%d (%d cells)", win.halo_rows.start,
                        win.halo_rows.stop - 1, win.halo_cols.start, win.halo_cols.stop - 1, win.elevation_m.size)
            return win

        def window_for(box: tuple[slice, slice]) -> _FineWindow:
            nonlocal fine
            if fine is None or not fine.holds(*box):
                fine = None  # free the smaller window before reading the bigger one
                win = read(*box)
                fine = _FineWindow(win, price(win))
            return fine

        def read_priced(box_rows: slice, box_cols: slice) -> tuple[ElevationWindow, EnergyCost]:
            win = read(box_rows, box_cols)
            return win, price(win)

        if coarse_path.found:
            for label, scale in zip(COARSE_FALLBACKS[:2], (1.0, 4.0), strict=True):
                near = corridor_mask(coarse, coarse_path.waypoints_m, width * scale)
                box = _box(near, f, (rows, cols))
                if haloed_cells(*box, (rows, cols)) > budget:
                    fine = None
                    widths = (width * scale, width * scale * 4.0) if scale == 1.0 else (width * scale,)
                    chained = chain_corridor(read_priced, coarse, coarse_path.waypoints_m, start, goal, options,
                                             (rows, cols), widths)
                    objective, n_nodes, width = chained.objective_j, chained.corridor_cells, chained.corridor_m
                    fallback = COARSE_FALLBACKS[1] if chained.widened or scale > 1.0 else label
                    break
                here = window_for(box)
                objective, waypoints, n_nodes = search_corridor(here.cost, start, goal, here.inside(near, f))
                if math.isfinite(objective):
                    width, fallback = width * scale, label
                    break
        if not math.isfinite(objective):
            fallback = COARSE_FALLBACKS[2]
            if rows * cols > budget:
                why = "the corridor holds no route" if coarse_path.found else "the coarse map joins no route"
                raise PlanningError(
                    f"{why} from {tuple(start.tolist())!r} to {tuple(goal.tolist())!r} m and the whole "
                    f"{rows} x {cols} map exceeds fine_window_budget_cells={budget}, so it cannot be searched "
                    "whole; plan with a smaller factor or a wider corridor_m, or raise the budget")
            logger.warning("coarse-to-fine: no route in the corridor; reading the whole %d x %d map", rows, cols)
            here = window_for((slice(0, rows), slice(0, cols)))
            labels = here.cost.components()
            if labels[here.cost.terrain.rowcol(*start)] == labels[here.cost.terrain.rowcol(*goal)]:
                objective, waypoints, n_nodes = search_corridor(here.cost, start, goal,
                                                                np.ones(here.cost.shape, dtype=bool))
        fine_s = time.perf_counter() - t0
        if chained is not None:
            route = chained.route.replace(planning_time_s=coarse_s + fine_s)
        elif math.isfinite(objective):
            route = evaluate_route(here.cost, waypoints, planner="coarse-to-fine", planning_time_s=coarse_s + fine_s)
        else:
            route = empty_route("infeasible", "coarse-to-fine", coarse_s + fine_s, coarse.battery_voltage_v)
    cells_read = sum((r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in windows)
    return CoarseToFine(route, coarse_path.waypoints_m, f, width, n_nodes, objective, math.nan, fallback,
                        coarse_s, fine_s, 0.0, cells_read, tuple(windows), grid, coarse_map=coarse.terrain,
                        fine_map=None if fine is None else fine.cost.terrain)
