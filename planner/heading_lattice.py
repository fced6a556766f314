"""The heading lattice: the 16-connected lattice searched over (node, heading), so its optimum pays for its turns.

A heading-free lattice (:class:`~planner.Lattice`) minimises drive energy alone; every route
is then priced with its turns too (:meth:`EnergyCost.path_energy_j`: each waypoint's turn in
place at the robot's turn rate, electronics running, the skid-steer turning resistance). For a
robot whose turns are slow or costly the two disagree: the drive-optimal route zig-zags and
its turns cost more than a longer, straighter one (a tracked platform turning at 0.02 rad/s
paid 6 % more on its "minimum-energy" route than on the shortest).

The heading lattice's states are ``(node, h)``: at ``node``, having arrived by move ``h`` (one of
the 16 :data:`~planner.lattice.LATTICE_OFFSETS`, so 16 headings match the 16 moves). Leaving by
move ``k`` costs the turn at ``node`` from ``h`` to ``k`` (:meth:`EnergyCost.turn_energy_at` of the
node's cell, at the angle between the two moves) plus the move's drive energy (the heading-free
lattice's weight). The start is joined to nearby nodes as in the heading-free lattice, the first
turn taken at the joined node from the joining segment's heading; the goal likewise, with the
turn onto the goal segment. So the cost of a state path is exactly the price
:meth:`EnergyCost.path_energy_j` gives its waypoints, and the optimum over the heading lattice
*is* the minimum of the reported price among lattice routes.

The search is the compiled A* of :mod:`planner.kernels.heading` with the heading-free
lattice's exact cost-to-go as heuristic (a backward Dijkstra bounded by the heading-free
route's own price, which is a feasible heading-lattice route). ``method="dijkstra"`` builds the
state graph explicitly and solves it with :func:`scipy.sparse.csgraph.dijkstra`: the reference
the tests compare the A* with (memory ``16 x`` the heading-free graph: small maps only).
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from terrawatt_base.errors import UnknownNameError

from .kernels import astar
from .kernels.heading import backward_cost_to_go, heading_astar
from .lattice import LATTICE_METHODS, LATTICE_OFFSETS, Lattice, LatticePath
from .points import as_points

__all__ = ["heading_shortest_path", "HEADING_COUNT", "move_turn_angles"]

#: Headings of the heading lattice: one per lattice move.
HEADING_COUNT = LATTICE_OFFSETS.shape[0]


def _heading_rad(drow: np.ndarray, dcol: np.ndarray) -> np.ndarray:
    return np.arctan2(drow, dcol)


def _turn_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Unsigned heading change (rad, in [0, pi]) from heading ``a`` to ``b``, as a route's turns are priced."""
    return np.abs((b - a + math.pi) % (2 * math.pi) - math.pi)


def move_turn_angles() -> np.ndarray:
    """(16, 16) unsigned angle (rad) of the turn from arriving by move ``h`` to leaving by move ``k``."""
    heading = _heading_rad(LATTICE_OFFSETS[:, 0].astype(float), LATTICE_OFFSETS[:, 1].astype(float))
    return _turn_angle(heading[:, None], heading[None, :])


