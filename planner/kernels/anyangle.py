"""Compiled any-angle search on the energy objective: a corridor of cells, Theta* in it, and a vertex polish.

- :func:`corridor_index` — the cells within a radius of a polyline, numbered as search nodes;
- :func:`theta_star` — Theta* over those cells' centres (start and goal cells stand for the
  exact start and goal points): each node keeps the cheaper of the straight segment from its
  neighbour's parent and the step from the neighbour, every segment priced by the cell walk
  (:func:`~planner.kernels.walk.walk_forward`), so a node's cost is the exact drive energy
  of its polyline;
- :func:`polish_polyline` — a pattern search on the interior vertices of a polyline with a
  step per vertex, minimising drive + turn energy (the cell walk and
  :func:`~planner.kernels.walk.turn_energy`: a stop, a pivot and a start, nothing where the
  heading does not change), then dropping vertices that do not pay for themselves.

Arguments are the arrays of a :class:`~planner.kernels.arrays.CostArrays`; nothing is
validated here (:mod:`planner.anyangle` checks its inputs).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .arrays import GEO_CELL, GEO_NCOLS, GEO_NROWS, GEO_X0, GEO_Y0
from .graph import heap_pop, heap_set
from .paths import drop_unpaid_vertices, move_vertex
from .walk import walk_forward

__all__ = ["corridor_index", "theta_star", "polish_polyline", "NEIGHBOURS_8", "NEIGHBOURS_16"]

#: (row, col) offsets of the king moves.
NEIGHBOURS_8 = np.array([(0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1)], dtype=np.int64)
#: King moves plus knight moves (the moves of the 16-connected lattice).
NEIGHBOURS_16 = np.concatenate([
    NEIGHBOURS_8,
    np.array([(1, 2), (2, 1), (2, -1), (1, -2), (-1, -2), (-2, -1), (-2, 1), (-1, 2)], dtype=np.int64),
])


@numba.njit(cache=True, nogil=True)
def corridor_index(cells, geo, xs, ys, radius_cells):  # pragma: no cover - compiled
    """Number the free cells within ``radius_cells`` (Chebyshev) of the polyline ``xs, ys``.

    Returns ``index`` (rows, cols; ``-1`` outside the corridor or blocked) and the row and
    column of every node, in row-major order of the cells.
    """
    nr = int(geo[GEO_NROWS])
    nc = int(geo[GEO_NCOLS])
    x0 = geo[GEO_X0]
    y0 = geo[GEO_Y0]
    d = geo[GEO_CELL]
    mark = np.zeros((nr, nc), np.bool_)
    w = radius_cells
    for k in range(xs.size - 1):
        length = math.hypot(xs[k + 1] - xs[k], ys[k + 1] - ys[k]) / d
        steps = max(1, int(math.ceil(length * 2.0)))  # samples every half cell
        for s in range(steps + 1):
            t = s / steps
            c = int(math.floor((xs[k] + t * (xs[k + 1] - xs[k]) - x0) / d))
            r = int(math.floor((ys[k] + t * (ys[k + 1] - ys[k]) - y0) / d))
            for rr in range(max(r - w, 0), min(r + w + 1, nr)):
                for cc in range(max(c - w, 0), min(c + w + 1, nc)):
                    mark[rr, cc] = True
    index = np.full((nr, nc), -1, np.int32)
    n = 0
    for r in range(nr):
        for c in range(nc):
            if mark[r, c] and cells[r, c, 2] >= 0.0:
                index[r, c] = n
                n += 1
    node_r = np.empty(n, np.int64)
    node_c = np.empty(n, np.int64)
    for r in range(nr):
        for c in range(nc):
            u = index[r, c]
            if u >= 0:
                node_r[u] = r
                node_c[u] = c
    return index, node_r, node_c


@numba.njit(cache=True, nogil=True)
def theta_star(cells, table, geo, index, node_r, node_c, moves, sx, sy, gx, gy, h_per_m, upper):
    """Theta* from point (sx, sy) to point (gx, gy) over the nodes of ``index`` (``corridor_index``).

    Node positions are cell centres, except the start's and the goal's cells, which stand for
    the start and goal points. Expanding node ``u`` with parent ``p``, each neighbour ``v``
    (offsets ``moves``) gets the cheaper of ``g[p] + E(p -> v)`` and ``g[u] + E(u -> v)``,
    ``E`` the exact drive energy of the straight segment (``inf`` when it crosses a blocked
    cell); a neighbour whose parent is already ``p`` is not walked again. A* order with ``f = g + h_per_m * |v -
    goal|`` (a lower bound when ``h_per_m`` bounds every free cell's energy per metre from
    below). The search stops when the goal is expanded or when no open node's ``f`` is below
    ``upper`` (the cost of a route already known).

    Returns ``(energy, xs, ys)``: the route's drive energy and its vertices from start to goal;
    ``(inf, [], [])`` when no route in the corridor costs less than ``upper``.
    """  # pragma: no cover - compiled
    n = node_r.size
    x0 = geo[GEO_X0]
    y0 = geo[GEO_Y0]
    d = geo[GEO_CELL]
    nr = index.shape[0]
    nc = index.shape[1]
    empty = np.empty(0)
    rs = min(max(int(math.floor((sy - y0) / d)), 0), nr - 1)
    cs = min(max(int(math.floor((sx - x0) / d)), 0), nc - 1)
    rg = min(max(int(math.floor((gy - y0) / d)), 0), nr - 1)
    cg = min(max(int(math.floor((gx - x0) / d)), 0), nc - 1)
    start = index[rs, cs]
    goal = index[rg, cg]
    if start < 0 or goal < 0 or start == goal:
        return math.inf, empty, empty
    px = np.empty(n)
    py = np.empty(n)
    for u in range(n):
        px[u] = x0 + (node_c[u] + 0.5) * d
        py[u] = y0 + (node_r[u] + 0.5) * d
    px[start] = sx
    py[start] = sy
    px[goal] = gx
    py[goal] = gy
    g = np.full(n, math.inf)
    parent = np.full(n, -1, np.int64)
    closed = np.zeros(n, np.bool_)
    keys = np.empty(n)
    nodes = np.empty(n, np.int64)
    where = np.full(n, -1, np.int64)
    g[start] = 0.0
    parent[start] = start
    size = heap_set(keys, nodes, where, 0, start, h_per_m * math.hypot(sx - gx, sy - gy))
    found = False
    nm = moves.shape[0]
    while size > 0:
        f, u, size = heap_pop(keys, nodes, where, size)
        if f >= upper:
            break
        if u == goal:
            found = True
            break
        closed[u] = True
        p = parent[u]
        gu = g[u]
        gp = g[p]
        xu = px[u]
        yu = py[u]
        xp = px[p]
        yp = py[p]
        ru = node_r[u]
        cu = node_c[u]
        for k in range(nm):
            r = ru + moves[k, 0]
            c = cu + moves[k, 1]
            if r < 0 or r >= nr or c < 0 or c >= nc:
                continue
            v = index[r, c]
            if v < 0 or closed[v]:
                continue
            xv = px[v]
            yv = py[v]
            best = g[v]
            via = -1
            if p != u and parent[v] != p:
                e = gp + walk_forward(cells, table, geo, xp, yp, xv, yv)
                if e < best:
                    best = e
                    via = p
            e = gu + walk_forward(cells, table, geo, xu, yu, xv, yv)
            if e < best:
                best = e
                via = u
            if via >= 0:
                g[v] = best
                parent[v] = via
                size = heap_set(keys, nodes, where, size, v, best + h_per_m * math.hypot(xv - gx, yv - gy))
    if not found:
        return math.inf, empty, empty
    m = 1
    u = goal
    while u != start:
        u = parent[u]
        m += 1
    xs = np.empty(m)
    ys = np.empty(m)
    u = goal
    for i in range(m - 1, -1, -1):
        xs[i] = px[u]
        ys[i] = py[u]
        u = parent[u]
    return g[goal], xs, ys


@numba.njit(cache=True, nogil=True)
def polish_polyline(cells, table, turn_table, geo, xs, ys, step0, step_min, max_sweeps, keep_rtol):
    """Pattern search on the interior vertices of a polyline, minimising drive + turn energy.

    Every interior vertex has its own step (``step0`` at first): a sweep tries to move each
    vertex whose step is still ``>= step_min`` by its step in 8 directions and takes the best
    strict improvement; a vertex that did not move halves its step, a vertex that moved
    wakes its neighbours (their steps grow back to at least its own). Sweeps stop when every
    step is below ``step_min`` or after ``max_sweeps``. Then vertices whose removal does not
    raise the energy by more than ``keep_rtol`` (relative) are dropped. ``xs``/``ys`` are
    updated in place (kept vertices first); returns how many are kept. Every accepted move
    keeps the polyline valid (an invalid position costs ``inf``).
    """  # pragma: no cover - compiled
    n = xs.shape[0]
    if n < 3:
        return n
    step = np.full(n, step0, np.float64)
    step[0] = 0.0
    step[n - 1] = 0.0
    for _ in range(max_sweeps):
        active = False
        for i in range(1, n - 1):
            h = step[i]
            if h < step_min:
                continue
            active = True
            if move_vertex(cells, table, turn_table, geo, xs, ys, i, h):
                if i > 1 and step[i - 1] < h:
                    step[i - 1] = h
                if i < n - 2 and step[i + 1] < h:
                    step[i + 1] = h
            else:
                step[i] = 0.5 * h
        if not active:
            break
    return drop_unpaid_vertices(cells, table, turn_table, geo, xs, ys, n, keep_rtol)
