"""Compiled D* Lite on a lattice: a backward incremental search whose state is kept between calls.

The search runs from a virtual goal (reached from the lattice nodes near the goal point at
their ``exit_cost``) towards a virtual start (joined to the nodes near the start point at
``src_cost``), as in Koenig & Likhachev's D* Lite (optimised version): ``g[u]`` is the
cost-to-goal of node ``u`` found so far, ``rhs[u]`` its one-step look-ahead
``min(exit_cost[u], min_k w(u, k) + g[u + delta[k]])``; the open set holds exactly the
nodes with ``g != rhs`` under the lexicographic key
``(min(g, rhs) + h(start, u), min(g, rhs))``, ``h = h_per_m * |start - u|``.

The graph is two dense move tables: ``fw[u, k]`` is the weight of move ``k`` of node ``u``,
which goes to ``u + delta[k]`` (``inf``: no such edge), and ``rw[v, k] = fw[v - delta[k], k]``
the weight of move ``k`` into ``v`` (the reverse graph: a node's in-edges in one row). An
edge appearing or vanishing is a weight changing to or from ``inf``. Node ``u`` sits at
``(col_x[u % nj], row_y[u // nj])``.

State arrays (all of length ``n_nodes``, changed in place): ``g``, ``rhs``, ``exit_cost``
and the open set, an indexed binary heap with keys ``key1``, ``key2``, entries ``nodes``
and slots ``where`` (-1: not in the heap); the kernels take and return its ``size``.
Between searches the keys are recomputed for the new start and heuristic
(:func:`dstar_rekey`), so the start may move and ``h_per_m`` may change (it must only stay
a lower bound of every move's energy per metre).
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["reverse_weights", "set_moves", "dstar_touch", "dstar_rekey", "dstar_search", "dstar_path"]


@numba.njit(cache=True, nogil=True)
def reverse_weights(fw, delta):  # pragma: no cover - compiled
    """The reverse move table ``rw[v, k] = fw[v - delta[k], k]`` (``inf``: no move ``k`` into ``v``)."""
    n, nd = fw.shape
    rw = np.full((n, nd), np.inf)
    for v in range(n):
        for k in range(nd):
            u = v - delta[k]
            if 0 <= u < n:
                rw[v, k] = fw[u, k]
    return rw


@numba.njit(cache=True, nogil=True)
def set_moves(moves, energies, fw, rw, delta):  # pragma: no cover - compiled
    """Write new ``energies`` of ``moves`` (ids ``node * nd + k``, ascending, on the node grid)
    into both tables; return the nodes they leave from, ascending, each once."""
    nd = delta.size
    heads = np.empty(moves.size, np.int64)
    count = 0
    for t in range(moves.size):
        u = moves[t] // nd
        k = moves[t] - u * nd
        fw[u, k] = energies[t]
        rw[u + delta[k], k] = energies[t]
        if count == 0 or heads[count - 1] != u:
            heads[count] = u
            count += 1
    return heads[:count]


@numba.njit(cache=True, nogil=True, inline="always")
def _less(a1, a2, b1, b2):  # pragma: no cover - compiled
    return a1 < b1 or (a1 == b1 and a2 < b2)


@numba.njit(cache=True, nogil=True)
def _sift_up(key1, key2, nodes, where, i):  # pragma: no cover - compiled
    a1 = key1[i]
    a2 = key2[i]
    u = nodes[i]
    while i > 0:
        parent = (i - 1) >> 1
        if not _less(a1, a2, key1[parent], key2[parent]):
            break
        key1[i] = key1[parent]
        key2[i] = key2[parent]
        nodes[i] = nodes[parent]
        where[nodes[i]] = i
        i = parent
    key1[i] = a1
    key2[i] = a2
    nodes[i] = u
    where[u] = i


@numba.njit(cache=True, nogil=True)
def _sift_down(key1, key2, nodes, where, size, i):  # pragma: no cover - compiled
    a1 = key1[i]
    a2 = key2[i]
    u = nodes[i]
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and _less(key1[c + 1], key2[c + 1], key1[c], key2[c]):
            c += 1
        if not _less(key1[c], key2[c], a1, a2):
            break
        key1[i] = key1[c]
        key2[i] = key2[c]
        nodes[i] = nodes[c]
        where[nodes[i]] = i
        i = c
    key1[i] = a1
    key2[i] = a2
    nodes[i] = u
    where[u] = i


@numba.njit(cache=True, nogil=True)
def _heap_set(key1, key2, nodes, where, size, u, a1, a2):  # pragma: no cover - compiled
    """Insert ``u`` with key ``(a1, a2)`` or change its key; return the new size."""
    i = where[u]
    if i < 0:
        i = size
        size += 1
        nodes[i] = u
        key1[i] = a1
        key2[i] = a2
        _sift_up(key1, key2, nodes, where, i)
        return size
    up = _less(a1, a2, key1[i], key2[i])
    key1[i] = a1
    key2[i] = a2
    if up:
        _sift_up(key1, key2, nodes, where, i)
    else:
        _sift_down(key1, key2, nodes, where, size, i)
    return size


@numba.njit(cache=True, nogil=True)
def _heap_remove(key1, key2, nodes, where, size, u):  # pragma: no cover - compiled
    """Remove ``u`` (in the heap); return the new size."""
    i = where[u]
    where[u] = -1
    size -= 1
    if i < size:
        key1[i] = key1[size]
        key2[i] = key2[size]
        nodes[i] = nodes[size]
        where[nodes[i]] = i
        if i > 0 and _less(key1[i], key2[i], key1[(i - 1) >> 1], key2[(i - 1) >> 1]):
            _sift_up(key1, key2, nodes, where, i)
        else:
            _sift_down(key1, key2, nodes, where, size, i)
    return size


@numba.njit(cache=True, nogil=True, inline="always")
def _h(u, col_x, row_y, nj, sx, sy, h_per_m):  # pragma: no cover - compiled
    return h_per_m * math.hypot(col_x[u % nj] - sx, row_y[u // nj] - sy)


@numba.njit(cache=True, nogil=True)
def _rhs_of(u, fw, delta, g, exit_cost):  # pragma: no cover - compiled
    """One-step look-ahead of ``u``: its exit to the goal or its best move plus the target's g."""
    r = exit_cost[u]
    for k in range(delta.size):
        w = fw[u, k]
        if w < math.inf:
            t = w + g[u + delta[k]]
            if t < r:
                r = t
    return r


