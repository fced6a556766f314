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
route's own price, which is a feasible heading-lattice route).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from terrawatt_base.errors import InvalidParameterError

from .kernels import astar
from .kernels.heading import backward_cost_to_go, heading_astar, heading_reset, heading_search
from .kernels.heading import lower_cost_to_go as lower_kernel
from .lattice import LATTICE_OFFSETS, Lattice, LatticePath
from .points import as_points

__all__ = ["heading_shortest_path", "heading_cost_to_go", "lower_cost_to_go", "HeadingWorkspace", "HEADING_COUNT",
           "move_turn_angles"]

#: Headings of the heading lattice: one per lattice move.
HEADING_COUNT = LATTICE_OFFSETS.shape[0]


def _heading_rad(drow: np.ndarray, dcol: np.ndarray) -> np.ndarray:
    return np.arctan2(drow, dcol)


def _turn_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Unsigned heading change (rad, in [0, pi]) from heading ``a`` to ``b``, as a route's turns are priced."""
    return np.abs((b - a + math.pi) % (2 * math.pi) - math.pi)


#: Heading (rad, in map cell units (row, col)) of each lattice move.
_MOVE_HEADING = _heading_rad(LATTICE_OFFSETS[:, 0].astype(float), LATTICE_OFFSETS[:, 1].astype(float))


def move_turn_angles() -> np.ndarray:
    """(16, 16) unsigned angle (rad) of the turn from arriving by move ``h`` to leaving by move ``k``."""
    return _turn_angle(_MOVE_HEADING[:, None], _MOVE_HEADING[None, :])


def _node_turns(lattice: Lattice) -> tuple[np.ndarray, np.ndarray]:
    """The turn prices of ``lattice``'s nodes: each node's turn table row (0 on a blocked cell: it has no
    move) and the turn energy (J) of every row by heading pair, shape (rows, 16, 16)."""
    cost = lattice.cost
    cells = np.ix_(lattice.node_rows, lattice.node_cols)
    node_row = np.where(cost.blocked[cells], 0, cost.ground_rows[cells]).ravel().astype(np.int64)
    rows = np.arange(cost.tables.turn_table_j.shape[0])[:, None, None]
    return node_row, np.ascontiguousarray(cost.turn_energy_at(rows, move_turn_angles()[None, :, :]))


def _cell_units(lattice: Lattice, xy: np.ndarray) -> np.ndarray:
    """Points (m) in map cell units (row, col): headings are measured there (a uniform scale of x, y)."""
    terrain = lattice.cost.terrain
    x0, y0 = terrain.origin_xy_m
    xy = np.atleast_2d(xy)
    return np.column_stack([xy[:, 1] - y0, xy[:, 0] - x0]) / terrain.cell_size_m


def _node_units(lattice: Lattice, nodes: np.ndarray) -> np.ndarray:
    return _cell_units(lattice, lattice.node_xy(nodes))


def _start_joins(lattice: Lattice, start: np.ndarray, node_row: np.ndarray,
                turn_row: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The nodes the start joins, their joining energies, the first turn (J) at each onto each move,
    shape (len(src), 16), and each joining segment's heading (rad; ``nan`` for a zero-length join,
    which has no heading and so no turn)."""
    src, e_src = lattice.joins(start)
    rc = _node_units(lattice, src) - _cell_units(lattice, start)
    heading = np.where(np.hypot(rc[:, 0], rc[:, 1]) > 0, _heading_rad(rc[:, 0], rc[:, 1]), np.nan)
    ang = _turn_angle(heading[:, None], _MOVE_HEADING[None, :])
    turn = np.where(np.isfinite(heading)[:, None], turn_row(node_row[src][:, None], np.nan_to_num(ang)), 0.0)
    return src, e_src, turn, heading


def _goal_exits(lattice: Lattice, goal: np.ndarray, node_row: np.ndarray,
               turn_row: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The nodes joined to the goal, their segments' energies, the exit cost (J) from each with each
    heading (the turn onto the goal segment plus its energy), shape (len(dst), 16), and each exit
    segment's heading (``nan``: zero length, no turn)."""
    dst, e_dst = lattice.joins(goal, to_point=True)
    rc = _cell_units(lattice, goal) - _node_units(lattice, dst)
    heading = np.where(np.hypot(rc[:, 0], rc[:, 1]) > 0, _heading_rad(rc[:, 0], rc[:, 1]), np.nan)
    ang = _turn_angle(_MOVE_HEADING[None, :], heading[:, None])
    turn = np.where(np.isfinite(heading)[:, None], turn_row(node_row[dst][:, None], np.nan_to_num(ang)), 0.0)
    return dst, e_dst, e_dst[:, None] + turn, heading


