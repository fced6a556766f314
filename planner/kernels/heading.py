"""Compiled search of the heading lattice: states (node, heading), arcs a turn then a move.

The heading lattice (:class:`planner.heading_lattice.HeadingLattice`) is the state lattice of
the 16-connected node grid: a state ``s = node * 16 + h`` is "at ``node``, having arrived by
move ``h``" (``h`` indexing ``LATTICE_OFFSETS``). Its arcs are implicit: from ``(u, h)``, move
``k`` leads to ``(u + offset_k, k)`` at ``turn[row(u), h, k] + w(u, k)``, the turn in place at
``u`` from heading ``h`` to ``k`` (the cost's turn table, read at the node's cell) plus the move's
drive energy (the heading-free lattice's weight ``data[pos[u, k]]``; ``pos < 0``: no move).
Nothing of size ``states x 16`` is stored.

A query enters from a virtual start: a start-joined node ``s`` is left by move ``k`` at
``e_src + turn_src[i, k] + w(s, k)`` (``turn_src``: the turn at ``s`` from the joining
segment's heading to ``k``), and leaves to a virtual goal from state ``(v, h)`` at
``exit_cost[exit_of[v], h]`` (the turn at ``v`` onto the goal segment plus its energy).

The heuristic is the heading-free lattice's exact cost-to-go, from a backward Dijkstra
(:func:`backward_cost_to_go`): turns cost nothing there, so it is a lower bound of the
heading lattice's cost-to-go, and consistent (it satisfies ``h(u) <= w(u, k) + h(v)``, and
turns only add). The backward search may stop at a bound ``upper`` on the answer: nodes it
did not settle get the last key it popped, which keeps the heuristic consistent.
"""

from __future__ import annotations

import numba
import numpy as np

from .graph import heap_pop, heap_set

__all__ = ["backward_cost_to_go", "backward_lower", "heading_astar", "heading_reset", "heading_search",
           "lower_cost_to_go"]

_N_MOVES = 16


@numba.njit(cache=True, nogil=True)
def backward_cost_to_go(pos, data, offsets, ni, nj, dst, dst_cost, upper):  # pragma: no cover - compiled
    """Heading-free cost (J) from every node to the virtual goal (reached from ``dst`` at ``dst_cost``).

    Dijkstra on the reversed moves (:func:`backward_lower` from nothing known): node ``v`` is
    reached from ``u = v - offset_k`` at ``data[pos[u, k]]``. Stops once the smallest open key
    exceeds ``upper``; every node not settled then (unreachable ones included) gets that key, a
    lower bound of its cost. Returns the cost per node (float64, ``n = ni * nj``).
    """
    h = np.full(ni * nj, np.inf)
    _, floor = backward_lower(pos, data, offsets, ni, nj, h, dst, dst_cost, upper)
    if floor < np.inf:
        for v in range(h.size):
            if h[v] > floor:  # not settled: its key is at least the floor
                h[v] = floor
    return h


@numba.njit(cache=True, nogil=True)
def backward_lower(pos, data, offsets, ni, nj, h, seeds, seed_cost, upper):  # pragma: no cover - compiled
    """Lower the cost-to-go ``h`` in place from ``seeds`` (each offered ``seed_cost``), backwards.

    Dijkstra on the reversed moves from the seeds whose offer is below ``h``: a node popped at
    key ``k`` offers ``k + data[pos[u, k]]`` to each ``u`` that moves into it. Stops once the
    smallest open key exceeds ``upper``. Returns the number of nodes settled and that stopping
    key (inf when the search ran out): nodes not settled hold ``h`` at or above it.
    """
    n = ni * nj
    keys = np.empty(n)
    nodes = np.empty(n, np.int64)
    where = np.full(n, -1, np.int64)
    size = 0
    for i in range(seeds.size):
        u = seeds[i]
        if seed_cost[i] < h[u]:
            h[u] = seed_cost[i]
            size = heap_set(keys, nodes, where, size, u, seed_cost[i])
    settled = 0
    floor = np.inf
    while size > 0:
        key, v, size = heap_pop(keys, nodes, where, size)
        if key > upper:
            floor = key
            break
        settled += 1
        iv = v // nj
        jv = v - iv * nj
        for k in range(_N_MOVES):
            iu = iv - offsets[k, 0]
            ju = jv - offsets[k, 1]
            if iu < 0 or iu >= ni or ju < 0 or ju >= nj:
                continue
            u = iu * nj + ju
            p = pos[u, k]
            if p < 0:
                continue
            nu = key + data[p]
            if nu < h[u]:
                h[u] = nu
                size = heap_set(keys, nodes, where, size, u, nu)
    return settled, floor