@numba.njit(cache=True, nogil=True)
def _update_vertex(u, g, rhs, key1, key2, nodes, where, size, col_x, row_y, nj, sx, sy, h_per_m):  # pragma: no cover
    """Put ``u`` in the open set with its key if ``g != rhs``, else take it out; return the size."""
    if g[u] != rhs[u]:
        m = min(g[u], rhs[u])
        return _heap_set(key1, key2, nodes, where, size, u, m + _h(u, col_x, row_y, nj, sx, sy, h_per_m), m)
    if where[u] >= 0:
        return _heap_remove(key1, key2, nodes, where, size, u)
    return size


@numba.njit(cache=True, nogil=True)
def dstar_touch(touched, fw, delta, g, rhs, exit_cost, key1, key2, nodes, where, size, col_x, row_y, nj,
                sx, sy, h_per_m):  # pragma: no cover - compiled
    """Recompute ``rhs`` of the ``touched`` nodes (whose out-moves or exit cost changed, already
    written into ``fw`` / ``exit_cost``) and fix their place in the open set; return its size."""
    for t in range(touched.size):
        u = touched[t]
        rhs[u] = _rhs_of(u, fw, delta, g, exit_cost)
        size = _update_vertex(u, g, rhs, key1, key2, nodes, where, size, col_x, row_y, nj, sx, sy, h_per_m)
    return size


