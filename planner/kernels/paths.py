"""Compiled polyline kernels: pattern-search relaxation of a route's energy, greedy line-of-sight pulls."""

from __future__ import annotations

import math

import numba
import numpy as np

from .arrays import GEO_CELL, GEO_NCOLS, GEO_NROWS, GEO_X0, GEO_Y0
from .walk import turn_energy, walk_pair

__all__ = ["relax_polyline", "vertex_energy_j", "move_vertex", "drop_unpaid_vertices", "string_pull_indices", "KEEP_RTOL"]

#: Relative energy change treated as rounding noise (drops collinear vertices; accepts polishing).
KEEP_RTOL = 1e-9
#: The 8 unit directions a vertex tries (axes, then diagonals), in this order.
_MOVE_X = np.array([1.0, -1.0, 0.0, 0.0, math.sqrt(0.5), -math.sqrt(0.5), math.sqrt(0.5), -math.sqrt(0.5)])
_MOVE_Y = np.array([0.0, 0.0, 1.0, -1.0, math.sqrt(0.5), math.sqrt(0.5), -math.sqrt(0.5), -math.sqrt(0.5)])


@numba.njit(cache=True, nogil=True)
def vertex_energy_j(cells, table, turn_table, geo, xs, ys, i, x, y):  # pragma: no cover - compiled
    """Energy terms that depend on vertex ``i`` placed at (x, y): its two segments and three turns."""
    n = xs.shape[0]
    e = walk_pair(cells, table, geo, xs[i - 1], ys[i - 1], x, y, False)[0]
    if e == math.inf:
        return e
    e += walk_pair(cells, table, geo, x, y, xs[i + 1], ys[i + 1], False)[0]
    if e == math.inf:
        return e
    if i - 2 >= 0:
        e += turn_energy(cells, turn_table, geo, xs[i - 2], ys[i - 2], xs[i - 1], ys[i - 1], x, y)
    e += turn_energy(cells, turn_table, geo, xs[i - 1], ys[i - 1], x, y, xs[i + 1], ys[i + 1])
    if i + 2 < n:
        e += turn_energy(cells, turn_table, geo, x, y, xs[i + 1], ys[i + 1], xs[i + 2], ys[i + 2])
    return e


@numba.njit(cache=True, nogil=True)
def move_vertex(cells, table, turn_table, geo, xs, ys, i, h):  # pragma: no cover - compiled
    """Move vertex ``i`` by ``h`` (m) in the best of 8 directions if that strictly lowers the
    energy terms it owns (:func:`vertex_energy_j`; a position off the map is never tried);
    returns whether it moved."""
    x0 = geo[GEO_X0]
    y0 = geo[GEO_Y0]
    xmax = x0 + geo[GEO_NCOLS] * geo[GEO_CELL]
    ymax = y0 + geo[GEO_NROWS] * geo[GEO_CELL]
    best = vertex_energy_j(cells, table, turn_table, geo, xs, ys, i, xs[i], ys[i])
    bx = xs[i]
    by = ys[i]
    for k in range(8):
        x = xs[i] + h * _MOVE_X[k]
        y = ys[i] + h * _MOVE_Y[k]
        if x < x0 or x > xmax or y < y0 or y > ymax:
            continue
        e = vertex_energy_j(cells, table, turn_table, geo, xs, ys, i, x, y)
        if e < best * (1.0 - 1e-12):
            best = e
            bx = x
            by = y
    if bx != xs[i] or by != ys[i]:
        xs[i] = bx
        ys[i] = by
        return True
    return False


@numba.njit(cache=True, nogil=True)
def drop_unpaid_vertices(cells, table, turn_table, geo, xs, ys, n, keep_rtol):  # pragma: no cover - compiled
    """Drop the interior vertices of ``xs[:n]``/``ys[:n]`` whose removal does not raise the
    energy (drive + turns, each turn a stop, a pivot and a start: :func:`~planner.kernels.walk.turn_energy`)
    by more than ``keep_rtol`` relative; compacts in place (kept vertices first) and returns
    how many are kept."""
    m = 1
    for i in range(1, n - 1):
        # candidate: previous kept vertex (m-1) -> next vertex (i+1), skipping i
        xp = xs[m - 1]
        yp = ys[m - 1]
        with_i = walk_pair(cells, table, geo, xp, yp, xs[i], ys[i], False)[0]
        with_i += walk_pair(cells, table, geo, xs[i], ys[i], xs[i + 1], ys[i + 1], False)[0]
        with_i += turn_energy(cells, turn_table, geo, xp, yp, xs[i], ys[i], xs[i + 1], ys[i + 1])
        without = walk_pair(cells, table, geo, xp, yp, xs[i + 1], ys[i + 1], False)[0]
        if m - 2 >= 0:
            with_i += turn_energy(cells, turn_table, geo, xs[m - 2], ys[m - 2], xp, yp, xs[i], ys[i])
            without += turn_energy(cells, turn_table, geo, xs[m - 2], ys[m - 2], xp, yp, xs[i + 1], ys[i + 1])
        if i + 2 < n:
            with_i += turn_energy(cells, turn_table, geo, xs[i], ys[i], xs[i + 1], ys[i + 1], xs[i + 2], ys[i + 2])
            without += turn_energy(cells, turn_table, geo, xp, yp, xs[i + 1], ys[i + 1], xs[i + 2], ys[i + 2])
        if without > with_i * (1.0 + keep_rtol):
            xs[m] = xs[i]
            ys[m] = ys[i]
            m += 1
    xs[m] = xs[n - 1]
    ys[m] = ys[n - 1]
    return m + 1


@numba.njit(cache=True, nogil=True)
def relax_polyline(cells, table, turn_table, geo, xs, ys, step0, step_min, max_sweeps):  # pragma: no cover
    """Pattern search on the interior vertices of a polyline, minimising drive + turn energy.

    Each sweep tries to move every interior vertex by ``step`` in 8 directions and keeps the
    best strict improvement; when a sweep improves nothing the step halves, until
    ``step_min``. Then vertices whose removal does not raise the energy are dropped.
    ``xs``/``ys`` are updated in place (kept vertices first); returns how many are kept.
    """
    n = xs.shape[0]
    if n < 3:
        return n
    step = step0
    sweeps = 0
    while step >= step_min and sweeps < max_sweeps:
        sweeps += 1
        improved = False
        for i in range(1, n - 1):
            if move_vertex(cells, table, turn_table, geo, xs, ys, i, step):
                improved = True
        if not improved:
            step *= 0.5
    return drop_unpaid_vertices(cells, table, turn_table, geo, xs, ys, n, KEEP_RTOL)


@numba.njit(cache=True, nogil=True)
def string_pull_indices(cells, table, geo, xs, ys):  # pragma: no cover - compiled
    """Greedy line-of-sight shortcut: indices of the kept vertices of a polyline."""
    n = xs.shape[0]
    keep = np.empty(n, np.int64)
    m = 0
    keep[m] = 0
    m += 1
    i = 0
    while i < n - 1:
        j = i + 1
        while j + 1 < n:
            ef, _ = walk_pair(cells, table, geo, xs[i], ys[i], xs[j + 1], ys[j + 1], False)
            if not math.isfinite(ef):
                break
            j += 1
        keep[m] = j
        m += 1
        i = j
    return keep[:m]