class _Query:
    """A query's arrays: start joins with their first turns, goal exits per heading, node rows, turn tables."""

    def __init__(self, lattice: Lattice, start: np.ndarray, goal: np.ndarray) -> None:
        cost = lattice.cost
        self.node_row, self.turn = _node_turns(lattice)
        self.src, self.e_src, self.turn_src, join_heading = _start_joins(lattice, start, self.node_row,
                                                                        cost.turn_energy_at)
        self.dst, self.e_dst, self.exit_cost, exit_heading = _goal_exits(lattice, goal, self.node_row,
                                                                        cost.turn_energy_at)
        self.exit_of = np.full(lattice.n_nodes, -1, dtype=np.int64)
        self.exit_of[self.dst] = np.arange(self.dst.size)
        # routes of no lattice move: start -> joined node -> goal, the turn at the node
        self.via = np.intersect1d(self.src, self.dst)
        self.via_total = np.full(self.via.size, math.inf)
        if self.via.size:
            i, j = _index_of(self.src, self.via), _index_of(self.dst, self.via)
            a, b = join_heading[i], exit_heading[j]
            both = np.isfinite(a) & np.isfinite(b)
            turn = np.where(both, cost.turn_energy_at(self.node_row[self.via], np.nan_to_num(_turn_angle(a, b))), 0.0)
            self.via_total = self.e_src[i] + turn + self.e_dst[j]


def _index_of(sorted_or_not: np.ndarray, values: np.ndarray) -> np.ndarray:
    order = np.argsort(sorted_or_not, kind="stable")
    return order[np.searchsorted(sorted_or_not[order], values)]


def heading_shortest_path(lattice: Lattice, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float],
                          *, cost_to_go: np.ndarray | None = None,
                          workspace: HeadingWorkspace | None = None) -> LatticePath:
    """The minimum of drive plus turn energy over ``lattice``'s routes from start to goal.

    Parameters
    ----------
    lattice : Lattice
        The heading-free lattice whose moves and weights the heading lattice uses.
    start_xy_m, goal_xy_m : (float, float)
        Points on the map (m).
    cost_to_go : ndarray, shape (lattice.n_nodes,), optional
        The A*'s heuristic: a consistent lower bound of each node's heading-free cost to this
        goal (:func:`heading_cost_to_go` computes one, :func:`lower_cost_to_go` keeps one
        valid after weights change). Default: computed for this query. A replanner passes
        the one it keeps (a wrong bound gives a wrong answer: it is not checked).
    workspace : HeadingWorkspace, optional
        The A*'s state arrays, reused between queries (default: fresh arrays).

    Returns
    -------
    LatticePath
        ``objective`` the route's total energy (J): drive, turns and the start and stop at its
        ends, as :meth:`EnergyCost.path_energy_j` prices its waypoints (the search minimises it
        without the ends, the same for every route: :meth:`EnergyCost.start_and_stop_j`);
        ``weight`` ``"energy"``.

    Raises
    ------
    InvalidParameterError, OutOfBoundsError
        NaN points / points outside the map.
    """
    t0 = time.perf_counter()
    pts = as_points([start_xy_m, goal_xy_m], "start/goal")
    cost = lattice.cost
    cost.check_inside(pts, "start/goal")
    start, goal = pts
    q = _Query(lattice, start, goal)
    best, nodes = _no_move_route(cost, q, start, goal)
    if workspace is not None and workspace.incumbent is not None:
        bound, suffix = _incumbent(lattice, q, workspace.incumbent)
        if bound < best:  # a lattice route of the last answer: the A* need only beat it
            best, nodes = bound, suffix
    if q.src.size and q.dst.size:
        total, chain = _astar(lattice, q, start, goal, best, cost_to_go, workspace)
        if chain and total < best:
            best, nodes = total, chain
    if workspace is not None:
        workspace.incumbent = np.asarray(nodes, dtype=np.int64)
    path = lattice.path_via(start, nodes, goal, best, "energy")
    objective = path.objective + cost.start_and_stop_j(start, goal) if path.found else path.objective
    return LatticePath(path.found, path.waypoints_m, objective, "energy", time.perf_counter() - t0)


def _no_move_route(cost: Any, q: _Query, start: np.ndarray, goal: np.ndarray) -> tuple[float, list[int]]:
    """The best route of no lattice move: the direct segment (no turn) or start, one joined node, goal."""
    best = float(cost.segment_energy_j(start, goal)[0])
    nodes: list[int] = []
    if q.via.size and float(q.via_total.min()) < best:
        k = int(np.argmin(q.via_total))
        best, nodes = float(q.via_total[k]), [int(q.via[k])]
    return best, nodes


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
    return min(best, lattice.cost.path_energy_j(path.waypoints_m) - lattice.cost.start_and_stop_j(start, goal))