@numba.njit(cache=True, nogil=True)
def dstar_rekey(g, rhs, key1, key2, nodes, where, size, col_x, row_y, nj, sx, sy, h_per_m):  # pragma: no cover
    """Recompute every open key for the start ``(sx, sy)`` and ``h_per_m``, and restore the heap."""
    for i in range(size):
        u = nodes[i]
        m = min(g[u], rhs[u])
        key1[i] = m + _h(u, col_x, row_y, nj, sx, sy, h_per_m)
        key2[i] = m
    for i in range(size // 2 - 1, -1, -1):
        _sift_down(key1, key2, nodes, where, size, i)


@numba.njit(cache=True, nogil=True, inline="always")
def _start_value(src, src_cost, g):  # pragma: no cover - compiled
    best = math.inf
    for k in range(src.size):
        t = src_cost[k] + g[src[k]]
        if t < best:
            best = t
    return best


@numba.njit(cache=True, nogil=True)
def dstar_search(src, src_cost, fw, rw, delta, g, rhs, exit_cost, key1, key2, nodes, where, size, col_x,
                 row_y, nj, sx, sy, h_per_m):  # pragma: no cover - compiled
    """Expand open nodes until none can lower the virtual start's value ``min(src_cost + g[src])``:
    until the smallest open key exceeds the start's key ``(value, value)``.

    The keys must be current (:func:`dstar_rekey` after the start or ``h_per_m`` moved: no
    key is ever outdated, unlike D* Lite's ``k_m`` scheme).
    Returns the start's value (``inf``: the goal cannot be reached), the number of nodes
    expanded and the open set's new size.
    """
    nd = delta.size
    expanded = 0
    while size > 0:
        best = _start_value(src, src_cost, g)
        a1 = key1[0]
        a2 = key2[0]
        if _less(best, best, a1, a2):
            break  # ties are expanded: a join to the start may cost 0 (a start on a node)
        u = nodes[0]  # its key is current: every key is (re)computed with this start and h_per_m
        expanded += 1
        if g[u] > rhs[u]:  # over-consistent: settle it and offer it to its predecessors
            g[u] = rhs[u]
            size = _heap_remove(key1, key2, nodes, where, size, u)
            gu = g[u]
            for k in range(nd):
                w = rw[u, k]
                if w == math.inf:
                    continue
                p = u - delta[k]
                t = w + gu
                if t < rhs[p]:
                    rhs[p] = t
                    size = _update_vertex(p, g, rhs, key1, key2, nodes, where, size, col_x, row_y, nj, sx, sy,
                                          h_per_m)
        else:  # under-consistent: forget its value; predecessors that relied on it look again
            g_old = g[u]
            g[u] = math.inf
            for k in range(nd):
                w = rw[u, k]
                if w == math.inf:
                    continue
                p = u - delta[k]
                if rhs[p] == w + g_old:
                    rhs[p] = _rhs_of(p, fw, delta, g, exit_cost)
                    size = _update_vertex(p, g, rhs, key1, key2, nodes, where, size, col_x, row_y, nj, sx, sy,
                                          h_per_m)
            size = _update_vertex(u, g, rhs, key1, key2, nodes, where, size, col_x, row_y, nj, sx, sy, h_per_m)
    return _start_value(src, src_cost, g), expanded, size


@numba.njit(cache=True, nogil=True)
def dstar_path(src, src_cost, fw, delta, g, exit_cost):  # pragma: no cover - compiled
    """Follow the best successors from the virtual start to the goal after :func:`dstar_search`.

    Returns the lattice nodes of the route (empty if none) and its objective: the joining
    segments plus the sum of its moves' weights, added in route order.
    """
    n = g.size
    chain = np.empty(n, np.int64)
    best = math.inf
    total = math.inf
    u = -1
    for k in range(src.size):
        t = src_cost[k] + g[src[k]]
        if t < best:
            best = t
            u = src[k]
            total = src_cost[k]
    if u < 0:
        return chain[:0], math.inf
    count = 0
    while count < n:
        chain[count] = u
        count += 1
        be = exit_cost[u]
        bw = math.inf
        bv = -1
        for k in range(delta.size):
            w = fw[u, k]
            if w == math.inf:
                continue
            v = u + delta[k]
            t = w + g[v]
            if t < be:
                be = t
                bw = w
                bv = v
        if bv < 0:
            return chain[:count], total + exit_cost[u]
        total += bw
        u = bv
    return chain[:0], math.inf  # no descent to the goal (a zero-energy cycle): not expected
