"""EnergyCost: the energy (J) of straight segments and turns across a terrain map, from per-cell tables.

An :class:`EnergyCost` is built once per (map, energy model, grounds, speed) — the *map
preparation* step — and then answers, for any straight segment, the battery energy (J) of
driving it at the planning speed:

``E(a -> b) = sum over crossed cells i of  l_i * f_{g(i)}(s_i)``,  ``s_i = grad_x_i u_x + grad_y_i u_y``

where ``l_i`` is the exact length of the segment inside cell ``i`` (grid-line crossings, an
Amanatides–Woo walk), ``u`` the unit direction of motion, ``grad_x, grad_y`` the map's
per-cell elevation gradients (so the grade ``s_i`` is signed: uphill ``!=`` downhill) and
``f_g(s)`` the energy per horizontal metre (J/m) on ground ``g`` at grade ``s``, tabulated once
per ground on a uniform grade grid over ``[-tan(max_slope), +tan(max_slope)]`` and linearly
interpolated (:mod:`planner.tables`). A segment that crosses (or touches at a corner between
two cells: the robot is not a point) a *blocked* cell — an obstacle, or a cell steeper than
``max_slope_rad`` — costs ``inf``; so does a segment meeting, in its direction of travel, a
grade its ground cannot be driven at (a model's ``inf`` energy), which blocks that direction
only. Obstacles are not inflated by the robot's size: inflate them in the map if needed.

Turning at a waypoint costs the turn table's entry for the heading change, tabulated per
ground over ``[0, pi]``; the ground is the one of the cell holding the waypoint. The robot
drives stop-turn-go (:mod:`energy.profiles`): with the physics model the entry holds the
stop before the pivot, the ramped pivot and the start after it, and a route pays one more
stop-and-go for starting from rest and ending at rest (the table's column 0, half at each
end: :meth:`EnergyCost.turn_energies_j`), so a route's edge price is what the robot drives
(:mod:`planner.tables`). A waypoint whose heading change is at most
:data:`energy.profiles.COLLINEAR_TOL_RAD` is driven through: no turn, no stop.

The walks are compiled kernels (:mod:`planner.kernels`) over the cost's packed, read-only
arrays, :attr:`EnergyCost.arrays` (a :class:`~planner.kernels.CostArrays`): the public seam
through which the lattice, the refinement and the OMPL objective call them.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from energy import PhysicsEnergyModel
from energy.profiles import COLLINEAR_TOL_RAD
from terrain import TerrainMap
from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError, OutOfBoundsError

from .cache import CACHE_SIZE, ResultCache
from .kernels import CostArrays, walk_forward, walk_many
from .points import as_points
from .refine import relax_path
from .tables import (
    DEFAULT_GRADE_SAMPLES,
    DEFAULT_TURN_SAMPLES,
    CostTables,
)

__all__ = [
    "EnergyCost",
    "DEFAULT_MAX_SLOPE_RAD",
    "DEFAULT_GRADE_SAMPLES",
    "DEFAULT_TURN_SAMPLES",
]

#: Default steepest slope a route may cross (20 degrees).
DEFAULT_MAX_SLOPE_RAD = math.radians(20.0)


class EnergyCost:
    """Precomputed per-cell tables for the energy (J) of straight segments and turns on a map.

    Build it for a map with :meth:`planner.CostSpec.build` (which tabulates an energy model over
    the map's grounds); the constructor takes ready tables (for custom cost models and tests) and
    validates them; then it answers segment, path and turn energies,
    free points, lower bounds and connected regions.

    Parameters
    ----------
    terrain : TerrainMap
        The map; its ``grad_x``, ``grad_y``, ``slope`` and ``obstacle`` layers are used.
    ground_rows : ndarray of int, shape (rows, cols)
        The row of ``tables`` that serves each cell.
    tables : CostTables
        The energy of a straight metre at each grade and of a turn at each angle, a row per
        kind of cell (with their spreads, when a model with an interval priced them); the
        grades span ``[-tan(max_slope_rad), +tan(max_slope_rad)]``.
    speed_mps : float
        Planning speed (m/s), used for durations.
    max_slope_rad : float
        Cells steeper than this are blocked; in ``(0, pi/2)``.
    battery_voltage_v : float
        Battery voltage (V) for charge in mAh.
    turn_rate_radps : float
        Rate of turning in place (rad/s), used for durations.

    Attributes
    ----------
    arrays : CostArrays
        The packed read-only arrays the compiled kernels walk over (:mod:`planner.kernels`):
        the public seam of the lattice, the refinement and the OMPL objective.
    blocked : ndarray of bool
        Obstacle or slope above ``max_slope_rad``.
    min_energy_per_metre_j : float
        Lowest energy per metre over every free cell and every grade that cell can present to
        a straight motion (``|grade| <= tan(slope)``); ``lower_bound_j`` is this times distance.
    prep_time_s : float
        Seconds spent building the tables (set by :meth:`planner.CostSpec.build`; numba compilation excluded).

    Raises
    ------
    InvalidParameterError
        ``tables`` not a :class:`CostTables`, rows that are not its rows, bad speed / slope /
        voltage / turn rate.
    GridMismatchError
        ``ground_rows`` not on the map's grid.
    """

    def __init__(
        self,
        terrain: TerrainMap,
        ground_rows: np.ndarray,
        tables: CostTables,
        *,
        speed_mps: float,
        max_slope_rad: float = DEFAULT_MAX_SLOPE_RAD,
        battery_voltage_v: float,
        turn_rate_radps: float,
    ) -> None:
        t0 = time.perf_counter()
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        speed = check_real("speed_mps", speed_mps, low=0.0, low_inclusive=False)
        voltage = check_real("battery_voltage_v", battery_voltage_v, low=0.0, low_inclusive=False)
        turn_rate = check_real("turn_rate_radps", turn_rate_radps, low=0.0, low_inclusive=False)
        slope = check_real("max_slope_rad", max_slope_rad, low=0.0, high=math.pi / 2, low_inclusive=False,
                           high_inclusive=False)
        if not isinstance(tables, CostTables):
            raise InvalidParameterError(f"tables must be a CostTables, got {type(tables).__name__!r}",
                                        parameter="tables")

        self.terrain = terrain
        self.speed_mps = speed
        self.max_slope_rad = slope
        self.battery_voltage_v = voltage
        self.turn_rate_radps = turn_rate
        self.grade_max = math.tan(self.max_slope_rad)
        #: The energy tables, a row per kind of cell (:class:`CostTables`).
        self.tables = tables
        self.ground_rows = tables.rows_on(terrain.shape, ground_rows)
        self.blocked = np.asarray(terrain.obstacle) | (np.asarray(terrain["slope"]) > self.max_slope_rad)
        self.blocked.setflags(write=False)
        self.arrays = CostArrays.build(
            terrain.grid, terrain["grad_x"], terrain["grad_y"], self.ground_rows, self.blocked,
            tables.grade_table_j_per_m, tables.turn_table_j, self.grade_max,
        )
        self._free_grade_index: np.ndarray | None = None  # geometry only: shared by with_tables
        self.min_energy_per_metre_j = self._min_energy_per_metre()
        self._components: np.ndarray | None = None
        #: Lattice graphs built over this cost, by stride (see :meth:`Lattice.for_cost`).
        self.lattices: dict[int, Any] = {}
        #: Per-query results derived from this cost (e.g. route comparisons), least recently
        #: used dropped beyond :data:`CACHE_SIZE` entries.
        self.results = ResultCache(CACHE_SIZE)
        #: Cells whose table row content differs from the cost this one was derived from
        #: (:meth:`with_tables`); ``None`` for a cost built from scratch.
        self.changed_cells: np.ndarray | None = None
        #: The physics model that priced the tables (:meth:`planner.CostSpec.build` with
        #: :class:`energy.PhysicsEnergyModel`) and its ground parameters per table row, so a
        #: mission forecast can price the whole driven profile (:func:`planner.route_price.profile_forecast_w`);
        #: ``None`` otherwise.
        self.physics_model: PhysicsEnergyModel | None = None
        self.ground_params: tuple[Any, ...] | None = None
        #: The learned model that priced the tables (:meth:`planner.LearnedEnergyModel.energy_cost`), so
        #: :func:`planner.route_price.price_route` can price a route's whole drive profile with it; ``None`` otherwise.
        self.learned_model: Any = None
        self.prep_time_s = time.perf_counter() - t0

    def with_tables(self, tables: CostTables, ground_rows: np.ndarray | None = None) -> EnergyCost:
        """The same map geometry with new energy tables (a table-only refresh, e.g. after a model update).

        Equal in every query to ``EnergyCost(self.terrain, ground_rows, tables, ...)`` with this
        cost's speed, slope limit, voltage and turn rate, but the per-cell geometry (gradients,
        blocked cells, connected regions) is shared, and every lattice graph cached on this cost
        is carried over by recomputing only the weights of edges that cross a cell whose table
        row *content* changed (:meth:`Lattice.refreshed`), instead of being rebuilt. Cells whose
        row index changed but whose row content did not (rows renumbered) count as unchanged.

        Parameters
        ----------
        tables : CostTables
            The new tables (their spreads, if any, with them: the old spreads are not carried
            over); as many grade samples as this cost's (the grade grid is part of the geometry).
        ground_rows : ndarray of int, optional
            New per-cell rows (default: the current ones).

        Returns
        -------
        EnergyCost
            A new cost; its :attr:`changed_cells` marks the cells whose energy changed and its
            ``prep_time_s`` is the refresh time (lattice updates included). ``self`` is not
            modified.

        Raises
        ------
        InvalidParameterError
            ``tables`` not a :class:`CostTables` or of another number of grade samples; rows
            that are not its rows.
        GridMismatchError
            ``ground_rows`` not on the map's grid.
        """
        t0 = time.perf_counter()
        if not isinstance(tables, CostTables):
            raise InvalidParameterError(f"tables must be a CostTables, got {type(tables).__name__!r}",
                                        parameter="tables")
        rows = tables.rows_on(self.terrain.shape, self.ground_rows if ground_rows is None else ground_rows)
        if tables.grade_table_j_per_m.shape[1] != self.tables.grade_table_j_per_m.shape[1]:
            raise InvalidParameterError(
                f"grade_table_j_per_m has {tables.grade_table_j_per_m.shape[1]} grade samples; this cost's grade "
                f"grid has {self.tables.grade_table_j_per_m.shape[1]} (build a new EnergyCost to change it)", parameter="tables"
            )
        new = object.__new__(EnergyCost)
        for name in ("terrain", "speed_mps", "max_slope_rad", "battery_voltage_v", "turn_rate_radps", "grade_max",
                     "blocked", "_free_grade_index", "_components"):
            setattr(new, name, getattr(self, name))
        new.tables = tables
        new.ground_rows = rows
        new.arrays = self.arrays.with_tables(new.ground_rows, self.blocked, tables.grade_table_j_per_m,
                                             tables.turn_table_j)
        new.min_energy_per_metre_j = new._min_energy_per_metre()
        new.changed_cells = self._changed_cells(new)
        new.changed_cells.setflags(write=False)
        new.results = ResultCache(CACHE_SIZE)
        new.physics_model, new.ground_params = None, None  # other tables: not that physics model's any more
        new.learned_model = None
        new.lattices = {stride: lat.refreshed(new, new.changed_cells) for stride, lat in self.lattices.items()}
        new.prep_time_s = time.perf_counter() - t0
        return new

    @property
    def has_interval(self) -> bool:
        """Whether the tables carry run-level standard deviations with some spread > 0."""
        return self.tables.grade_sd_table_j_per_m is not None and bool(
            np.any(self.tables.grade_sd_table_j_per_m > 0) or np.any(self.tables.turn_sd_table_j > 0))

    def _changed_cells(self, other: EnergyCost) -> np.ndarray:
        """Free cells whose grade-table row content differs between ``self`` and ``other``."""
        n_new = other.tables.grade_table_j_per_m.shape[0]
        code = self.ground_rows.astype(np.int64) * n_new + other.ground_rows
        present = np.flatnonzero(np.bincount(code.ravel(), minlength=self.tables.grade_table_j_per_m.shape[0] * n_new))
        differs = np.zeros(self.tables.grade_table_j_per_m.shape[0] * n_new, dtype=bool)
        for pair in present.tolist():
            a, b = divmod(pair, n_new)
            differs[pair] = not np.array_equal(self.tables.grade_table_j_per_m[a], other.tables.grade_table_j_per_m[b])
        return differs[code] & ~self.blocked

    def _min_energy_per_metre(self) -> float:
        """Lowest J/m any straight motion through a free cell can cost (admissible per-metre bound)."""
        dg = self.arrays.grade_step
        free = ~self.blocked
        if not np.any(free):
            return 0.0
        table = self.tables.grade_table_j_per_m
        n = table.shape[1]
        m = (n - 1) // 2  # index of grade 0
        # prefix[row, k] = min of table[row, m-k .. m+k]: lowest J/m at |grade| <= k*dg.
        left = np.minimum.accumulate(table[:, m::-1], axis=1)
        right = np.minimum.accumulate(table[:, m:], axis=1)
        prefix = np.minimum(left, right)
        if self._free_grade_index is None:
            grad = np.hypot(self.terrain["grad_x"], self.terrain["grad_y"])[free]
            self._free_grade_index = np.minimum(np.ceil(grad / dg * (1 + 1e-9)).astype(np.int64), m)
        value = float(np.min(prefix[self.ground_rows[free], self._free_grade_index]))
        return value if math.isfinite(value) else 0.0

    def relax_path(
        self,
        waypoints_m: Any,
        *,
        spacing_m: float | None = None,
        levels: int = 3,
        min_gain: float = 1e-3,
        step_m: float | None = None,
        max_sweeps: int = 300,
    ) -> np.ndarray:
        """Locally optimise a valid polyline's true energy (drive + turns), ends fixed.

        :func:`planner.refine.relax_path` on this cost (see there for the method and errors).
        """
        return relax_path(self, waypoints_m, spacing_m=spacing_m, levels=levels, min_gain=min_gain,
                          step_m=step_m, max_sweeps=max_sweeps)

    # ------------------------------------------------------------------ queries
    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape of the map."""
        return self.terrain.shape

    def check_inside(self, pts: np.ndarray, name: str) -> None:
        """Raise :class:`OutOfBoundsError` naming ``name`` if a point of ``pts`` (N, 2) lies outside the map."""
        inside = np.asarray(self.terrain.contains(pts[:, 0], pts[:, 1]))
        if not np.all(inside):
            bad = pts[~inside][0]
            raise OutOfBoundsError(
                f"{name} point {tuple(bad.tolist())!r} m lies outside the map bounds {self.terrain.bounds!r}"
            )

    def segment_energy_j(self, starts_xy_m: Any, ends_xy_m: Any) -> np.ndarray:
        """Energy (J) of driving each straight segment ``starts[i] -> ends[i]`` at the planning speed.

        Exact cell-by-cell integration; ``inf`` for a segment that crosses a blocked cell.

        Parameters
        ----------
        starts_xy_m, ends_xy_m : array_like, shape (N, 2) or (2,)
            Segment ends (m).

        Returns
        -------
        ndarray, shape (N,)

        Raises
        ------
        InvalidParameterError
            Wrong shapes or NaN/inf coordinates.
        OutOfBoundsError
            A point outside the map.
        """
        a = as_points(starts_xy_m, "starts_xy_m")
        b = as_points(ends_xy_m, "ends_xy_m")
        if a.shape != b.shape:
            raise InvalidParameterError(f"starts_xy_m {a.shape!r} and ends_xy_m {b.shape!r} must have equal shapes")
        self.check_inside(a, "starts_xy_m")
        self.check_inside(b, "ends_xy_m")
        arr = self.arrays
        return walk_many(
            arr.cells,
            arr.grade_table,
            arr.geo,
            np.array(a[:, 0]),  # fresh writable copies: one compiled signature for all callers
            np.array(a[:, 1]),
            np.array(b[:, 0]),
            np.array(b[:, 1]),
        )

    def segment_energy_one_j(self, xa: float, ya: float, xb: float, yb: float) -> float:
        """Energy (J) of one segment from scalars, without validation (compiled; for callbacks).

        Points outside the map, NaN, or a blocked crossing give ``inf``.
        """
        arr = self.arrays
        return walk_forward(arr.cells, arr.grade_table, arr.geo, xa, ya, xb, yb)

    def is_free(self, xy_m: Any) -> np.ndarray:
        """Whether points lie on free cells (inside the map, no obstacle, not too steep).

        Raises
        ------
        InvalidParameterError
            Wrong shape or NaN coordinates.
        OutOfBoundsError
            A point outside the map.
        """
        pts = as_points(xy_m, "xy_m")
        self.check_inside(pts, "xy_m")
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        return ~self.blocked[r, c]

    def turn_energies_j(self, waypoints_m: Any) -> tuple[np.ndarray, np.ndarray]:
        """Heading change (rad, in [0, pi]) and the energy (J) of stopping, turning and starting at every waypoint.

        The first and last waypoints have no turn; they hold half the stop-and-go of their
        ground each (the tables' column 0, :mod:`planner.tables`): the route starts from rest
        and ends at rest. Zero-length segments (repeated points) have no heading: the turn is
        taken between the neighbouring non-degenerate segments, at the waypoint where the new
        heading starts. A waypoint the robot drives through (:meth:`turn_energy_at`) costs 0.

        Returns
        -------
        angles_rad, energies_j : ndarray, shape (K,)
        """
        pts = as_points(waypoints_m, "waypoints_m")
        self.check_inside(pts, "waypoints_m")
        k = pts.shape[0]
        angles = np.zeros(k)
        if k < 2:
            return angles, np.zeros(k)
        seg = np.diff(pts, axis=0)
        nonzero = np.flatnonzero(np.hypot(seg[:, 0], seg[:, 1]) > 0)
        if nonzero.size >= 2:
            heading = np.arctan2(seg[nonzero, 1], seg[nonzero, 0])
            turn = np.abs((np.diff(heading) + math.pi) % (2 * math.pi) - math.pi)
            angles[nonzero[1:]] = turn  # waypoint index where segment nonzero[j] starts
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        rows = self.ground_rows[r, c]
        energies = self.turn_energy_at(rows, angles)
        energies[[0, -1]] += 0.5 * self.stop_go_at(rows[[0, -1]])
        return angles, energies

    def start_and_stop_j(self, start_xy_m: Any, goal_xy_m: Any) -> float:
        """What a route from ``start_xy_m`` to ``goal_xy_m`` pays for starting from rest and stopping at rest (J).

        Half the stop-and-go of the start's ground and half the goal's (:meth:`turn_energies_j`'s
        ends): the same for every route between the two points, so a search leaves it out of its
        objective and adds it to the price it reports.
        """
        pts = as_points([start_xy_m, goal_xy_m], "start/goal")
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        return float(0.5 * self.stop_go_at(self.ground_rows[r, c]).sum())

    def stop_go_at(self, rows: Any) -> np.ndarray:
        """The energy (J) of stopping and starting again without turning, on table ``rows``: the turn table's column 0.

        What every turn of the stop-turn-go drive includes and a route pays once (its start
        from rest and its stop at rest); 0 for tables that price no stop and go
        (:mod:`planner.tables`).
        """
        return self.tables.turn_table_j[np.asarray(rows, dtype=np.int64), 0]

    def turn_energy_at(self, rows: Any, angles_rad: Any) -> np.ndarray:
        """Turn-in-place energy (J) of table ``rows`` at heading changes ``angles_rad`` (in [0, pi]):
        the turn table linearly interpolated (its stop and start included), 0 where the angle is at
        most :data:`energy.profiles.COLLINEAR_TOL_RAD` (the robot drives through). The one rule that
        prices a turn: :meth:`turn_energies_j` (every route's turns), the heading lattice's arcs
        and the compiled kernels' turn (:mod:`planner.kernels.walk`) use it.

        Parameters
        ----------
        rows, angles_rad : array_like of int / float, broadcast together
            Rows of the tables' ``turn_table_j`` (as :attr:`ground_rows`) and unsigned heading changes.
        """
        rows = np.asarray(rows, dtype=np.int64)
        angles = np.asarray(angles_rad, dtype=np.float64)
        n_turn = self.tables.turn_table_j.shape[1]
        f = angles / math.pi * (n_turn - 1)
        i0 = np.minimum(np.floor(f).astype(np.int64), n_turn - 2)
        w = f - i0
        energies = self.tables.turn_table_j[rows, i0] * (1 - w) + self.tables.turn_table_j[rows, i0 + 1] * w
        return np.where(angles <= COLLINEAR_TOL_RAD, 0.0, energies)

    def turn_spread_at(self, rows: Any, angles_rad: Any) -> np.ndarray:
        """Run-level spread (J) of a turn in place of table ``rows`` at heading changes ``angles_rad`` (in [0, pi]):
        the tables' ``turn_sd_table_j`` linearly interpolated. The one rule for a turn's spread: a route's
        (:meth:`path_spreads_j`) and a tour's stop allowance (:meth:`planner.tours.PairPrices.stop_turn_quantile_j`).

        Parameters
        ----------
        rows, angles_rad : array_like of int / float, same length
            Rows of the tables (as :attr:`ground_rows`) and unsigned heading changes.

        Raises
        ------
        InvalidParameterError
            Tables without spreads.
        """
        table = self.tables.turn_sd_table_j
        if table is None:
            raise InvalidParameterError(f"the cost ({self!r}) carries no standard-deviation tables: its energy model "
                                        "gives no interval", parameter="interval")
        grid = np.linspace(0.0, math.pi, table.shape[1])
        angles = np.asarray(angles_rad, dtype=np.float64).ravel()
        rows = np.asarray(rows, dtype=np.int64).ravel()
        out = np.empty(angles.shape)
        for k in np.unique(rows):  # one interpolation per table row, not per turn
            at = rows == k
            out[at] = np.interp(angles[at], grid, table[k])
        return out

    def path_energy_j(self, waypoints_m: Any) -> float:
        """Total energy (J) of a polyline: every segment plus the turns at its waypoints.

        ``inf`` when a segment crosses a blocked cell.

        Raises
        ------
        InvalidParameterError
            Fewer than 1 waypoint, wrong shape or NaN.
        OutOfBoundsError
            A waypoint outside the map.
        """
        pts = as_points(waypoints_m, "waypoints_m")
        if pts.shape[0] < 2:
            return 0.0
        seg = self.segment_energy_j(pts[:-1], pts[1:])
        _, turns = self.turn_energies_j(pts)
        return float(seg.sum() + turns.sum())

    def path_spreads_j(self, waypoints_m: Any, *,
                       segment_cache: dict[tuple[float, float, float, float], np.ndarray] | None = None) -> np.ndarray:
        """The run-level spread (J) of driving a polyline, per table row: each row's spreads summed linearly.

        Each straight segment is walked cell by cell (:meth:`terrain.TerrainMap.segment_cells`):
        a cell adds its horizontal length times its row's spread at the cell's grade in the
        direction of travel (linear interpolation of the tables' ``grade_sd_table_j_per_m``, as the
        mean tables are read); each turn adds its row's turn spread at the waypoint, and the ends
        half the spread of their stop-and-go each (as :meth:`turn_energies_j`). What a
        route's interval is made of (:func:`planner.price_route`; :mod:`planner.route_price` says how).

        Parameters
        ----------
        waypoints_m : array_like, shape (K, 2)
            The polyline (m).
        segment_cache : dict, optional
            Per-segment spreads already walked, keyed by ``(x0, y0, x1, y1)``, filled as segments
            are walked: many routes of this cost that share segments walk each once.

        Returns
        -------
        ndarray, shape (n_rows,)

        Raises
        ------
        InvalidParameterError
            Tables without spreads; bad points.
        OutOfBoundsError
            A waypoint outside the map.
        """
        sd_table = self.tables.grade_sd_table_j_per_m
        if sd_table is None:
            raise InvalidParameterError(
                f"the cost ({self!r}) carries no standard-deviation tables: its energy model gives no interval "
                "(plan with a current model whose gives_interval is True)", parameter="interval")
        pts = as_points(waypoints_m, "waypoints_m")
        angles, _ = self.turn_energies_j(pts)
        per_row = np.zeros(sd_table.shape[0])
        for a, b in zip(pts[:-1].tolist(), pts[1:].tolist()):
            key = (a[0], a[1], b[0], b[1])
            seg = None if segment_cache is None else segment_cache.get(key)
            if seg is None:
                seg = self._segment_spreads(sd_table, a, b)
                if segment_cache is not None:
                    segment_cache[key] = seg
            per_row += seg
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        row = self.ground_rows[r, c]
        turn_sd = np.where(angles > COLLINEAR_TOL_RAD, self.turn_spread_at(row, angles), 0.0)
        turn_sd[[0, -1]] += 0.5 * self.tables.turn_sd_table_j[row[[0, -1]], 0]  # the start and the stop
        return per_row + np.bincount(row, weights=turn_sd, minlength=sd_table.shape[0])

    def _segment_spreads(self, sd_table: np.ndarray, a: list[float], b: list[float]) -> np.ndarray:
        """The linear spread sums (J) per table row of driving the straight segment ``a -> b`` (cell by cell)."""
        n_rows, n_grade = sd_table.shape
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        if length == 0.0:
            return np.zeros(n_rows)
        step = 2.0 * self.grade_max / (n_grade - 1)
        gx, gy = self.terrain["grad_x"], self.terrain["grad_y"]
        rows, cols, pieces = self.terrain.segment_cells(tuple(a), tuple(b))
        grade = (gx[rows, cols] * (b[0] - a[0]) + gy[rows, cols] * (b[1] - a[1])) / length
        f = np.clip((grade + self.grade_max) / step, 0.0, n_grade - 1.0)
        i0 = np.minimum(np.floor(f).astype(np.int64), n_grade - 2)
        w = f - i0
        row = self.ground_rows[rows, cols]
        sd = sd_table[row, i0] * (1.0 - w) + sd_table[row, i0 + 1] * w
        return np.bincount(row, weights=np.asarray(pieces) * sd, minlength=n_rows)

    def surface_length_m(self, waypoints_m: Any) -> float:
        """Length (m) of a polyline along the terrain surface: per cell, horizontal length
        times ``sqrt(1 + grade**2)`` with the cell's grade in the direction of travel.

        Raises
        ------
        InvalidParameterError, OutOfBoundsError
            Bad shape / NaN, or a waypoint outside the map.
        """
        pts = as_points(waypoints_m, "waypoints_m")
        self.check_inside(pts, "waypoints_m")
        gx, gy = self.terrain["grad_x"], self.terrain["grad_y"]
        total = 0.0
        for a, b in zip(pts[:-1], pts[1:]):
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            if length == 0.0:
                continue
            rows, cols, pieces = self.terrain.segment_cells(tuple(a), tuple(b))
            grade = (gx[rows, cols] * (b[0] - a[0]) + gy[rows, cols] * (b[1] - a[1])) / length
            total += float(np.sum(pieces * np.sqrt(1.0 + grade**2)))
        return total

    def lower_bound_j(self, a_xy_m: Any, b_xy_m: Any) -> np.ndarray:
        """Admissible lower bound (J) on the drive energy of any route from ``a`` to ``b``.

        ``min_energy_per_metre_j * |b - a|``: every route of length ``L >= |b - a|`` only
        crosses free cells, and on each of them a straight piece costs at least the lowest
        energy per metre at any grade that cell can present (``|grade| <= tan(slope)``).
        It never overestimates (the elevation change is deliberately not used: with
        per-cell gradients the integrated grade along a route is not exactly
        ``z(b) - z(a)``, so a grade term could overestimate).

        Returns
        -------
        ndarray, shape (N,)
        """
        a = as_points(a_xy_m, "a_xy_m")
        b = as_points(b_xy_m, "b_xy_m")
        return self.min_energy_per_metre_j * np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])

    def components(self) -> np.ndarray:
        """Label of the 4-connected region of free cells holding each cell (``0`` = blocked).

        Two points are joined by some valid polyline exactly when their cells share a label
        (a valid segment crosses a chain of edge-adjacent free cells, and a corner crossing
        needs both side cells free).
        """
        if self._components is None:
            from scipy import ndimage

            labels, _ = ndimage.label(~self.blocked)
            self._components = labels
        return self._components

    def __repr__(self) -> str:
        return (
            f"EnergyCost(shape={self.shape}, speed_mps={self.speed_mps}, max_slope_rad={self.max_slope_rad:.4f}, "
            f"grounds={list(self.tables.ground_labels)}, blocked_cells={int(self.blocked.sum())})"
        )