def _cost_to_go(lattice: Lattice, q: _Query, start: np.ndarray, goal: np.ndarray, best: float) -> np.ndarray:
    """The heading-free cost-to-go, bounded by a feasible heading-lattice route's price (module docstring)."""
    upper = _upper_bound(lattice, q, start, goal, best)
    return backward_cost_to_go(lattice._pos, lattice._energy_data(), LATTICE_OFFSETS, lattice._ni, lattice._nj,
                               q.dst, q.e_dst, upper * (1 + 1e-12) + 1e-9)


def heading_cost_to_go(lattice: Lattice, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float]) -> np.ndarray:
    """Each node's heading-free cost (J) to the goal: the heading A*'s heuristic, for reuse.

    Exact where it is below the price (turns included) of the heading-free route from
    ``start_xy_m``; every other node gets that bound (a lower bound of its cost), so the array
    stays a consistent lower bound, valid for any start (tightest for routes no dearer than
    this one). Keep it valid after weights change with :func:`lower_cost_to_go`.

    Returns
    -------
    ndarray, shape (lattice.n_nodes,)
        Float64 (J).

    Raises
    ------
    InvalidParameterError, OutOfBoundsError
        NaN points / points outside the map.
    """
    pts = as_points([start_xy_m, goal_xy_m], "start/goal")
    lattice.cost.check_inside(pts, "start/goal")
    start, goal = pts
    q = _Query(lattice, start, goal)
    if not (q.src.size and q.dst.size):
        return np.zeros(lattice.n_nodes)  # no lattice route: any zero bound is consistent
    best, _ = _no_move_route(lattice.cost, q, start, goal)
    return _cost_to_go(lattice, q, start, goal, best)


def lower_cost_to_go(cost_to_go: np.ndarray, lattice: Lattice, moves: np.ndarray, goal_xy_m: tuple[float, float]) -> int:
    """Keep a :func:`heading_cost_to_go` array a consistent lower bound after move energies changed.

    ``cost_to_go`` was valid for the lattice before the change; ``lattice`` is the refreshed
    one and ``moves`` the ids of the moves whose energy changed (:meth:`Lattice.changed_moves_since`).
    Where energies rose the old values remain lower bounds; where a move or a goal join got
    cheaper, the lowering is propagated (:func:`planner.kernels.heading.lower_cost_to_go`),
    in place. Returns the number of nodes lowered.
    """
    moves = np.asarray(moves, dtype=np.int64)
    u, k = np.divmod(moves, HEADING_COUNT)
    w = lattice.move_energies_j(moves)
    ok = np.isfinite(w)
    v = u[ok] + LATTICE_OFFSETS[k[ok], 0] * lattice._nj + LATTICE_OFFSETS[k[ok], 1]
    offer = w[ok] + cost_to_go[v]
    dst, e_dst = lattice.joins(as_points(goal_xy_m, "goal_xy_m")[0], to_point=True)
    seeds = np.concatenate([u[ok], dst]).astype(np.int64)
    seed_cost = np.concatenate([offer, e_dst]).astype(float)
    return int(lower_kernel(lattice._pos, lattice._energy_data(), LATTICE_OFFSETS, lattice._ni, lattice._nj,
                            cost_to_go, seeds, seed_cost))


class HeadingWorkspace:
    """The heading A*'s arrays (one entry per state, 41 bytes: 172 MB at 512^2 nodes), kept between queries.

    A search from scratch allocates (and the system zeroes) these arrays for every query,
    about half its time on a large lattice; a replanner keeps one workspace and each search
    puts back only the entries it touched. It also keeps the last answer's node chain: a
    replan after new energies or a few metres of driving starts from that route's price on
    the new lattice (from the node where the new start joins it), so the A* keeps no state
    that cannot beat it.
    """

    def __init__(self, n_nodes: int) -> None:
        ns = int(n_nodes) * HEADING_COUNT
        self.n_nodes = int(n_nodes)
        self.g = np.full(ns, np.inf)
        self.pred = np.full(ns, -2, np.int64)
        self.closed = np.zeros(ns, np.bool_)
        self.keys = np.empty(ns)
        self.heap = np.empty(ns, np.int64)
        self.where = np.full(ns, -1, np.int64)
        self.touched = np.empty(ns, np.int64)
        #: States the last search touched.
        self.last_touched = 0
        #: The node chain of the last answer (None before the first): the next query's incumbent,
        #: re-priced on its lattice from wherever its start joins the chain (:func:`_incumbent`).
        self.incumbent: np.ndarray | None = None


