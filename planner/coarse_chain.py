"""The fine stage of coarse-to-fine in chained windows along the coarse route: memory bounded by the corridor, not its box.

:func:`chain_corridor` is the fine stage of :func:`planner.plan_coarse_to_fine` on a GeoTIFF read by windows when
the corridor's bounding window would exceed a cell budget (a route across a map: the box of a
diagonal corridor is most of the map). The coarse route is followed as the ordered coarse
cells it crosses, in stretches of at most :data:`CHAIN_STRETCH_CELLS` fine cells, each read
as the full-resolution window around the stretch's corridor (the stretch shortened until the
window, halo included, fits the budget):

1. from the point reached so far, the 1-cell lattice route inside the corridor is searched
   to a target at the stretch's far end — the free corridor cell nearest the coarse route
   there, in the free region (8-connected) of the point reached; the goal in the last
   stretch;
2. only the first :data:`CHAIN_KEEP` of that route (by length, up to a lattice node) is kept;
   the next window starts from its end. So each junction lies on a route that went on beyond
   it: junctions are not forced onto the coarse route, and the route is not bent towards
   them (the last third of each search is thrown away and re-planned from the next window);
3. a stretch whose corridor holds no route is searched again with the next of the
   corridor half-widths ``widths_m`` (a bigger window, the stretch shortened to the budget).

The route is a sequence of corridor lattice routes, each a subgraph route of the full 1-cell
lattice, so its energy is never below the full-resolution optimum; it is evaluated piece by
piece on the window each piece was searched in (segments, surface length, turns inside a
piece) plus the turn at each junction (priced on the next window).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from terrain import ElevationWindow
from terrawatt_base.errors import PlanningError

from .coarse import CoarseOptions, corridor_mask, merge_straight, search_corridor
from .edge_cost import EnergyCost
from .route import Route
from .route_time import route_duration_s

__all__ = ["ChainedRoute", "chain_corridor", "haloed_cells", "min_window_cells", "CHAIN_STRETCH_CELLS", "CHAIN_KEEP"]

logger = logging.getLogger(__name__)

#: Fine cells of coarse route one chained window covers at most (a few thousand: the window
#: of a diagonal stretch holds about its square over two, so shorter stretches read fewer
#: cells per metre of route, longer ones have fewer junctions).
CHAIN_STRETCH_CELLS = 2048
#: Cells around the corridor searched in a fine window: a lattice move spans two cells and a
#: segment through a cell corner checks the cells beside it.
FINE_MARGIN_CELLS = 2
#: Share (by length) of each window's route that is kept; the rest is planned again from
#: the next window.
CHAIN_KEEP = 2.0 / 3.0

#: Reads and prices a block of the map (rows, cols) with a halo of one cell.
ReadPriced = Callable[[slice, slice], tuple[ElevationWindow, EnergyCost]]


@dataclass(frozen=True)
class ChainedRoute:
    """What :func:`chain_corridor` found.

    Attributes
    ----------
    route : Route
        The whole route (``planner="coarse-to-fine"``, planning time 0: the caller's).
    objective_j : float
        Drive energy (J) of the route (its segments).
    corridor_m : float
        The widest corridor half-width (m) searched in a window that found its piece.
    widened : bool
        Whether some stretch needed the wider corridor.
    corridor_cells : int
        Free corridor cells of the searched graphs, summed over the windows (overlaps
        counted in each).
    pieces : int
        Route pieces kept (one per window searched to the end).
    """

    route: Route
    objective_j: float
    corridor_m: float
    widened: bool
    corridor_cells: int
    pieces: int


def haloed_cells(rows: slice, cols: slice, shape: tuple[int, int], halo: int = 1) -> int:
    """Cells of the block ``rows`` x ``cols`` grown by ``halo`` cells and clipped to a map of ``shape``."""
    r0, r1 = max(0, rows.start - halo), min(shape[0], rows.stop + halo)
    c0, c1 = max(0, cols.start - halo), min(shape[1], cols.stop + halo)
    return (r1 - r0) * (c1 - c0)


def min_window_cells(width_m: float, coarse_cell_m: float, factor: int, margin_cells: int) -> int:
    """Cells (halo included) of the window around one diagonal coarse step of a corridor of half-width ``width_m``.

    The smallest window a chained search reads away from the map's edges: each of the two
    coarse cells with ``corridor_mask``'s reach around it, the margin and the halo."""
    reach = int(math.floor(width_m / coarse_cell_m + 1.0))
    side = (2 * reach + 2) * factor + 2 * margin_cells + 2
    return side * side


def _route_cells(coarse: EnergyCost, waypoints_m: np.ndarray) -> np.ndarray:
    """The coarse cells the coarse route crosses, in order, as ``(row, col)`` rows (no repeats in a row)."""
    grid = coarse.terrain.grid
    parts = []
    for a, b in zip(waypoints_m[:-1], waypoints_m[1:], strict=True):
        r, c, _ = grid.segment_cells(tuple(a), tuple(b))
        parts.append(np.column_stack([r, c]))
    cells = np.vstack(parts).astype(np.int64)
    return cells[np.concatenate([[True], np.any(np.diff(cells, axis=0) != 0, axis=1)])]


@dataclass
class _Piece:
    """A kept piece: merged waypoints and their evaluation on the piece's window."""

    points: np.ndarray
    segment_energy_j: np.ndarray
    turn_energy_j: np.ndarray


def _evaluate(cost: EnergyCost, nodes: np.ndarray) -> _Piece:
    pts = merge_straight(nodes)
    seg = cost.segment_energy_j(pts[:-1], pts[1:])
    if not np.all(np.isfinite(seg)):  # the searched moves were finite: a broken invariant, not a user error
        raise PlanningError("a chained corridor piece crosses a blocked cell once merged; this is a bug")
    _, turns = cost.turn_energies_j(pts)
    return _Piece(pts, seg, turns)


def _junction_turn(cost: EnergyCost, before: np.ndarray, at: np.ndarray, after: np.ndarray) -> tuple[float, float]:
    """Heading change (rad) and turn energy (J) at ``at`` between the directions ``before -> at`` and ``at -> after``.

    Priced on ``cost`` from points a quarter cell either side of ``at`` (the directions are
    kept; ``before`` may lie outside the window)."""
    d = 0.25 * cost.terrain.cell_size_m
    u_in, u_out = at - before, after - at
    pts = np.vstack([at - d * u_in / np.hypot(*u_in), at, at + d * u_out / np.hypot(*u_out)])
    angles, turns = cost.turn_energies_j(pts)
    return float(angles[1]), float(turns[1])


class _Chain:
    """The state of one chained search: the coarse route's cells, the windows, the pieces kept."""

    def __init__(self, read: ReadPriced, coarse: EnergyCost, waypoints_m: np.ndarray, factor: int,
                 shape: tuple[int, int], budget_cells: int, margin_cells: int) -> None:
        self.read, self.coarse, self.waypoints_m = read, coarse, waypoints_m
        self.f, self.shape, self.budget, self.margin = factor, shape, budget_cells, margin_cells
        self.cells = _route_cells(coarse, waypoints_m)
        steps = np.hypot(*np.diff(self.cells, axis=0).T) * factor
        self.arc = np.concatenate([[0.0], np.cumsum(steps)])  # fine cells along the coarse route
        self.near: dict[float, np.ndarray] = {}
        self.corridor_cells = 0

    def corridor(self, width_m: float) -> np.ndarray:
        if width_m not in self.near:
            self.near[width_m] = corridor_mask(self.coarse, self.waypoints_m, width_m)
        return self.near[width_m]

    def coarse_cell(self, p: np.ndarray) -> np.ndarray:
        """Continuous coarse ``(row, col)`` of a point (cell centres at integers)."""
        t = self.coarse.terrain
        return np.array([(p[1] - t.origin_xy_m[1]) / t.cell_size_m - 0.5, (p[0] - t.origin_xy_m[0]) / t.cell_size_m - 0.5])

    def box(self, a: int, b: int, here: np.ndarray, reach: int) -> tuple[slice, slice]:
        """Fine rows / cols around the stretch ``cells[a..b]`` and the point reached: corridor reach plus margin."""
        pts = np.vstack([self.cells[a:b + 1], np.floor(here + 0.5).astype(np.int64)])
        lo = np.maximum(pts.min(axis=0) - reach, 0)
        hi = np.minimum(pts.max(axis=0) + reach + 1, self.coarse.shape)
        f, m = self.f, self.margin
        return (slice(max(0, int(lo[0]) * f - m), min(self.shape[0], int(hi[0]) * f + m)),
                slice(max(0, int(lo[1]) * f - m), min(self.shape[1], int(hi[1]) * f + m)))

    def stretch(self, a: int, here: np.ndarray, reach: int) -> tuple[int, tuple[slice, slice]] | None:
        """The far end of the longest stretch from ``a`` (at most :data:`CHAIN_STRETCH_CELLS`, at least one
        coarse step) whose window fits, and the window; None when not even one step fits."""
        b = int(np.searchsorted(self.arc, self.arc[a] + CHAIN_STRETCH_CELLS, side="right")) - 1
        b = min(max(b, a + 1), len(self.cells) - 1)
        lo, hi = min(a + 1, b), b  # the window grows with b: the last b (past a) whose window fits
        if haloed_cells(*self.box(a, lo, here, reach), self.shape) > self.budget:
            return None
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if haloed_cells(*self.box(a, mid, here, reach), self.shape) <= self.budget:
                lo = mid
            else:
                hi = mid - 1
        return lo, self.box(a, lo, here, reach)

    def inside(self, win: ElevationWindow, near: np.ndarray, box: tuple[slice, slice]) -> np.ndarray:
        """The corridor on the window's cells, but for the margin inside the box (its outer cells, and the halo)."""
        f, m = self.f, self.margin
        rows = np.arange(win.halo_rows.start, win.halo_rows.stop)
        cols = np.arange(win.halo_cols.start, win.halo_cols.stop)
        r_lo = box[0].start + (m if box[0].start > 0 else 0)
        r_hi = box[0].stop - (m if box[0].stop < self.shape[0] else 0)
        c_lo = box[1].start + (m if box[1].start > 0 else 0)
        c_hi = box[1].stop - (m if box[1].stop < self.shape[1] else 0)
        keep_r = (rows >= r_lo) & (rows < r_hi)
        keep_c = (cols >= c_lo) & (cols < c_hi)
        return near[np.ix_(rows // f, cols // f)] & keep_r[:, None] & keep_c[None, :]

    def target(self, cost: EnergyCost, free: np.ndarray, here: np.ndarray, cell: np.ndarray,
               win: ElevationWindow) -> np.ndarray | None:
        """The free corridor cell nearest the centre of coarse ``cell``, in the free region of ``here``."""
        labels, _ = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
        r, c = cost.terrain.rowcol(here[0], here[1])
        mine = labels[r, c]
        if mine == 0:
            return None
        rr, cc = np.nonzero(labels == mine)
        centre = cell * self.f + (self.f - 1) / 2.0 - np.array([win.halo_rows.start, win.halo_cols.start])
        k = int(np.argmin((rr - centre[0]) ** 2 + (cc - centre[1]) ** 2))
        return np.array(cost.terrain.xy(int(rr[k]), int(cc[k])), dtype=float)


def chain_corridor(
    read: ReadPriced,
    coarse: EnergyCost,
    coarse_waypoints_m: np.ndarray,
    start: np.ndarray,
    goal: np.ndarray,
    options: CoarseOptions,
    shape: tuple[int, int],
    widths_m: tuple[float, ...],
) -> ChainedRoute:
    """The fine route along the coarse route in chained windows of at most ``options.budget_cells`` (module docstring).

    Parameters
    ----------
    read : callable
        ``(rows, cols) -> (ElevationWindow, EnergyCost)``: reads the map block with a halo of
        one cell and prices it (the caller counts and frees the windows).
    coarse : EnergyCost
        The coarse cost the coarse route was planned on.
    coarse_waypoints_m : ndarray, shape (K, 2)
        The coarse route (start first, goal last).
    start, goal : ndarray, shape (2,)
        Free points on the map (m).
    options : CoarseOptions
        Its ``factor`` (fine cells per coarse cell along a side) and ``budget_cells`` (most cells
        one window may hold, halo included); :data:`FINE_MARGIN_CELLS` are kept between the
        corridor searched and a window's edge.
    shape : (int, int)
        The fine map's rows and columns.
    widths_m : tuple of float
        Corridor half-widths (m, as :func:`planner.coarse.corridor_mask`) tried per stretch, in order.

    Returns
    -------
    ChainedRoute

    Raises
    ------
    PlanningError
        A stretch whose corridor holds no route at any width tried (e.g. a passage the
        coarse map saw but the full resolution does not have), a width whose windows exceed
        the budget counting as tried (:func:`min_window_cells` is the caller's check).
    """
    factor, budget_cells = options.factor, options.budget_cells
    chain = _Chain(read, coarse, coarse_waypoints_m, factor, shape, budget_cells, FINE_MARGIN_CELLS)
    cells, last = chain.cells, len(chain.cells) - 1
    here, a = np.asarray(start, dtype=float), 0
    pieces: list[_Piece] = []
    junctions: list[tuple[float, float]] = []
    widest, widened = 0.0, False
    for _ in range(4 * len(cells) + 16):
        found, too_big = None, set()
        for i, width in enumerate(widths_m):
            reach = int(math.floor(width / coarse.terrain.cell_size_m + 1.0))  # corridor_mask's reach, whole cells
            fit = chain.stretch(a, chain.coarse_cell(here), reach)
            if fit is None:
                too_big.add(width)
                continue
            b, box = fit
            win = cost = inside = free = None  # one window in memory at a time
            win, cost = read(*box)
            inside = chain.inside(win, chain.corridor(width), box)
            free = inside & ~cost.blocked
            aim = goal if b == last else chain.target(cost, free, here, cells[b], win)
            if aim is None or np.array_equal(aim, here):
                continue
            energy, pts, n = search_corridor(cost, here, aim, inside, merge=False)
            chain.corridor_cells += n
            if math.isfinite(energy):
                found = (pts, cost, b, width)
                widened |= i > 0
                widest = max(widest, width)
                break
            logger.info("chained corridor: no route in stretch %d..%d at half-width %g m", a, b, width)
        if found is None:
            skipped = sorted(too_big)
            raise PlanningError(
                f"the corridor around the coarse route holds no full-resolution route near coarse cell "
                f"{tuple(cells[a].tolist())!r} (half-widths {list(widths_m)!r} m"
                + (f"; {skipped!r} m not tried, its windows exceed budget_cells={budget_cells}" if skipped else "")
                + "); a passage the coarse map sees may not exist at full resolution: plan with a smaller factor "
                "or a wider corridor_m")
        pts, cost, b, _ = found
        pts = pts[np.concatenate([[True], np.any(np.diff(pts, axis=0) != 0, axis=1)])]
        done = b == last
        if not done:
            run = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
            k = max(1, int(np.searchsorted(run, CHAIN_KEEP * run[-1], side="left")))
            pts = pts[:k + 1]
        if pieces:
            junctions.append(_junction_turn(cost, pieces[-1].points[-2], here, pts[1]))
        pieces.append(_evaluate(cost, pts))
        if done:
            break
        here = pts[-1]
        near_cells = np.hypot(*(cells[a:b + 1] - chain.coarse_cell(here)).T)
        a = a + int(np.argmin(near_cells))
    else:
        raise PlanningError(f"the chained corridor search did not reach the goal in {4 * len(cells) + 16} windows "
                            f"(stuck near coarse cell {tuple(cells[a].tolist())!r}); windows of budget_cells="
                            f"{budget_cells} may be too small to move on: raise the budget")
    return _assemble(pieces, junctions, cost, widest, widened, chain.corridor_cells)


def _assemble(pieces: list[_Piece], junctions: list[tuple[float, float]], cost: EnergyCost, widest: float,
              widened: bool, corridor_cells: int) -> ChainedRoute:
    """One route from the kept pieces: their segments, their inner turns and the turns at the junctions."""
    points = [pieces[0].points] + [p.points[1:] for p in pieces[1:]]
    seg = np.concatenate([p.segment_energy_j for p in pieces])
    turns = [pieces[0].turn_energy_j[:-1]]
    for p, (_, turn) in zip(pieces[1:], junctions, strict=True):
        turns += [np.array([turn]), p.turn_energy_j[1:-1]]
    turns.append(pieces[-1].turn_energy_j[-1:])  # the stop at the goal
    wp = np.vstack(points)
    turn = np.concatenate(turns)
    duration = route_duration_s(wp, cost.speed_mps, cost.turn_rate_radps)
    route = Route(status="exact", waypoints_m=wp, segment_energy_j=seg, turn_energy_j=turn,
                  length_m=float(np.hypot(*np.diff(wp, axis=0).T).sum()), duration_s=duration,
                  energy_j=float(seg.sum() + turn.sum()), battery_voltage_v=cost.battery_voltage_v,
                  planner="coarse-to-fine", planning_time_s=0.0)
    return ChainedRoute(route, float(seg.sum()), widest, widened, corridor_cells, len(pieces))