@numba.njit(cache=True, nogil=True)
def heading_astar(pos, data, offsets, nj, node_row, turn, src, src_cost, turn_src, exit_of, exit_cost,
                  h_node, upper):  # pragma: no cover - compiled
    """A* over the heading lattice's states (module docstring), in fresh arrays.

    Parameters: ``pos`` (n, 16) move -> weight index (-1: none) and ``data`` the weights;
    ``offsets`` (16, 2) node-grid moves; ``node_row`` (n,) the turn table row of each node's
    cell (-1: blocked); ``turn`` (rows, 16, 16) turn energies by heading pair; ``src`` /
    ``src_cost`` the start-joined nodes and their joining energies, ``turn_src`` (len(src), 16)
    their first turns; ``exit_of`` (n,) a node's row in ``exit_cost`` (len(dst), 16), -1 for a
    node not joined to the goal; ``h_node`` (n,) the heuristic; ``upper`` the best total known
    (a route that takes no lattice move).

    Returns the best total (``upper`` if none is lower), the last state of that route (-1:
    none) and the predecessor array (-1: entered from the virtual start).
    """
    ns = pos.shape[0] * _N_MOVES
    g = np.full(ns, np.inf)
    pred = np.full(ns, -2, np.int64)
    closed = np.zeros(ns, np.bool_)
    where = np.full(ns, -1, np.int64)
    touched = np.empty(ns, np.int64)
    best, best_state, _ = heading_search(pos, data, offsets, nj, node_row, turn, src, src_cost, turn_src, exit_of,
                                         exit_cost, h_node, upper, g, pred, closed, np.empty(ns),
                                         np.empty(ns, np.int64), where, touched)
    return best, best_state, pred


@numba.njit(cache=True, nogil=True)
def heading_search(pos, data, offsets, nj, node_row, turn, src, src_cost, turn_src, exit_of, exit_cost,
                   h_node, upper, g, pred, closed, keys, nodes, where, touched):  # pragma: no cover - compiled
    """The A* of :func:`heading_astar` in a caller's workspace of one entry per state.

    ``g`` (inf), ``pred`` (-2), ``closed`` (False) and ``where`` (-1) must hold those values on
    entry; ``keys`` / ``nodes`` are the heap's storage. Every state whose entries the search
    changes is listed once in ``touched``; returns the best total, its last state and how many
    states are listed (:func:`heading_reset` puts the workspace back).
    """
    nj_ = nj
    size = 0
    count = 0
    best = upper
    best_state = -1
    for i in range(src.size):
        u = src[i]
        for k in range(_N_MOVES):
            p = pos[u, k]
            if p < 0:
                continue
            v = u + offsets[k, 0] * nj_ + offsets[k, 1]
            s = v * _N_MOVES + k
            gv = src_cost[i] + turn_src[i, k] + data[p]
            if gv < g[s] and gv + h_node[v] < best:
                if g[s] == np.inf:
                    touched[count] = s
                    count += 1
                g[s] = gv
                pred[s] = -1
                size = heap_set(keys, nodes, where, size, s, gv + h_node[v])
    while size > 0:
        f, s, size = heap_pop(keys, nodes, where, size)
        if f >= best:
            break  # no open state can lead to a cheaper route
        closed[s] = True
        gs = g[s]
        u = s // _N_MOVES
        h = s - u * _N_MOVES
        e = exit_of[u]
        if e >= 0 and gs + exit_cost[e, h] < best:
            best = gs + exit_cost[e, h]
            best_state = s
        row = node_row[u]
        for k in range(_N_MOVES):
            p = pos[u, k]
            if p < 0:
                continue
            v = u + offsets[k, 0] * nj_ + offsets[k, 1]
            t = v * _N_MOVES + k
            if closed[t]:
                continue
            nv = gs + turn[row, h, k] + data[p]
            if nv < g[t] and nv + h_node[v] < best:  # a state that cannot beat the best route is not kept
                if g[t] == np.inf:
                    touched[count] = t
                    count += 1
                g[t] = nv
                pred[t] = s
                size = heap_set(keys, nodes, where, size, t, nv + h_node[v])
    return best, best_state, count


@numba.njit(cache=True, nogil=True)
def heading_reset(touched, count, g, pred, closed, where):  # pragma: no cover - compiled
    """Put back the workspace entries of the ``count`` states a :func:`heading_search` listed."""
    for i in range(count):
        s = touched[i]
        g[s] = np.inf
        pred[s] = -2
        closed[s] = False
        where[s] = -1


@numba.njit(cache=True, nogil=True)
def lower_cost_to_go(pos, data, offsets, ni, nj, h, seeds, seed_cost):  # pragma: no cover - compiled
    """Lower ``h`` in place where moves got cheaper, keeping it a consistent lower bound.

    ``h`` is a consistent lower bound of the heading-free cost to the goal under the old
    weights (as :func:`backward_cost_to_go` gives). Where weights rose it still is one; where a
    move got cheaper (or appeared) or a goal join did, ``seeds`` / ``seed_cost`` give the node
    and the new value that move offers it (``data[pos[u, k]] + h[v]``, or the join's energy).
    The lowering is propagated backwards (:func:`backward_lower`, each node settled at most
    once), so afterwards ``h[u] <= data[pos[u, k]] + h[v]`` for every move again and ``h`` is a
    lower bound of the new cost-to-go. Returns the number of nodes lowered.
    """
    lowered, _ = backward_lower(pos, data, offsets, ni, nj, h, seeds, seed_cost, np.inf)
    return lowered