def _astar(lattice: Lattice, q: _Query, start: np.ndarray, goal: np.ndarray, best: float,
           h: np.ndarray | None = None, ws: HeadingWorkspace | None = None) -> tuple[float, list[int]]:
    data = lattice._energy_data()
    if h is None:
        h = _cost_to_go(lattice, q, start, goal, best)
    elif h.shape != (lattice.n_nodes,):
        raise InvalidParameterError(f"cost_to_go must have one value per lattice node ({lattice.n_nodes}), "
                                    f"got shape {h.shape}")
    args = (lattice._pos, data, LATTICE_OFFSETS, lattice._nj, q.node_row, q.turn, q.src, q.e_src, q.turn_src,
            q.exit_of, q.exit_cost, h, best)
    if ws is None:
        total, last, pred = heading_astar(*args)
        return (math.inf, []) if last < 0 else (float(total), _state_nodes(lattice, _chain(pred, int(last))))
    if ws.n_nodes != lattice.n_nodes:
        raise InvalidParameterError(f"workspace is for {ws.n_nodes} nodes, the lattice has {lattice.n_nodes}")
    total, last, count = heading_search(*args, ws.g, ws.pred, ws.closed, ws.keys, ws.heap, ws.where, ws.touched)
    try:
        chain = [] if last < 0 else _chain(ws.pred, int(last))
    finally:
        heading_reset(ws.touched, count, ws.g, ws.pred, ws.closed, ws.where)
        ws.last_touched = int(count)
    return (math.inf, []) if last < 0 else (float(total), _state_nodes(lattice, chain))


#: Move index of each node-grid step (row, col) in [-2, 2]^2, offset by 2 (-1: no lattice move).
_MOVE_OF_STEP = np.full((5, 5), -1, dtype=np.int64)
_MOVE_OF_STEP[LATTICE_OFFSETS[:, 0] + 2, LATTICE_OFFSETS[:, 1] + 2] = np.arange(HEADING_COUNT)


def _incumbent(lattice: Lattice, q: _Query, chain: np.ndarray) -> tuple[float, list[int]]:
    """The cheapest lattice route of this query that ends like ``chain`` (an earlier answer's nodes).

    For every node of the chain (but its last) that the start joins: the joining segment,
    the turn onto the chain's next move, then the chain's moves and turns priced on this
    lattice, and the exit to this query's goal from the chain's last node. Returns its total
    and its nodes, or inf and no nodes when the start joins no node of the chain, a move of
    the suffix no longer exists, or the last node is not joined to this goal.
    """
    nodes = np.asarray(chain, dtype=np.int64)
    if nodes.size < 2 or not q.src.size or np.any((nodes < 0) | (nodes >= lattice.n_nodes)):
        return math.inf, []
    nj = lattice._nj
    rows, cols = np.divmod(nodes, nj)
    dr, dc = np.diff(rows), np.diff(cols)
    if np.any(np.abs(dr) > 2) or np.any(np.abs(dc) > 2):
        return math.inf, []
    moves = _MOVE_OF_STEP[dr + 2, dc + 2]
    exit_row = q.exit_of[nodes[-1]]
    if np.any(moves < 0) or exit_row < 0:
        return math.inf, []
    pos = lattice._pos[nodes[:-1], moves]
    drive = np.where(pos >= 0, lattice._energy_data()[np.maximum(pos, 0)], math.inf)
    turns = np.zeros(moves.size)
    turns[1:] = q.turn[q.node_row[nodes[1:-1]], moves[:-1], moves[1:]]  # at each inner node of the chain
    # from node i of the chain: its move, then every later node's turn and move, then the exit
    arcs = drive + turns
    suffix = np.cumsum(arcs[::-1])[::-1] - turns + q.exit_cost[exit_row, moves[-1]]
    where = {int(n): i for i, n in enumerate(nodes[:-1])}  # a chain node's last place
    best, first = math.inf, -1
    for j, node in enumerate(q.src):
        i = where.get(int(node))
        if i is not None:
            total = float(q.e_src[j] + q.turn_src[j, moves[i]] + suffix[i])
            if total < best:
                best, first = total, i
    return (best, [int(n) for n in nodes[first:]]) if first >= 0 else (math.inf, [])


def _chain(pred: np.ndarray, last: int) -> list[int]:
    """The states of a route, first to last, from the predecessor array."""
    states = []
    s = last
    while s >= 0:
        states.append(s)
        s = int(pred[s])
    return states[::-1]


def _state_nodes(lattice: Lattice, states: list[int]) -> list[int]:
    """The node chain of a state path: the first state's predecessor node, then each state's node."""
    nj = lattice._nj
    first, h0 = divmod(states[0], HEADING_COUNT)
    delta = LATTICE_OFFSETS[h0, 0] * nj + LATTICE_OFFSETS[h0, 1]
    return [int(first - delta)] + [s // HEADING_COUNT for s in states]