class _Query:
    """A query's arrays: start joins with their first turns, goal exits per heading, node rows, turn tables."""

    def __init__(self, lattice: Lattice, start: np.ndarray, goal: np.ndarray) -> None:
        cost = lattice.cost
        self.lattice = lattice
        self.src, self.e_src = lattice.joins(start)
        self.dst, self.e_dst = lattice.joins(goal, to_point=True)
        rows = cost.ground_rows[np.ix_(lattice.node_rows, lattice.node_cols)].ravel()
        self.node_row = np.where(cost.blocked[np.ix_(lattice.node_rows, lattice.node_cols)].ravel(), 0, rows)
        self.node_row = self.node_row.astype(np.int64)
        n_rows = cost.turn_table_j.shape[0]
        angles = move_turn_angles()
        self.turn = cost.turn_energy_at(np.arange(n_rows)[:, None, None], angles[None, :, :])
        move_heading = _heading_rad(LATTICE_OFFSETS[:, 0].astype(float), LATTICE_OFFSETS[:, 1].astype(float))
        # the sign of y per row does not change an unsigned angle: headings in (row, col) units throughout
        sxy = self._node_rc(self.src)
        dxy = self._node_rc(self.dst)
        srow, scol = self._point_rc(start)
        grow, gcol = self._point_rc(goal)
        join_len = np.hypot(sxy[:, 0] - srow, sxy[:, 1] - scol)
        join_heading = _heading_rad(sxy[:, 0] - srow, sxy[:, 1] - scol)
        ang = _turn_angle(join_heading[:, None], move_heading[None, :])
        self.turn_src = np.where(join_len[:, None] > 0,
                                 cost.turn_energy_at(self.node_row[self.src][:, None], ang), 0.0)
        exit_len = np.hypot(grow - dxy[:, 0], gcol - dxy[:, 1])
        exit_heading = _heading_rad(grow - dxy[:, 0], gcol - dxy[:, 1])
        ang = _turn_angle(move_heading[None, :], exit_heading[:, None])
        exit_turn = np.where(exit_len[:, None] > 0, cost.turn_energy_at(self.node_row[self.dst][:, None], ang), 0.0)
        self.exit_cost = self.e_dst[:, None] + exit_turn
        self.exit_of = np.full(lattice.n_nodes, -1, dtype=np.int64)
        self.exit_of[self.dst] = np.arange(self.dst.size)
        # routes of no lattice move: start -> joined node -> goal, the turn at the node
        both = np.intersect1d(self.src, self.dst)
        self.via_total = np.full(both.size, math.inf)
        self.via = both
        if both.size:
            i = np.searchsorted(self.src, both) if np.all(np.diff(self.src) > 0) else _index_of(self.src, both)
            j = _index_of(self.dst, both)
            ang = _turn_angle(join_heading[i], exit_heading[j])
            turn = np.where((join_len[i] > 0) & (exit_len[j] > 0), cost.turn_energy_at(self.node_row[both], ang), 0.0)
            self.via_total = self.e_src[i] + turn + self.e_dst[j]

    def _node_rc(self, nodes: np.ndarray) -> np.ndarray:
        """Node positions in map cell units (row, col) of the node grid's cells (centres)."""
        lat = self.lattice
        nj = lat.node_cols.size
        return np.column_stack([lat.node_rows[nodes // nj], lat.node_cols[nodes % nj]]).astype(float) + 0.5

    def _point_rc(self, p: np.ndarray) -> tuple[float, float]:
        terrain = self.lattice.cost.terrain
        x0, y0 = terrain.origin_xy_m
        d = terrain.cell_size_m
        return (float(p[1]) - y0) / d, (float(p[0]) - x0) / d


def _index_of(sorted_or_not: np.ndarray, values: np.ndarray) -> np.ndarray:
    order = np.argsort(sorted_or_not, kind="stable")
    return order[np.searchsorted(sorted_or_not[order], values)]


def heading_shortest_path(lattice: Lattice, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float],
                          method: str = "astar") -> LatticePath:
    """The minimum of drive plus turn energy over ``lattice``'s routes from start to goal.

    Parameters
    ----------
    lattice : Lattice
        The heading-free lattice whose moves and weights the heading lattice uses.
    start_xy_m, goal_xy_m : (float, float)
        Points on the map (m).
    method : {"astar", "dijkstra"}
        The compiled A* (module docstring) or scipy's Dijkstra over the explicit state graph
        (the reference; memory 16 times the heading-free graph's).

    Returns
    -------
    LatticePath
        ``objective`` the route's total energy (J): drive and turns, as
        :meth:`EnergyCost.path_energy_j` prices its waypoints; ``weight`` ``"energy"``.

    Raises
    ------
    UnknownNameError
        Unknown ``method``.
    InvalidParameterError, OutOfBoundsError
        NaN points / points outside the map.
    """
    t0 = time.perf_counter()
    if method not in LATTICE_METHODS:
        raise UnknownNameError(f"method must be one of {LATTICE_METHODS!r}, got {method!r}")
    pts = as_points([start_xy_m, goal_xy_m], "start/goal")
    cost = lattice.cost
    cost.check_inside(pts, "start/goal")
    start, goal = pts
    q = _Query(lattice, start, goal)
    best = float(cost.segment_energy_j(start, goal)[0])  # the direct segment: no turn
    nodes: list[int] = []
    if q.via.size and float(q.via_total.min()) < best:
        k = int(np.argmin(q.via_total))
        best, nodes = float(q.via_total[k]), [int(q.via[k])]
    if q.src.size and q.dst.size:
        solve = _astar if method == "astar" else _dijkstra
        total, chain = solve(lattice, q, start, goal, best)
        if chain and total < best:
            best, nodes = total, chain
    path = lattice.path_via(start, nodes, goal, best, "energy")
    return LatticePath(path.found, path.waypoints_m, path.objective, "energy", time.perf_counter() - t0)


def _upper_bound(lattice: Lattice, q: _Query, start: np.ndarray, goal: np.ndarray, best: float) -> float:
    """The heading-free optimum's price with its turns: a feasible heading-lattice route's cost."""
    total, last, pred = astar(lattice._indptr, lattice._indices, lattice._energy_data(), lattice._node_x,
                              lattice._node_y, lattice._nj, q.src, q.e_src, q.dst, q.e_dst, float(goal[0]),
                              float(goal[1]), float(lattice.cost.min_energy_per_metre_j), math.inf)
    if last < 0:
        return best
    chain = []
    node = int(last)
    while node >= 0:
        chain.append(node)
        node = int(pred[node])
    path = lattice.path_via(start, chain[::-1], goal, float(total), "energy")
    return min(best, lattice.cost.path_energy_j(path.waypoints_m))


def _astar(lattice: Lattice, q: _Query, start: np.ndarray, goal: np.ndarray, best: float) -> tuple[float, list[int]]:
    data = lattice._energy_data()
    upper = _upper_bound(lattice, q, start, goal, best)
    h = backward_cost_to_go(lattice._pos, data, LATTICE_OFFSETS, lattice._ni, lattice._nj, q.dst, q.e_dst,
                            upper * (1 + 1e-12) + 1e-9)
    total, last, pred = heading_astar(lattice._pos, data, LATTICE_OFFSETS, lattice._nj, q.node_row, q.turn,
                                      q.src, q.e_src, q.turn_src, q.exit_of, q.exit_cost, h, best)
    if last < 0:
        return math.inf, []
    states = []
    s = int(last)
    while s >= 0:
        states.append(s)
        s = int(pred[s])
    return float(total), _state_nodes(lattice, states[::-1])


def _state_nodes(lattice: Lattice, states: list[int]) -> list[int]:
    """The node chain of a state path: the first state's predecessor node, then each state's node."""
    nj = lattice._nj
    first, h0 = divmod(states[0], HEADING_COUNT)
    delta = LATTICE_OFFSETS[h0, 0] * nj + LATTICE_OFFSETS[h0, 1]
    return [int(first - delta)] + [s // HEADING_COUNT for s in states]


def _dijkstra(lattice: Lattice, q: _Query, start: np.ndarray, goal: np.ndarray,
              best: float) -> tuple[float, list[int]]:
    """scipy's Dijkstra over the explicit state graph (the reference of the compiled A*)."""
    n = lattice.n_nodes
    ns = n * HEADING_COUNT
    moves = lattice.move_energies_j()  # (n, 16), inf: no move
    nj = lattice._nj
    u, k = np.nonzero(np.isfinite(moves))
    v = u + LATTICE_OFFSETS[k, 0] * nj + LATTICE_OFFSETS[k, 1]
    h = np.arange(HEADING_COUNT)
    # arcs (u, h) -> (v, k) for every heading h of u
    tail = (u[:, None] * HEADING_COUNT + h[None, :]).ravel()
    head = np.repeat(v * HEADING_COUNT + k, HEADING_COUNT)
    weight = (q.turn[q.node_row[u][:, None], h[None, :], k[:, None]] + moves[u, k][:, None]).ravel()
    # the virtual start (state ns) enters (v, k) from a start-joined node; the virtual goal is ns + 1
    si, sk = np.nonzero(np.isfinite(moves[q.src]))
    sv = q.src[si] + LATTICE_OFFSETS[sk, 0] * nj + LATTICE_OFFSETS[sk, 1]
    s_tail = np.full(si.size, ns)
    s_head = sv * HEADING_COUNT + sk
    s_weight = q.e_src[si] + q.turn_src[si, sk] + moves[q.src[si], sk]
    g_tail = (q.dst[:, None] * HEADING_COUNT + h[None, :]).ravel()
    g_head = np.full(g_tail.size, ns + 1)
    g_weight = q.exit_cost.ravel()
    rows = np.concatenate([tail, s_tail, g_tail])
    cols = np.concatenate([head, s_head, g_head])
    w = np.concatenate([weight, s_weight, g_weight])
    # scipy keeps the smallest of duplicate (row, col) entries only via an explicit reduction
    order = np.lexsort((w, cols, rows))
    rows, cols, w = rows[order], cols[order], w[order]
    first = np.concatenate([[True], (np.diff(rows) != 0) | (np.diff(cols) != 0)])
    rows, cols, w = rows[first], cols[first], w[first]
    graph = csr_matrix((w, (rows, cols)), shape=(ns + 2, ns + 2))
    dist, pred = dijkstra(graph, directed=True, indices=ns, return_predecessors=True)
    total = float(dist[ns + 1])
    if not (total < best):
        return math.inf, []
    states = []
    s = int(pred[ns + 1])
    while s != ns and s >= 0:
        states.append(s)
        s = int(pred[s])
    return total, _state_nodes(lattice, states[::-1])
