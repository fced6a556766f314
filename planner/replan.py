"""Incremental replanning on the lattice: D* Lite toward a fixed goal, repaired where move energies changed.

An :class:`IncrementalPlanner` searches a :class:`~planner.Lattice` backwards from the goal
(D* Lite, :mod:`planner.kernels.incremental`) and keeps its search state between calls.
When the robot moves, :meth:`~IncrementalPlanner.plan` continues the search from the new
start; when energies change (a model update refreshed the cost and its lattice with
:meth:`EnergyCost.with_tables`), :meth:`~IncrementalPlanner.update` takes the refreshed
lattice and marks only the nodes whose moves changed (:attr:`Lattice.changed_moves`), and
the next search repairs the previous one from there instead of starting over.

By default (``heading=True``) the planner answers with the heading lattice
(:func:`~planner.heading_lattice.heading_shortest_path`: drive and turns, the price every route
reports), by an A* over its states that is cheap to repeat: the planner keeps the A*'s
heuristic, the heading-free cost to the goal per node (:func:`~planner.heading_lattice.heading_cost_to_go`,
computed on the first search), and its state arrays (a
:class:`~planner.heading_lattice.HeadingWorkspace`, of which each search puts back only what
it touched). After an update the heuristic is kept a consistent lower bound
(:func:`~planner.heading_lattice.lower_cost_to_go`: where moves got dearer the old values still
bound the cost, where they got cheaper the lowering is propagated), so every answer is still the
heading lattice's exact optimum; once updates have touched more than :attr:`REFRESH_SHARE` of
the nodes, it is computed again (a looser bound makes the A* expand more). An answer is
reused when neither the start nor the energies changed. D* Lite over the 16 states per node was tried and measured: with the
energy-per-metre heuristic the first search on 512² expanded 3.3 M states (5.8 s against 0.33 s
from scratch) and a repair after a 20 × 20 patch cost as much as a search, so it is not used.
With ``heading=False`` the planner searches the heading-free lattice incrementally, drive
energy alone: its answers are those of :meth:`Lattice.shortest_path` with
``weight="energy"``: the same
joins of start and goal to the nearby nodes, the same direct start-goal segment (taken when
no lattice route is cheaper), the same admissible heuristic
``cost.min_energy_per_metre_j * |start - node|``, the same optimum (up to the order of
the additions) and the same :class:`~planner.lattice.LatticePath` assembly. Among routes of equal
energy the two searches may pick different ones. :meth:`~IncrementalPlanner.route` adds the
post-processing of ``plan_route(planner="lattice")`` (refinement, costing).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_seed
from terrawatt_base.errors import InvalidParameterError

from .heading_lattice import HeadingWorkspace, heading_cost_to_go, heading_shortest_path, lower_cost_to_go
from .kernels.incremental import dstar_path, dstar_rekey, dstar_search, dstar_touch, reverse_weights, set_moves
from .lattice import LATTICE_OFFSETS, Lattice, LatticePath
from .points import as_points
from .problem import PlanningProblem
from .refined import refine_planned
from .route import Route, empty_route, evaluate_route
from .settings import PlannerSettings

__all__ = ["IncrementalPlanner"]


class IncrementalPlanner:
    """Minimum-energy lattice routes to one goal, replanned incrementally (D* Lite).

    Parameters
    ----------
    lattice : Lattice
        The lattice to search (its cost gives the energies and the heuristic).
    goal_xy_m : (float, float)
        The goal (m), fixed for the planner's life.

    Attributes
    ----------
    lattice : Lattice
        The lattice whose energies the search state reflects (the last one given to
        :meth:`update`).
    goal_xy_m : ndarray, shape (2,)
    heading : bool
        Whether answers are the heading lattice's (drive and turns; default) or the
        heading-free lattice's, searched incrementally (drive energy alone).
    expanded : int
        Nodes expanded by the last :meth:`plan` (a repair expands only what changed); with
        ``heading``, the heading states the A* touched (0 when the answer was reused).
    touched : int
        Nodes whose moves or goal join changed in the last :meth:`update`.

    Raises
    ------
    InvalidParameterError
        ``lattice`` not a :class:`Lattice`; a NaN goal.
    OutOfBoundsError
        Goal outside the map.

    Notes
    -----
    The planner keeps its own move energies, as two dense tables (the 16 moves out of and
    into each node, ``inf`` where no edge: an edge appearing or vanishing is an energy
    changing), besides 7 arrays of one value per node: about 300 bytes per node, 80 MB for
    a 512 x 512 lattice. A repair costs about what changed: a patch of a
    few hundred cells across the route re-expands a part of the search, a model update over
    a quarter of the map about as much as a new search. With ``heading`` (the default) it
    keeps instead one float per node (the heuristic) and the A*'s workspace, 41 bytes per
    heading state of which about 110 MB are resident for a 512 x 512 lattice.

    Examples
    --------
    >>> import numpy as np
    >>> from planner import CostSpec, CostTables, Lattice
    >>> from terrain import flat_map
    >>> tmap = flat_map((30, 40), 1.0)  # level asphalt, 1 m cells
    >>> cost = CostSpec(speed_mps=0.5).build(tmap)  # the Husky's physics on the asphalt preset
    >>> planner = IncrementalPlanner(Lattice.for_cost(cost), (35.0, 25.0))
    >>> planner.plan((5.0, 5.0)).found
    True
    >>> cheaper = cost.with_tables(CostTables(0.5 * cost.tables.grade_table_j_per_m, cost.tables.turn_table_j))  # a model update
    >>> path = planner.replan((8.0, 6.0), Lattice.for_cost(cheaper))  # moved, and repaired
    >>> scratch = Lattice(cheaper).shortest_path((8.0, 6.0), (35.0, 25.0))  # from scratch, drive only: no turn here
    >>> bool(np.isclose(path.objective, scratch.objective + cheaper.start_and_stop_j((8.0, 6.0), (35.0, 25.0))))
    True
    """

    def __init__(self, lattice: Lattice, goal_xy_m: tuple[float, float], *, heading: bool = True) -> None:
        if not isinstance(lattice, Lattice):
            raise InvalidParameterError(f"lattice must be a Lattice, got {type(lattice).__name__!r}")
        self.heading = check_bool("heading", heading)
        self._answer: tuple[tuple[float, float], LatticePath] | None = None  # heading: the last answer and its start
        self._h: np.ndarray | None = None  # heading: the A*'s heuristic, kept valid across updates
        self._ws: HeadingWorkspace | None = None  # heading: the A*'s arrays, kept between searches
        self._stale = 0  # heading: nodes touched by updates since the heuristic was computed
        goal = as_points(goal_xy_m, "goal_xy_m")
        lattice.cost.check_inside(goal, "goal_xy_m")
        self.goal_xy_m = goal[0]
        self.goal_xy_m.setflags(write=False)
        ni, nj = lattice.node_rows.size, lattice.node_cols.size
        n = lattice.n_nodes
        self._nj = nj
        self._delta = (LATTICE_OFFSETS[:, 0] * nj + LATTICE_OFFSETS[:, 1]).astype(np.int64)
        self._col_x = lattice.node_xy(np.arange(nj))[:, 0].copy()
        self._row_y = lattice.node_xy(np.arange(ni) * nj)[:, 1].copy()
        n = 0 if self.heading else n  # the heading search keeps no D* Lite arrays
        self._g = np.full(n, math.inf)
        self._rhs = np.full(n, math.inf)
        self._exit = np.full(n, math.inf)
        self._key1 = np.empty(n)
        self._key2 = np.empty(n)
        self._nodes = np.empty(n, np.int64)
        self._where = np.full(n, -1, np.int64)
        self._size = 0
        self.lattice = lattice
        self.expanded = 0
        self.touched = 0
        self._dst = np.empty(0, np.int64)
        if self.heading:  # the heading lattice keeps a heuristic and a workspace instead (module docstring)
            return
        self._fw = lattice.move_energies_j()  # the planner's own weights, changed in place by update
        self._rw = reverse_weights(self._fw, self._delta)
        self._set_goal_joins()

    @property
    def cost(self) -> Any:
        """The :class:`EnergyCost` of the current lattice."""
        return self.lattice.cost

    def _set_goal_joins(self) -> np.ndarray:
        """Join the goal to the current lattice; the nodes looked at again (old and new joins)."""
        old = self._dst
        self._exit[old] = math.inf
        self._dst, e_dst = self.lattice.joins(self.goal_xy_m, to_point=True)
        self._exit[self._dst] = e_dst
        nodes = np.union1d(old, self._dst)
        self._touch(nodes)
        return nodes

    def _touch(self, nodes: np.ndarray) -> None:
        g = self.goal_xy_m
        self._size = dstar_touch(
            np.ascontiguousarray(nodes, dtype=np.int64), self._fw, self._delta, self._g, self._rhs,
            self._exit, self._key1, self._key2, self._nodes, self._where, self._size, self._col_x, self._row_y,
            self._nj, float(g[0]), float(g[1]), 0.0,
        )

    def update(self, lattice: Lattice) -> IncrementalPlanner:
        """Take new move energies: ``lattice`` is this planner's lattice refreshed for new tables.

        Only the nodes whose moves changed (:meth:`Lattice.changed_moves_since`: free when
        ``lattice`` was refreshed from the current one) and the goal's joins are looked at
        again; the next :meth:`plan` repairs the search from them.

        Parameters
        ----------
        lattice : Lattice
            A lattice over the same node grid (normally ``Lattice.for_cost(new_cost, stride)``
            after ``new_cost = cost.with_tables(...)``).

        Returns
        -------
        IncrementalPlanner
            ``self``; :attr:`touched` counts the nodes looked at again.

        Raises
        ------
        InvalidParameterError
            ``lattice`` not a lattice over the same map grid, stride and node grid.
        """
        if not isinstance(lattice, Lattice):
            raise InvalidParameterError(f"lattice must be a Lattice, got {type(lattice).__name__!r}")
        moves = lattice.changed_moves_since(self.lattice)
        self._answer = None
        if self.heading:
            self.touched = int(np.unique(moves // LATTICE_OFFSETS.shape[0]).size)
            self._stale += self.touched
            if self._h is not None and self._stale > lattice.n_nodes * self.REFRESH_SHARE:
                self._h = None  # rises over much of the map leave the bound loose: computed again
            elif self._h is not None:
                lower_cost_to_go(self._h, lattice, moves, self.goal_xy_m)
            self.lattice = lattice
            return self
        # new energies (inf: the edge vanished) into both tables; a changed move stays on the grid
        moves = np.ascontiguousarray(moves, dtype=np.int64)
        heads = set_moves(moves, lattice.move_energies_j(moves), self._fw, self._rw, self._delta)
        self.lattice = lattice
        self._touch(heads)
        goal_side = self._set_goal_joins()  # ascending
        at = np.minimum(np.searchsorted(heads, goal_side), max(heads.size - 1, 0))
        both = np.count_nonzero(heads[at] == goal_side) if heads.size else 0
        self.touched = int(heads.size + goal_side.size - both)
        return self

    def plan(self, start_xy_m: tuple[float, float]) -> LatticePath:
        """The minimum-energy lattice route from ``start_xy_m`` to the goal, repairing the last search.

        Parameters
        ----------
        start_xy_m : (float, float)
            The start (m); it may differ from call to call (a moving robot).

        Returns
        -------
        LatticePath
            As :meth:`Lattice.shortest_path` (``weight="energy"``): ``found=False`` when no
            route exists; ``solve_time_s`` is this call's time.

        Raises
        ------
        InvalidParameterError, OutOfBoundsError
            NaN start / start outside the map.
        """
        t0 = time.perf_counter()
        pts = as_points(start_xy_m, "start_xy_m")
        cost = self.cost
        cost.check_inside(pts, "start_xy_m")
        start, goal = pts[0], self.goal_xy_m
        if self.heading:  # drive and turns: searched again unless neither the start nor the energies moved
            key = (float(start[0]), float(start[1]))
            self.expanded = 0
            if self._answer is None or self._answer[0] != key:
                if self._h is None:
                    self._h, self._stale = heading_cost_to_go(self.lattice, start, goal), 0
                if self._ws is None:
                    self._ws = HeadingWorkspace(self.lattice.n_nodes)
                self._answer = key, heading_shortest_path(self.lattice, start, goal, cost_to_go=self._h,
                                                          workspace=self._ws)
                self.expanded = self._ws.last_touched
            return dataclasses.replace(self._answer[1], solve_time_s=time.perf_counter() - t0)
        e_direct = float(cost.segment_energy_j(start, goal)[0])
        src, e_src = self.lattice.joins(start)
        nodes, objective = np.empty(0, np.int64), math.inf
        self.expanded = 0
        if src.size and self._dst.size:
            sx, sy, h_per_m = float(start[0]), float(start[1]), max(float(cost.min_energy_per_metre_j), 0.0)
            dstar_rekey(self._g, self._rhs, self._key1, self._key2, self._nodes, self._where, self._size,
                        self._col_x, self._row_y, self._nj, sx, sy, h_per_m)
            best, self.expanded, self._size = dstar_search(
                src, e_src, self._fw, self._rw, self._delta, self._g, self._rhs, self._exit, self._key1, self._key2,
                self._nodes, self._where, self._size, self._col_x, self._row_y, self._nj, sx, sy, h_per_m,
            )
            if best < e_direct:
                nodes, objective = dstar_path(src, e_src, self._fw, self._delta, self._g, self._exit)
        if not objective < e_direct:  # the direct segment (or nothing) is best, as in shortest_path
            nodes, objective = np.empty(0, np.int64), e_direct
        return self.lattice.path_via(start, nodes, goal, float(objective), "energy", time.perf_counter() - t0)

    #: Share of the lattice's nodes whose moves may change (summed over updates) before the heading
    #: search's heuristic is computed again rather than kept (rises leave it a looser bound).
    REFRESH_SHARE = 0.125

    #: The search's arrays (besides the move energies, which follow from the lattice).
    SEARCH_ARRAYS = ("g", "rhs", "exit", "key1", "key2", "nodes", "where", "dst")

    def search_state(self) -> dict[str, np.ndarray]:
        """The search's memory as arrays (copies), for :meth:`restore_search` in a planner built
        again over the same lattice: a restored planner repairs exactly as this one would (empty
        with ``heading``, its heuristic)."""
        if self.heading:
            return {} if self._h is None else {"cost_to_go": self._h.copy(), "stale": np.array([self._stale], np.int64)}
        out = {name: getattr(self, f"_{name}").copy() for name in self.SEARCH_ARRAYS}
        out["size"] = np.array([self._size], np.int64)
        return out

    def restore_search(self, state: dict[str, np.ndarray]) -> IncrementalPlanner:
        """Put back a :meth:`search_state` taken from a planner over this lattice (its moves'
        energies must be this planner's).

        Raises
        ------
        InvalidParameterError
            Missing arrays, or arrays of another lattice's size.
        """
        if self.heading:
            h, stale = state.get("cost_to_go"), state.get("stale")
            if h is None:
                return self
            if (not isinstance(h, np.ndarray) or h.shape != (self.lattice.n_nodes,) or not isinstance(stale, np.ndarray)
                    or stale.shape != (1,) or np.isnan(h).any()):
                raise InvalidParameterError(f"search state 'cost_to_go' not of this lattice ({self.lattice.n_nodes} nodes)")
            self._h, self._stale, self._answer = np.array(h, dtype=float), int(stale[0]), None
            return self
        n = self._g.size
        for name in self.SEARCH_ARRAYS:
            arr = state.get(name)
            ref = getattr(self, f"_{name}")
            if not isinstance(arr, np.ndarray) or (name != "dst" and arr.shape != ref.shape) or arr.ndim != 1:
                raise InvalidParameterError(f"search state {name!r} missing or not of this lattice ({n} nodes)")
            setattr(self, f"_{name}", np.ascontiguousarray(arr, dtype=ref.dtype))
        size = state.get("size")
        if not isinstance(size, np.ndarray) or size.shape != (1,) or not 0 <= int(size[0]) <= n:
            raise InvalidParameterError("search state 'size' missing or out of range")
        self._size = int(size[0])
        return self

    def replan(self, start_xy_m: tuple[float, float], lattice: Lattice | None = None) -> LatticePath:
        """:meth:`update` with ``lattice`` (if given), then :meth:`plan` from ``start_xy_m``."""
        if lattice is not None:
            self.update(lattice)
        return self.plan(start_xy_m)

    def route(
        self,
        start_xy_m: tuple[float, float],
        *,
        seed: int | None = None,
        refine: bool = True,
        settings: PlannerSettings | None = None,
    ) -> Route:
        """The route ``plan_route(terrain, start, goal, cost=self.cost, planner="lattice")`` gives,
        from this planner's incremental search.

        The same checks (start and goal on free cells, in one connected region: else
        ``"infeasible"``), the same fallback to the 1-cell lattice when a coarser one finds
        nothing, the same refinement (:func:`~planner.refine.refine_route`, seeded by ``seed`` or
        ``REFINE_DEFAULT_SEED``), the same shortest-route candidate
        (:func:`~planner.refined.refine_planned`) and costing (:func:`evaluate_route`).

        Parameters
        ----------
        start_xy_m : (float, float)
        seed : int, optional
            Seed of the refinement.
        refine : bool
            Refine the lattice route (the planner's name then reads ``"lattice+refine"``).
        settings : PlannerSettings, optional
            Refinement steps and rounds.

        Returns
        -------
        Route
            ``"exact"`` or ``"infeasible"``; ``planning_time_s`` holds the search and the
            refinement.

        Raises
        ------
        InvalidParameterError
            NaN start, start equal to the goal, bad seed or settings.
        OutOfBoundsError
            Start outside the map.
        BlockedPositionError
            Start or goal on a blocked cell.
        """
        settings = PlannerSettings() if settings is None else settings
        if not isinstance(settings, PlannerSettings):
            raise InvalidParameterError(f"settings must be a PlannerSettings, got {type(settings).__name__!r}")
        refine = check_bool("refine", refine)
        seed = check_seed(seed)
        cost = self.cost
        problem = PlanningProblem(cost, start_xy_m, self.goal_xy_m)  # the query's checks, as plan_route makes them
        start, goal = problem.start, problem.goal
        if not problem.connected:
            return empty_route("infeasible", "lattice", 0.0, cost.battery_voltage_v)
        t0 = time.perf_counter()
        path = self.plan(start)
        if not path.found and self.lattice.stride_cells > 1:  # a passage too narrow for the coarse lattice
            fine = Lattice.for_cost(cost, 1)
            path = heading_shortest_path(fine, start, goal) if self.heading else fine.shortest_path(start, goal)
        elapsed = time.perf_counter() - t0
        if not path.found:
            return empty_route("infeasible", "lattice", elapsed, cost.battery_voltage_v)
        waypoints, name = path.waypoints_m, "lattice"
        if refine:
            t0 = time.perf_counter()
            waypoints, name = refine_planned(problem, "lattice", waypoints, seed, settings)
            elapsed += time.perf_counter() - t0
        return evaluate_route(cost, waypoints, status="exact", planner=name, planning_time_s=elapsed)
