"""Compiled lattice-graph kernels: directed move energies of a node grid, their refresh, an indexed heap, and A*."""

from __future__ import annotations

import math

import numba
import numpy as np

from .variants import compile_variants, use_parallel
from .walk import walk_pair

__all__ = [
    "heap_set",
    "heap_pop",
    "heap_sift_up",
    "astar",
    "lattice_weights",
    "lattice_reweight",
    "reweight_band",
    "lattice_weights_serial",
    "lattice_weights_parallel",
    "lattice_reweight_serial",
    "lattice_reweight_parallel",
]


@numba.njit(cache=True, nogil=True)
def heap_sift_up(keys, nodes, where, i):  # pragma: no cover - compiled
    """Move heap entry ``i`` up to its place (``where[node]`` tracks each node's slot)."""
    key = keys[i]
    node = nodes[i]
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= key:
            break
        keys[i] = keys[parent]
        nodes[i] = nodes[parent]
        where[nodes[i]] = i
        i = parent
    keys[i] = key
    nodes[i] = node
    where[node] = i


@numba.njit(cache=True, nogil=True)
def heap_set(keys, nodes, where, size, node, key):  # pragma: no cover - compiled
    """Insert ``node`` with ``key``, or lower its key if it is in the heap; return the new size."""
    i = where[node]
    if i < 0:
        i = size
        nodes[i] = node
        size += 1
    keys[i] = key
    heap_sift_up(keys, nodes, where, i)
    return size


@numba.njit(cache=True, nogil=True)
def heap_pop(keys, nodes, where, size):  # pragma: no cover - compiled
    """Pop the minimum of the indexed binary heap ``keys[:size]``; return key, node, new size."""
    top_k = keys[0]
    top_n = nodes[0]
    where[top_n] = -1
    size -= 1
    if size > 0:
        key = keys[size]
        node = nodes[size]
        i = 0
        while True:
            c = 2 * i + 1
            if c >= size:
                break
            if c + 1 < size and keys[c + 1] < keys[c]:
                c += 1
            if key <= keys[c]:
                break
            keys[i] = keys[c]
            nodes[i] = nodes[c]
            where[nodes[i]] = i
            i = c
        keys[i] = key
        nodes[i] = node
        where[node] = i
    return top_k, top_n, size


