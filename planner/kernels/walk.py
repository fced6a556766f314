"""Compiled cell walks: the energy of straight segments, free points and turns on packed arrays.

An Amanatides-Woo walk over the cells a segment crosses, summing per cell its exact length
times the energy per metre of the cell's table row at the cell's grade in the direction of
travel (linear interpolation on the uniform grade grid). A segment crossing, or touching at
a corner, a blocked cell (row ``-1``) costs ``inf``; so does one outside the map, NaN, or a
grade the ground cannot be driven at in that direction. Arguments are the arrays of a
:class:`~planner.kernels.arrays.CostArrays` (``cells``, ``grade_table``, ``turn_table``, ``geo``);
the kernels run without validation (the public queries of :class:`~planner.EnergyCost` check
their inputs) and are cheap enough to call from OMPL callbacks (about 1-2 microseconds).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from energy.profiles import COLLINEAR_TOL_RAD

from .arrays import GEO_CELL, GEO_GRADE_MIN, GEO_INV_DGRADE, GEO_NCOLS, GEO_NROWS, GEO_X0, GEO_Y0
from .variants import compile_variants, use_parallel

__all__ = [
    "walk_pair",
    "walk_forward",
    "walk_many",
    "walk_many_serial",
    "walk_many_parallel",
    "point_free",
    "turn_energy",
    "rate_per_metre",
    "CORNER_EPS",
]

#: Two parametric crossings closer than this (in segment-parameter units) are one corner crossing.
CORNER_EPS = 1e-12


@numba.njit(cache=True, nogil=True)
def _start_index(u: float, du: float, n: int) -> int:
    """Cell index along one axis where a walk from coordinate ``u`` (cell units) starts."""
    i = math.floor(u)
    if du < 0.0 and i == u:
        i -= 1  # on a grid line and moving down: the first cell entered is the lower one
    if i < 0:
        i = 0
    elif i > n - 1:
        i = n - 1
    return int(i)


@numba.njit(cache=True, nogil=True, inline="always")
def rate_per_metre(table, row: int, grade: float, gmin: float, inv_dg: float) -> float:  # pragma: no cover - compiled
    """Energy per horizontal metre (J/m) of table ``row`` at ``grade``, linearly interpolated
    on the uniform grade grid (clamped at its ends); ``inf`` if a neighbouring sample is."""
    ns = table.shape[1]
    fi = (grade - gmin) * inv_dg
    i0 = int(math.floor(fi))
    if i0 < 0:
        i0 = 0
    elif i0 > ns - 2:
        i0 = ns - 2
    w = fi - i0
    if w < 0.0:
        w = 0.0
    elif w > 1.0:
        w = 1.0
    lo = table[row, i0]
    hi = table[row, i0 + 1]
    if lo == math.inf or hi == math.inf:
        return math.inf
    return lo * (1.0 - w) + hi * w


@numba.njit(cache=True, nogil=True)
def walk_pair(cells, table, geo, xa, ya, xb, yb, both):  # pragma: no cover - compiled
    """Energy (J) of a -> b and (if ``both``) of b -> a in one cell walk; ``inf`` when blocked,
    outside the map, or at a grade the ground cannot be driven at."""
    inf = math.inf
    x0 = geo[GEO_X0]
    y0 = geo[GEO_Y0]
    d = geo[GEO_CELL]
    nr = int(geo[GEO_NROWS])
    nc = int(geo[GEO_NCOLS])
    gmin = geo[GEO_GRADE_MIN]
    inv_dg = geo[GEO_INV_DGRADE]
    ua = (xa - x0) / d
    va = (ya - y0) / d
    ub = (xb - x0) / d
    vb = (yb - y0) / d
    if not (ua >= 0.0 and ua <= nc and va >= 0.0 and va <= nr and ub >= 0.0 and ub <= nc and vb >= 0.0 and vb <= nr):
        return inf, inf  # outside the map, or NaN
    du = ub - ua
    dv = vb - va
    c = _start_index(ua, du, nc)
    r = _start_index(va, dv, nr)
    length = math.hypot(xb - xa, yb - ya)
    if length == 0.0:
        if cells[r, c, 2] < 0.0:
            return inf, inf
        return 0.0, 0.0
    ux = (xb - xa) / length
    uy = (yb - ya) / length
    if du > 0.0:
        sc = 1
        tmx = (c + 1 - ua) / du
        tdx = 1.0 / du
    elif du < 0.0:
        sc = -1
        tmx = (c - ua) / du
        tdx = -1.0 / du
    else:
        sc = 0
        tmx = inf
        tdx = inf
    if dv > 0.0:
        sr = 1
        tmy = (r + 1 - va) / dv
        tdy = 1.0 / dv
    elif dv < 0.0:
        sr = -1
        tmy = (r - va) / dv
        tdy = -1.0 / dv
    else:
        sr = 0
        tmy = inf
        tdy = inf
    t = 0.0
    e_fwd = 0.0
    e_bwd = 0.0
    while True:
        k = cells[r, c, 2]
        if k < 0.0:
            return inf, inf
        tn = min(tmx, tmy, 1.0)
        if tn > t:
            grade = cells[r, c, 0] * ux + cells[r, c, 1] * uy
            seg = (tn - t) * length
            ki = int(k)
            # forward: grade; backward: -grade (same cells, opposite direction)
            rate = rate_per_metre(table, ki, grade, gmin, inv_dg)
            if rate == inf:
                e_fwd = inf  # a grade this ground cannot be driven at (in this direction)
            else:
                e_fwd += seg * rate
            if not both and e_fwd == inf:
                return inf, inf
            if both:
                rate = rate_per_metre(table, ki, -grade, gmin, inv_dg)
                if rate == inf:
                    e_bwd = inf
                else:
                    e_bwd += seg * rate
                if e_fwd == inf and e_bwd == inf:
                    return inf, inf
            t = tn
        if tn >= 1.0:
            break
        if abs(tmx - tmy) <= CORNER_EPS:
            # Through a grid corner: both side cells touch the segment; either one blocked blocks it.
            c2 = c + sc
            r2 = r + sr
            if 0 <= c2 < nc and cells[r, c2, 2] < 0.0:
                return inf, inf
            if 0 <= r2 < nr and cells[r2, c, 2] < 0.0:
                return inf, inf
            c = c2
            r = r2
            tmx += tdx
            tmy += tdy
        elif tmx < tmy:
            c += sc
            tmx += tdx
        else:
            r += sr
            tmy += tdy
        if c < 0 or c >= nc or r < 0 or r >= nr:
            break  # rounding at the far map edge: the remaining length is ~1e-16 of the segment
    return e_fwd, e_bwd


@numba.njit(cache=True, nogil=True)
def walk_forward(cells, table, geo, xa, ya, xb, yb):  # pragma: no cover - compiled
    """Energy (J) of driving a -> b; ``inf`` when blocked or outside. One OMPL motion."""
    return walk_pair(cells, table, geo, xa, ya, xb, yb, False)[0]


def _walk_many(cells, table, geo, xa, ya, xb, yb):  # pragma: no cover - compiled
    """Forward energies of N segments (a ``prange`` loop: parallel in the parallel variant)."""
    n = xa.shape[0]
    out = np.empty(n)
    for i in numba.prange(n):
        out[i] = walk_pair(cells, table, geo, xa[i], ya[i], xb[i], yb[i], False)[0]
    return out


walk_many_serial, walk_many_parallel = compile_variants(_walk_many)


def walk_many(cells, table, geo, xa, ya, xb, yb):
    """Forward energies (J) of N segments: the serial or parallel kernel, by work size."""
    kernel = walk_many_parallel if use_parallel(xa.shape[0]) else walk_many_serial
    return kernel(cells, table, geo, xa, ya, xb, yb)


@numba.njit(cache=True, nogil=True)
def point_free(cells, geo, x, y):  # pragma: no cover - compiled
    """Whether a world point lies inside the map on a free (not blocked) cell."""
    u = (x - geo[GEO_X0]) / geo[GEO_CELL]
    v = (y - geo[GEO_Y0]) / geo[GEO_CELL]
    nr = int(geo[GEO_NROWS])
    nc = int(geo[GEO_NCOLS])
    if not (u >= 0.0 and u <= nc and v >= 0.0 and v <= nr):
        return False
    c = min(int(u), nc - 1)
    r = min(int(v), nr - 1)
    return cells[r, c, 2] >= 0.0


@numba.njit(cache=True, nogil=True)
def turn_energy(cells, turn_table, geo, xp, yp, x, y, xn, yn):  # pragma: no cover - compiled
    """Turn energy (J) at vertex (x, y) between (xp, yp) -> (x, y) and (x, y) -> (xn, yn).

    The rule of :meth:`planner.EnergyCost.turn_energy_at`: 0 at a heading change of at most
    ``COLLINEAR_TOL_RAD`` (driven through), else the turn table (stop, pivot, go) interpolated.
    """
    dx1 = x - xp
    dy1 = y - yp
    dx2 = xn - x
    dy2 = yn - y
    if (dx1 == 0.0 and dy1 == 0.0) or (dx2 == 0.0 and dy2 == 0.0):
        return 0.0
    ang = abs(math.atan2(dx1 * dy2 - dy1 * dx2, dx1 * dx2 + dy1 * dy2))
    if ang <= COLLINEAR_TOL_RAD:
        return 0.0
    nr = int(geo[GEO_NROWS])
    nc = int(geo[GEO_NCOLS])
    c = min(max(int((x - geo[GEO_X0]) / geo[GEO_CELL]), 0), nc - 1)
    r = min(max(int((y - geo[GEO_Y0]) / geo[GEO_CELL]), 0), nr - 1)
    k = cells[r, c, 2]
    if k < 0.0:
        return math.inf
    nt = turn_table.shape[1]
    f = ang / math.pi * (nt - 1)
    i0 = min(int(f), nt - 2)
    w = f - i0
    return turn_table[int(k), i0] * (1.0 - w) + turn_table[int(k), i0 + 1] * w
