"""Compiled single-source Dijkstra over a node grid's dense move energies, forward or on the reversed graph.

The graph is the one of :func:`~planner.kernels.graph.lattice_weights`: ``w[u, k]`` is the
energy (J) of move ``k`` (node offset ``(di[k], dj[k])``) out of node ``u = i * nj + j``,
``inf`` when the move is absent. No adjacency lists are built: the neighbours of a node
are its grid offsets. Forward, the search relaxes ``u -> u + offset[k]`` at ``w[u, k]``;
reversed, it relaxes ``u <- u - offset[k]`` at ``w[u - offset[k], k]``, so a reversed
search from a target gives every node's cheapest energy *to* that target. The open set is
the indexed binary heap of :mod:`planner.kernels.graph` (decrease-key, each node once).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .graph import heap_pop, heap_set

__all__ = ["grid_dijkstra"]


@numba.njit(cache=True, nogil=True)
def grid_dijkstra(w, ni, nj, di, dj, src, src_cost, reverse):  # pragma: no cover - compiled
    """Least energy (J) from the virtual source (edges to nodes ``src`` costing ``src_cost``) to every node.

    With ``reverse`` the moves are followed backwards: the result is then every node's least
    energy to the virtual target reached from ``src`` nodes at ``src_cost``. Returns a
    float64 array of ``ni * nj`` energies, ``inf`` where no route exists.
    """
    n = ni * nj
    nk = di.shape[0]
    dist = np.full(n, np.inf)
    keys = np.empty(n)
    nodes = np.empty(n, np.int32)
    where = np.full(n, -1, np.int32)
    size = 0
    for k in range(src.shape[0]):
        u = src[k]
        if src_cost[k] < dist[u]:
            dist[u] = src_cost[k]
            size = heap_set(keys, nodes, where, size, u, src_cost[k])
    # Linear index offsets of the moves. A finite w[u, k] means the move lands on the grid, so
    # no row/column arithmetic is needed: forward, v = u + delta[k] is then a node; reversed,
    # v = u - delta[k] inside [0, n) with a finite w[v, k] is a node whose move k lands on u.
    delta = np.empty(nk, np.int64)
    for k in range(nk):
        delta[k] = di[k] * nj + dj[k]
    while size > 0:
        du, u, size = heap_pop(keys, nodes, where, size)
        for k in range(nk):
            if reverse:
                v = u - delta[k]
                if v < 0 or v >= n:
                    continue
                e = w[v, k]
            else:
                e = w[u, k]
                if e == math.inf:
                    continue  # no move (possibly off the grid: v would not be a node)
                v = u + delta[k]
            nv = du + e
            if nv < dist[v]:
                dist[v] = nv
                size = heap_set(keys, nodes, where, size, v, nv)
    return dist