@numba.njit(cache=True, nogil=True)
def astar(indptr, indices, data, node_x, node_y, nj, src, src_cost, dst, dst_cost, gx, gy, h_per_m, upper):
    """A* from a virtual start (edges to ``src`` costing ``src_cost``) to a virtual goal (reached
    from ``dst`` at ``dst_cost``). Returns the best total (``upper`` if none is lower), the last
    lattice node of that route (-1: none) and the predecessor array (-1: the virtual start).
    The open set is an indexed binary heap with decrease-key (each node at most once)."""  # pragma: no cover
    n = indptr.size - 1
    g = np.full(n, np.inf)
    pred = np.full(n, -2, np.int64)
    closed = np.zeros(n, np.bool_)
    exit_cost = np.full(n, np.inf)
    for k in range(dst.size):
        if dst_cost[k] < exit_cost[dst[k]]:
            exit_cost[dst[k]] = dst_cost[k]
    keys = np.empty(n)
    nodes = np.empty(n, np.int64)
    where = np.full(n, -1, np.int64)
    size = 0
    best = upper
    best_node = -1
    for k in range(src.size):
        u = src[k]
        if src_cost[k] < g[u]:
            g[u] = src_cost[k]
            pred[u] = -1
            f = src_cost[k] + h_per_m * math.hypot(node_x[u % nj] - gx, node_y[u // nj] - gy)
            size = heap_set(keys, nodes, where, size, u, f)
    while size > 0:
        f, u, size = heap_pop(keys, nodes, where, size)
        if f >= best:
            break  # no open node can lead to a cheaper route
        closed[u] = True
        gu = g[u]
        if gu + exit_cost[u] < best:
            best = gu + exit_cost[u]
            best_node = u
        for p in range(indptr[u], indptr[u + 1]):
            v = indices[p]
            if closed[v]:
                continue
            nv = gu + data[p]
            if nv < g[v]:
                g[v] = nv
                pred[v] = u
                f = nv + h_per_m * math.hypot(node_x[v % nj] - gx, node_y[v // nj] - gy)
                size = heap_set(keys, nodes, where, size, v, f)
    return best, best_node, pred


def _lattice_weights(cells, table, geo, stride, offset, ni, nj, half):  # pragma: no cover - compiled
    """Directed energies of the 16 moves of every node; ``inf`` = no edge."""
    n = ni * nj
    nh = half.shape[0]
    w = np.full((n, 2 * nh), np.inf)
    x0 = geo[0]
    y0 = geo[1]
    d = geo[2]
    for i in numba.prange(ni):
        ya = y0 + ((i * stride + offset) + 0.5) * d
        for j in range(nj):
            xa = x0 + ((j * stride + offset) + 0.5) * d
            src = i * nj + j
            for k in range(nh):
                ti = i + half[k, 0]
                tj = j + half[k, 1]
                if ti < 0 or ti >= ni or tj < 0 or tj >= nj:
                    continue
                xb = x0 + ((tj * stride + offset) + 0.5) * d
                yb = y0 + ((ti * stride + offset) + 0.5) * d
                ef, eb = walk_pair(cells, table, geo, xa, ya, xb, yb, True)
                w[src, k] = ef
                w[ti * nj + tj, nh + k] = eb  # the reverse move is offset k + nh from the target
    return w


def _lattice_reweight(cells, table, geo, stride, offset, ni, nj, half, changed_sat, pos, data,
                      i0=0, i1=-1, j0=0, j1=-1, data_lo=0):  # pragma: no cover - compiled
    """Recompute, into ``data``, the energies of the edges whose cell box holds a changed cell.

    ``changed_sat`` is the summed-area table of the changed-cell mask (shape rows+1, cols+1);
    ``pos[node, k]`` is the index of move ``k`` of ``node`` among the edges (-1: no edge),
    whose weight is ``data[pos - data_lo]`` (``data`` may hold a slice of the weights). Only
    the half-plane moves of the nodes in rows ``i0:i1`` and columns ``j0:j1`` are looked at
    (default all; ``-1``: to the end); their edges lie in node rows ``i0:i1 + 2``. Returns
    per node-row counts of recomputed moves and of edges whose presence would change (an
    absent edge becoming finite or a present one becoming ``inf``), and a
    ``((min(ni, i1 + 2) - i0) * nj, 2 * nh)`` mask (uint8) of the moves whose energy changed
    (``inf`` standing for an absent edge), its first row being node ``i0 * nj``.
    """
    nh = half.shape[0]
    if i1 < 0:
        i1 = ni
    if j1 < 0:
        j1 = nj
    recomputed = np.zeros(ni, np.int64)
    flips = np.zeros(ni, np.int64)
    first = i0 * nj
    changed = np.zeros(((min(ni, i1 + 2) - i0) * nj, 2 * nh), np.uint8)
    for ii in numba.prange(i1 - i0):
        i = i0 + ii
        ra = i * stride + offset
        ya = geo[1] + (ra + 0.5) * geo[2]
        for j in range(j0, j1):
            ca = j * stride + offset
            xa = geo[0] + (ca + 0.5) * geo[2]
            src = i * nj + j
            for k in range(nh):
                ti = i + half[k, 0]
                tj = j + half[k, 1]
                if ti < 0 or ti >= ni or tj < 0 or tj >= nj:
                    continue
                rb = ti * stride + offset
                cb = tj * stride + offset
                r0 = min(ra, rb)
                r1 = max(ra, rb) + 1
                c0 = min(ca, cb)
                c1 = max(ca, cb) + 1
                if changed_sat[r1, c1] - changed_sat[r0, c1] - changed_sat[r1, c0] + changed_sat[r0, c0] == 0:
                    continue
                xb = geo[0] + (cb + 0.5) * geo[2]
                yb = geo[1] + (rb + 0.5) * geo[2]
                ef, eb = walk_pair(cells, table, geo, xa, ya, xb, yb, True)
                recomputed[i] += 2
                tgt = ti * nj + tj
                q = pos[src, k]
                old = data[q - data_lo] if q >= 0 else math.inf
                if ef != old:
                    changed[src - first, k] = 1
                if q >= 0:
                    data[q - data_lo] = ef
                if (q >= 0) != (ef < math.inf):
                    flips[i] += 1
                q = pos[tgt, nh + k]
                old = data[q - data_lo] if q >= 0 else math.inf
                if eb != old:
                    changed[tgt - first, nh + k] = 1
                if q >= 0:
                    data[q - data_lo] = eb
                if (q >= 0) != (eb < math.inf):
                    flips[i] += 1
    return recomputed, flips, changed


lattice_weights_serial, lattice_weights_parallel = compile_variants(_lattice_weights)
lattice_reweight_serial, lattice_reweight_parallel = compile_variants(_lattice_reweight)


def lattice_weights(cells, table, geo, stride, offset, ni, nj, half):
    """Directed energies ``(ni * nj, 2 * len(half))`` of every node's moves (``inf``: no edge);
    the serial or parallel kernel by work size (one walk per node and half-plane move)."""
    parallel = use_parallel(ni * nj * half.shape[0])
    kernel = lattice_weights_parallel if parallel else lattice_weights_serial
    return kernel(cells, table, geo, stride, offset, ni, nj, half)


def reweight_band(changed_sat, stride, offset, ni, nj, half):
    """Node rows ``i0:i1`` and columns ``j0:j1`` whose half-plane moves can reach a changed cell
    (within their bounding box), from the changed-cell mask's summed-area table; ``None`` when
    no move can."""
    rows, cols = changed_sat.shape[0] - 1, changed_sat.shape[1] - 1
    per_row = changed_sat[1:, cols] - changed_sat[:-1, cols]
    if not per_row.any():
        return None
    per_col = changed_sat[rows, 1:] - changed_sat[rows, :-1]
    reach = int(np.abs(half).max()) * stride  # farthest a move goes along an axis, in cells
    r_min, r_max = np.flatnonzero(per_row)[[0, -1]]
    c_min, c_max = np.flatnonzero(per_col)[[0, -1]]
    # half-plane moves go down (row offsets >= 0): a node's box reaches rows [ra, ra + reach]
    i0 = max(0, (int(r_min) - reach - offset) // stride)
    i1 = min(ni, (int(r_max) - offset) // stride + 1)
    j0 = max(0, (int(c_min) - reach - offset) // stride)
    j1 = min(nj, (int(c_max) + reach - offset) // stride + 1)
    if i1 <= i0 or j1 <= j0:
        return None
    return i0, i1, j0, j1


def lattice_reweight(cells, table, geo, stride, offset, ni, nj, half, changed_sat, pos, data, band, data_lo=0):
    """Recompute in ``data`` the moves whose cell box holds a changed cell (see ``_lattice_reweight``).

    Only the nodes of ``band`` (:func:`reweight_band`) are scanned; ``data`` holds the edge
    weights from index ``data_lo`` on (at least the edges of node rows ``i0:i1 + 2``); the
    serial or parallel kernel by the number of moves to scan. Returns the recomputed and
    flipped counts per node row and the ascending ids ``node * 2 * len(half) + k`` of the
    moves whose energy changed.
    """
    i0, i1, j0, j1 = band
    nh = half.shape[0]
    parallel = use_parallel((i1 - i0) * (j1 - j0) * nh)
    kernel = lattice_reweight_parallel if parallel else lattice_reweight_serial
    recomputed, flips, changed = kernel(cells, table, geo, stride, offset, ni, nj, half, changed_sat, pos, data,
                                        i0, i1, j0, j1, data_lo)
    return recomputed, flips, np.flatnonzero(changed.ravel()) + i0 * nj * 2 * nh
