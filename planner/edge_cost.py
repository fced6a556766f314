"""Energy of straight segments across a terrain map: per-cell tables and compiled cell walks.

An :class:`EnergyCost` is built once per (map, energy model, grounds, speed) — the *map
preparation* step — and then answers, for any straight segment, the battery energy (J) of
driving it at the planning speed:

``E(a -> b) = sum over crossed cells i of  l_i * f_{g(i)}(s_i)``,  ``s_i = grad_x_i u_x + grad_y_i u_y``

where ``l_i`` is the exact length of the segment inside cell ``i`` (grid-line crossings, an
Amanatides–Woo walk), ``u`` the unit direction of motion, ``grad_x, grad_y`` the map's
per-cell elevation gradients (so the grade ``s_i`` is signed: uphill ``!=`` downhill) and
``f_g(s)`` the energy per horizontal metre (J/m) on ground ``g`` at grade ``s``, tabulated once
per ground on a uniform grade grid over ``[-tan(max_slope), +tan(max_slope)]`` and linearly
interpolated. A segment that crosses (or touches at a corner between two cells: the robot
is not a point) a *blocked* cell — an obstacle, or a cell steeper than ``max_slope_rad`` —
costs ``inf``; so does a segment meeting, in its direction of travel, a grade its ground
cannot be driven at (a model's ``inf`` energy), which blocks that direction only. Obstacles
are not inflated by the robot's size: inflate them in the map if needed.

Turning at a waypoint costs the model's ``turn_energy_j`` for the heading change, tabulated
per ground over ``[0, pi]``; the ground is the one of the cell holding the waypoint.

The walk is compiled with numba: one segment per call for OMPL's per-motion callbacks
(about 1-2 microseconds a call from Python, no numpy inside), a parallel loop for many
segments (bulk queries), a both-directions-in-one-walk variant for lattice graphs, and a
pattern-search polisher of whole routes (:meth:`EnergyCost.relax_path`). Kernels are compiled
with ``cache=True``; :func:`warm_up_kernels` compiles or loads them and reports the time,
which is *not* part of map preparation.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from numbers import Integral, Real
from typing import Any

import numba
import numpy as np

from terrain import TerrainMap
from terrain.errors import InvalidParameterError, OutOfBoundsError, UnknownNameError
from terrain.terrain_map import UNKNOWN_GROUND

__all__ = [
    "EnergyCost",
    "DEFAULT_MAX_SLOPE_RAD",
    "DEFAULT_GRADE_SAMPLES",
    "DEFAULT_TURN_SAMPLES",
    "warm_up_kernels",
]

#: Default steepest slope a route may cross (20 degrees).
DEFAULT_MAX_SLOPE_RAD = math.radians(20.0)
#: Default number of samples of each ground's energy-per-metre-vs-grade table (odd: grade 0 is a sample).
DEFAULT_GRADE_SAMPLES = 513
#: Default number of samples of each ground's turn-energy-vs-angle table over [0, pi].
DEFAULT_TURN_SAMPLES = 65

# Layout of the float64 "geometry" vector handed to the kernels.
_G_X0, _G_Y0, _G_D, _G_NROWS, _G_NCOLS, _G_GMIN, _G_INV_DG = range(7)
# Two parametric crossings closer than this (in segment-parameter units) are one corner crossing.
_CORNER_EPS = 1e-12
# Relative energy change treated as rounding noise (drops collinear vertices; accepts polishing).
_KEEP_RTOL = 1e-9


# --------------------------------------------------------------------------- numba kernels
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
def _rate_per_metre(table, row: int, grade: float, gmin: float, inv_dg: float) -> float:  # pragma: no cover - compiled
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
def _walk(cells, table, geo, xa, ya, xb, yb, both):  # pragma: no cover - compiled
    """Energy (J) of a -> b and (if ``both``) of b -> a in one cell walk; ``inf`` when blocked,
    outside the map, or at a grade the ground cannot be driven at."""
    inf = math.inf
    x0 = geo[_G_X0]
    y0 = geo[_G_Y0]
    d = geo[_G_D]
    nr = int(geo[_G_NROWS])
    nc = int(geo[_G_NCOLS])
    gmin = geo[_G_GMIN]
    inv_dg = geo[_G_INV_DG]
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
            rate = _rate_per_metre(table, ki, grade, gmin, inv_dg)
            if rate == inf:
                e_fwd = inf  # a grade this ground cannot be driven at (in this direction)
            else:
                e_fwd += seg * rate
            if not both and e_fwd == inf:
                return inf, inf
            if both:
                rate = _rate_per_metre(table, ki, -grade, gmin, inv_dg)
                if rate == inf:
                    e_bwd = inf
                else:
                    e_bwd += seg * rate
                if e_fwd == inf and e_bwd == inf:
                    return inf, inf
            t = tn
        if tn >= 1.0:
            break
        if abs(tmx - tmy) <= _CORNER_EPS:
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
def _walk_forward(cells, table, geo, xa, ya, xb, yb):  # pragma: no cover - compiled
    """Energy (J) of driving a -> b; ``inf`` when blocked or outside. One OMPL motion."""
    return _walk(cells, table, geo, xa, ya, xb, yb, False)[0]


@numba.njit(cache=True, nogil=True, parallel=True)
def _walk_many(cells, table, geo, xa, ya, xb, yb):  # pragma: no cover - compiled
    """Forward energies of N segments (parallel over segments)."""
    n = xa.shape[0]
    out = np.empty(n)
    for i in numba.prange(n):
        out[i] = _walk(cells, table, geo, xa[i], ya[i], xb[i], yb[i], False)[0]
    return out


@numba.njit(cache=True, nogil=True)
def _point_free(cells, geo, x, y):  # pragma: no cover - compiled
    """Whether a world point lies inside the map on a free (not blocked) cell."""
    u = (x - geo[_G_X0]) / geo[_G_D]
    v = (y - geo[_G_Y0]) / geo[_G_D]
    nr = int(geo[_G_NROWS])
    nc = int(geo[_G_NCOLS])
    if not (u >= 0.0 and u <= nc and v >= 0.0 and v <= nr):
        return False
    c = min(int(u), nc - 1)
    r = min(int(v), nr - 1)
    return cells[r, c, 2] >= 0.0


@numba.njit(cache=True, nogil=True)
def _turn_j(cells, turn_table, geo, xp, yp, x, y, xn, yn):  # pragma: no cover - compiled
    """Turn energy (J) at vertex (x, y) between (xp, yp) -> (x, y) and (x, y) -> (xn, yn)."""
    dx1 = x - xp
    dy1 = y - yp
    dx2 = xn - x
    dy2 = yn - y
    if (dx1 == 0.0 and dy1 == 0.0) or (dx2 == 0.0 and dy2 == 0.0):
        return 0.0
    ang = abs(math.atan2(dx1 * dy2 - dy1 * dx2, dx1 * dx2 + dy1 * dy2))
    if ang == 0.0:
        return 0.0
    nr = int(geo[_G_NROWS])
    nc = int(geo[_G_NCOLS])
    c = min(max(int((x - geo[_G_X0]) / geo[_G_D]), 0), nc - 1)
    r = min(max(int((y - geo[_G_Y0]) / geo[_G_D]), 0), nr - 1)
    k = cells[r, c, 2]
    if k < 0.0:
        return math.inf
    nt = turn_table.shape[1]
    f = ang / math.pi * (nt - 1)
    i0 = min(int(f), nt - 2)
    w = f - i0
    return turn_table[int(k), i0] * (1.0 - w) + turn_table[int(k), i0 + 1] * w


@numba.njit(cache=True, nogil=True)
def _local_j(cells, table, turn_table, geo, xs, ys, i, x, y):  # pragma: no cover - compiled
    """Energy terms that depend on vertex i placed at (x, y): its two segments and three turns."""
    n = xs.shape[0]
    e = _walk(cells, table, geo, xs[i - 1], ys[i - 1], x, y, False)[0]
    e += _walk(cells, table, geo, x, y, xs[i + 1], ys[i + 1], False)[0]
    if e == math.inf:
        return e
    if i - 2 >= 0:
        e += _turn_j(cells, turn_table, geo, xs[i - 2], ys[i - 2], xs[i - 1], ys[i - 1], x, y)
    e += _turn_j(cells, turn_table, geo, xs[i - 1], ys[i - 1], x, y, xs[i + 1], ys[i + 1])
    if i + 2 < n:
        e += _turn_j(cells, turn_table, geo, x, y, xs[i + 1], ys[i + 1], xs[i + 2], ys[i + 2])
    return e


@numba.njit(cache=True, nogil=True)
def _relax(cells, table, turn_table, geo, xs, ys, step0, step_min, max_sweeps):  # pragma: no cover
    """Pattern search on the interior vertices of a polyline, minimising drive + turn energy.

    Each sweep tries to move every interior vertex by ``step`` in 8 directions and keeps the
    best strict improvement; when a sweep improves nothing the step halves, until
    ``step_min``. Then vertices whose removal does not raise the energy are dropped.
    ``xs``/``ys`` are updated in place (kept vertices first); returns how many are kept.
    """
    n = xs.shape[0]
    if n < 3:
        return n
    s2 = math.sqrt(0.5)
    dx = np.array([1.0, -1.0, 0.0, 0.0, s2, -s2, s2, -s2])
    dy = np.array([0.0, 0.0, 1.0, -1.0, s2, s2, -s2, -s2])
    xmax = geo[_G_X0] + geo[_G_NCOLS] * geo[_G_D]
    ymax = geo[_G_Y0] + geo[_G_NROWS] * geo[_G_D]
    step = step0
    sweeps = 0
    while step >= step_min and sweeps < max_sweeps:
        sweeps += 1
        improved = False
        for i in range(1, n - 1):
            best = _local_j(cells, table, turn_table, geo, xs, ys, i, xs[i], ys[i])
            bx = xs[i]
            by = ys[i]
            for k in range(8):
                x = xs[i] + step * dx[k]
                y = ys[i] + step * dy[k]
                if x < geo[_G_X0] or x > xmax or y < geo[_G_Y0] or y > ymax:
                    continue
                e = _local_j(cells, table, turn_table, geo, xs, ys, i, x, y)
                if e < best * (1.0 - 1e-12):
                    best = e
                    bx = x
                    by = y
            if bx != xs[i] or by != ys[i]:
                xs[i] = bx
                ys[i] = by
                improved = True
        if not improved:
            step *= 0.5
    # Drop vertices that do not pay for themselves (compact the arrays as we go).
    m = 1
    for i in range(1, n - 1):
        # candidate: previous kept vertex (m-1) -> next vertex (i+1), skipping i
        xp = xs[m - 1]
        yp = ys[m - 1]
        with_i = _walk(cells, table, geo, xp, yp, xs[i], ys[i], False)[0]
        with_i += _walk(cells, table, geo, xs[i], ys[i], xs[i + 1], ys[i + 1], False)[0]
        with_i += _turn_j(cells, turn_table, geo, xp, yp, xs[i], ys[i], xs[i + 1], ys[i + 1])
        without = _walk(cells, table, geo, xp, yp, xs[i + 1], ys[i + 1], False)[0]
        if m - 2 >= 0:
            with_i += _turn_j(cells, turn_table, geo, xs[m - 2], ys[m - 2], xp, yp, xs[i], ys[i])
            without += _turn_j(cells, turn_table, geo, xs[m - 2], ys[m - 2], xp, yp, xs[i + 1], ys[i + 1])
        if i + 2 < n:
            with_i += _turn_j(cells, turn_table, geo, xs[i], ys[i], xs[i + 1], ys[i + 1], xs[i + 2], ys[i + 2])
            without += _turn_j(cells, turn_table, geo, xp, yp, xs[i + 1], ys[i + 1], xs[i + 2], ys[i + 2])
        if without > with_i * (1.0 + _KEEP_RTOL):
            xs[m] = xs[i]
            ys[m] = ys[i]
            m += 1
    xs[m] = xs[n - 1]
    ys[m] = ys[n - 1]
    return m + 1


def warm_up_kernels() -> float:
    """Compile (or load from numba's on-disk cache) every compiled kernel of the planner.

    Runs each kernel once on a tiny map with the same argument types as real use, so that
    neither map preparation nor planning times include compilation.

    Returns
    -------
    float
        Seconds spent; the first call in a fresh environment compiles (tens of seconds on a
        slow machine), later processes load the cached machine code (well under a second).
    """
    from .lattice import Lattice, string_pull  # lattice imports this module

    t0 = time.perf_counter()
    tmap = TerrainMap(np.zeros((4, 4)), 1.0)
    cost = EnergyCost(
        tmap, np.zeros((4, 4), np.int32), np.ones((1, 3)), np.ones((1, 2)),
        speed_mps=1.0, battery_voltage_v=1.0, turn_rate_radps=1.0,
    )
    cost.segment_energy_j([[0.5, 0.5]], [[3.5, 2.5]])
    cost.segment_energy_one_j(0.5, 0.5, 3.5, 2.5)
    cost.relax_path([[0.5, 0.5], [2.0, 3.0], [3.5, 0.5]])
    _point_free(cost._cells, cost._geo, 0.5, 0.5)
    path = Lattice.for_cost(cost, 1).shortest_path((0.5, 0.5), (3.5, 3.5), weight="length")
    cost.with_tables(2.0 * cost.grade_table_j_per_m, cost.turn_table_j)  # incremental lattice reweighting
    string_pull(cost, np.vstack([path.waypoints_m, [[0.5, 3.5]]]))
    return time.perf_counter() - t0


# --------------------------------------------------------------------------- EnergyCost
def _as_points(xy: Any, name: str) -> np.ndarray:
    arr = np.asarray(xy, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == 2:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidParameterError(f"{name} must have shape (N, 2) (x_m, y_m), got shape {arr.shape!r}")
    if not np.all(np.isfinite(arr)):
        bad = arr[~np.all(np.isfinite(arr), axis=1)][0]
        raise InvalidParameterError(f"{name} must be finite coordinates in metres, got {tuple(bad.tolist())!r}")
    return arr


def _model_turn_rate_radps(model: Any) -> float | None:
    for owner in (model, getattr(model, "robot", None)):
        value = getattr(owner, "turn_rate_radps", None)
        if value is not None:
            return float(value)
    return None


def _check_tables(
    shape: tuple[int, int], ground_rows: Any, grade_table_j_per_m: Any, turn_table_j: Any, ground_labels: Any
) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], np.ndarray]:
    """Validated copies of EnergyCost tables and per-cell rows (see :class:`EnergyCost`)."""
    grade_table = np.array(grade_table_j_per_m, dtype=np.float64, order="C", copy=True)
    turn_table = np.array(turn_table_j, dtype=np.float64, order="C", copy=True)
    if grade_table.ndim != 2 or grade_table.shape[1] < 3 or grade_table.shape[1] % 2 == 0:
        raise InvalidParameterError(
            f"grade_table_j_per_m must have shape (n_grounds, n_grade) with odd n_grade >= 3, "
            f"got {grade_table.shape!r}"
        )
    n_rows = grade_table.shape[0]
    if turn_table.ndim != 2 or turn_table.shape[0] != n_rows or turn_table.shape[1] < 2:
        raise InvalidParameterError(
            f"turn_table_j must have shape ({n_rows}, n_turn >= 2), got {turn_table.shape!r}"
        )
    labels = tuple(ground_labels) if ground_labels is not None else tuple(f"row{i}" for i in range(n_rows))
    if len(labels) != n_rows:
        raise InvalidParameterError(f"ground_labels needs {n_rows} names, got {labels!r}")
    for tname, tab, allowed in (
        ("grade_table_j_per_m", grade_table, "energies >= 0 or +inf (a grade the ground cannot be driven at)"),
        ("turn_table_j", turn_table, "finite energies >= 0"),
    ):
        bad = np.isnan(tab) | (tab < 0)
        if tname == "turn_table_j":
            bad |= ~np.isfinite(tab)
        if np.any(bad):
            i, j = np.argwhere(bad)[0]
            raise InvalidParameterError(
                f"{tname} must hold {allowed} (minimum-energy planning needs non-negative edge "
                f"costs; a regenerating model must not go below 0), got {tab[i, j]!r} for "
                f"ground {labels[i]!r} at sample {j}"
            )
    rows = np.asarray(ground_rows)
    if rows.shape != tuple(shape):
        from terrain.errors import GridMismatchError

        raise GridMismatchError(f"ground_rows has shape {rows.shape!r}; the map's grid is {tuple(shape)!r}")
    if not np.issubdtype(rows.dtype, np.integer) or rows.min() < 0 or rows.max() >= n_rows:
        raise InvalidParameterError(
            f"ground_rows must hold integer table rows in 0..{n_rows - 1}, got values in "
            f"[{rows.min()!r}, {rows.max()!r}] of dtype {rows.dtype}"
        )
    return grade_table, turn_table, labels, rows


class EnergyCost:
    """Precomputed per-cell tables for the energy (J) of straight segments and turns on a map.

    Build it with :meth:`from_model`; the constructor takes ready tables (for custom cost
    models and tests) and validates them.

    Parameters
    ----------
    terrain : TerrainMap
        The map; its ``grad_x``, ``grad_y``, ``slope`` and ``obstacle`` layers are used.
    ground_rows : ndarray of int, shape (rows, cols)
        Row of ``grade_table_j_per_m`` / ``turn_table_j`` that serves each cell.
    grade_table_j_per_m : ndarray, shape (n_grounds, n_grade)
        Energy per horizontal metre (J/m, >= 0; ``+inf`` = this grade cannot be driven on
        this ground) at uniformly spaced grades from ``-tan(max_slope_rad)`` to
        ``+tan(max_slope_rad)``; ``n_grade`` odd and >= 3.
    turn_table_j : ndarray, shape (n_grounds, n_turn)
        Energy (J, >= 0, finite) of turning in place by angles uniformly spaced over ``[0, pi]``.
    speed_mps : float
        Planning speed (m/s), used for durations.
    max_slope_rad : float
        Cells steeper than this are blocked; in ``(0, pi/2)``.
    battery_voltage_v : float
        Battery voltage (V) for charge in mAh.
    turn_rate_radps : float
        Rate of turning in place (rad/s), used for durations.
    ground_labels : tuple of str, optional
        A label per table row (ground names), for messages.

    Attributes
    ----------
    blocked : ndarray of bool
        Obstacle or slope above ``max_slope_rad``.
    min_energy_per_metre_j : float
        Lowest energy per metre over every free cell and every grade that cell can present to
        a straight motion (``|grade| <= tan(slope)``); ``lower_bound_j`` is this times distance.
    prep_time_s : float
        Seconds spent building the tables (set by :meth:`from_model`; numba compilation excluded).

    Raises
    ------
    InvalidParameterError
        Tables of the wrong shape, negative or non-finite energies, bad speed / slope / voltage.
    GridMismatchError
        ``ground_rows`` not on the map's grid.
    """

    def __init__(
        self,
        terrain: TerrainMap,
        ground_rows: np.ndarray,
        grade_table_j_per_m: np.ndarray,
        turn_table_j: np.ndarray,
        *,
        speed_mps: float,
        max_slope_rad: float = DEFAULT_MAX_SLOPE_RAD,
        battery_voltage_v: float,
        turn_rate_radps: float,
        ground_labels: tuple[str, ...] | None = None,
    ) -> None:
        t0 = time.perf_counter()
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        for name, value, hi in (
            ("speed_mps", speed_mps, math.inf),
            ("battery_voltage_v", battery_voltage_v, math.inf),
            ("turn_rate_radps", turn_rate_radps, math.inf),
            ("max_slope_rad", max_slope_rad, math.pi / 2),
        ):
            v = float(value)
            if not (math.isfinite(v) and 0.0 < v < hi):
                raise InvalidParameterError(f"{name} must be a finite number in (0, {hi!r}), got {value!r}")
        grade_table, turn_table, labels, rows = _check_tables(
            terrain.shape, ground_rows, grade_table_j_per_m, turn_table_j, ground_labels
        )

        self.terrain = terrain
        self.speed_mps = float(speed_mps)
        self.max_slope_rad = float(max_slope_rad)
        self.battery_voltage_v = float(battery_voltage_v)
        self.turn_rate_radps = float(turn_rate_radps)
        self.ground_labels = labels
        self.grade_max = math.tan(self.max_slope_rad)
        self.grade_table_j_per_m = grade_table
        self.turn_table_j = turn_table
        self.ground_rows = rows.astype(np.int32)
        self.blocked = np.asarray(terrain.obstacle) | (np.asarray(terrain["slope"]) > self.max_slope_rad)
        n_grade = grade_table.shape[1]
        dg = 2.0 * self.grade_max / (n_grade - 1)
        # Packed per-cell data for the kernels: grad_x, grad_y, table row (-1 = blocked).
        cells = np.empty(terrain.shape + (3,), dtype=np.float64)
        cells[..., 0] = terrain["grad_x"]
        cells[..., 1] = terrain["grad_y"]
        cells[..., 2] = np.where(self.blocked, -1.0, self.ground_rows)
        self._cells = cells
        x0, y0 = terrain.origin_xy_m
        rows_n, cols_n = terrain.shape
        self._geo = np.array([x0, y0, terrain.cell_size_m, rows_n, cols_n, -self.grade_max, 1.0 / dg])
        for arr in (grade_table, turn_table, self.ground_rows, self.blocked, self._cells, self._geo):
            arr.setflags(write=False)
        self._free_grade_index: np.ndarray | None = None  # geometry only: shared by with_tables
        self.min_energy_per_metre_j = self._min_energy_per_metre(dg)
        self._components: np.ndarray | None = None
        self._cache: dict[Any, Any] = {}  # lattice graphs etc., keyed by their builders
        #: Cells whose table row content differs from the cost this one was derived from
        #: (:meth:`with_tables`); ``None`` for a cost built from scratch.
        self.changed_cells: np.ndarray | None = None
        self.prep_time_s = time.perf_counter() - t0

    def with_tables(
        self,
        grade_table_j_per_m: np.ndarray,
        turn_table_j: np.ndarray,
        ground_rows: np.ndarray | None = None,
        *,
        ground_labels: tuple[str, ...] | None = None,
    ) -> EnergyCost:
        """The same map geometry with new energy tables (a table-only refresh, e.g. after a model update).

        Equal in every query to ``EnergyCost(self.terrain, ground_rows, grade_table_j_per_m,
        turn_table_j, ...)`` with this cost's speed, slope limit, voltage and turn rate, but
        the per-cell geometry (gradients, blocked cells, connected regions) is shared, and
        every lattice graph cached on this cost is carried over by recomputing only the
        weights of edges that cross a cell whose table row *content* changed
        (:meth:`Lattice.refreshed`), instead of being rebuilt. Cells whose row index changed
        but whose row content did not (rows renumbered) count as unchanged.

        Parameters
        ----------
        grade_table_j_per_m, turn_table_j : ndarray
            New tables, as in the constructor; ``grade_table_j_per_m`` must have this cost's
            number of grade samples (the grade grid is part of the geometry).
        ground_rows : ndarray of int, optional
            New per-cell rows (default: the current ones).
        ground_labels : tuple of str, optional
            Labels of the new rows.

        Returns
        -------
        EnergyCost
            A new cost; its :attr:`changed_cells` marks the cells whose energy changed and its
            ``prep_time_s`` is the refresh time (lattice updates included). ``self`` is not
            modified.

        Raises
        ------
        InvalidParameterError
            Tables invalid as in the constructor, or another number of grade samples.
        GridMismatchError
            ``ground_rows`` not on the map's grid.
        """
        t0 = time.perf_counter()
        rows_in = self.ground_rows if ground_rows is None else ground_rows
        grade_table, turn_table, labels, rows = _check_tables(
            self.terrain.shape, rows_in, grade_table_j_per_m, turn_table_j, ground_labels
        )
        if grade_table.shape[1] != self.grade_table_j_per_m.shape[1]:
            raise InvalidParameterError(
                f"grade_table_j_per_m has {grade_table.shape[1]} grade samples; this cost's grade grid has "
                f"{self.grade_table_j_per_m.shape[1]} (build a new EnergyCost to change it)"
            )
        new = object.__new__(EnergyCost)
        for name in ("terrain", "speed_mps", "max_slope_rad", "battery_voltage_v", "turn_rate_radps", "grade_max",
                     "blocked", "_geo", "_free_grade_index", "_components"):
            setattr(new, name, getattr(self, name))
        new.ground_labels = labels
        new.grade_table_j_per_m = grade_table
        new.turn_table_j = turn_table
        new.ground_rows = rows.astype(np.int32)
        cells = self._cells.copy()
        cells[..., 2] = np.where(self.blocked, -1.0, new.ground_rows)
        new._cells = cells
        for arr in (grade_table, turn_table, new.ground_rows, cells):
            arr.setflags(write=False)
        dg = 2.0 * self.grade_max / (grade_table.shape[1] - 1)
        new.min_energy_per_metre_j = new._min_energy_per_metre(dg)
        new.changed_cells = self._changed_cells(new)
        new.changed_cells.setflags(write=False)
        new._cache = {}
        for key, value in self._cache.items():
            if isinstance(key, tuple) and key and key[0] == "lattice":
                new._cache[key] = value.refreshed(new, new.changed_cells)
        new.prep_time_s = time.perf_counter() - t0
        return new

    def _changed_cells(self, other: EnergyCost) -> np.ndarray:
        """Free cells whose grade-table row content differs between ``self`` and ``other``."""
        n_new = other.grade_table_j_per_m.shape[0]
        code = self.ground_rows.astype(np.int64) * n_new + other.ground_rows
        present = np.flatnonzero(np.bincount(code.ravel(), minlength=self.grade_table_j_per_m.shape[0] * n_new))
        differs = np.zeros(self.grade_table_j_per_m.shape[0] * n_new, dtype=bool)
        for pair in present.tolist():
            a, b = divmod(pair, n_new)
            differs[pair] = not np.array_equal(self.grade_table_j_per_m[a], other.grade_table_j_per_m[b])
        return differs[code] & ~self.blocked

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_model(
        cls,
        terrain: TerrainMap,
        model: Any,
        grounds: Mapping[str, Any] | Mapping[int, Any],
        speed_mps: float,
        *,
        unknown_ground: Any = None,
        max_slope_rad: float = DEFAULT_MAX_SLOPE_RAD,
        battery_voltage_v: float | None = None,
        turn_rate_radps: float | None = None,
        grade_samples: int = DEFAULT_GRADE_SAMPLES,
        turn_samples: int = DEFAULT_TURN_SAMPLES,
    ) -> EnergyCost:
        """Tabulate an energy model over a map's grounds (the map-preparation step).

        ``model.energy_per_metre_j(speed_mps, grades, ground)`` is called once per ground
        with all ``grade_samples`` grades, and ``model.turn_energy_j(angles, ground)`` once
        per ground with ``turn_samples`` angles over ``[0, pi]`` (turns are priced on level
        ground: a pivot's extra load on a slope is not in the table). The model's energy is per
        metre *travelled*; the table stores it per *horizontal* (map) metre, i.e. times
        ``sqrt(1 + grade**2)``. A model may return ``+inf`` for grades a ground cannot be
        driven at; segments meeting such a grade in their direction of travel are then
        invalid in that direction only.

        Parameters
        ----------
        terrain : TerrainMap
            The map.
        model : energy model
            Anything with ``energy_per_metre_j`` and ``turn_energy_j`` as in
            :class:`energy.PhysicsEnergyModel` (and, optionally, a ``robot`` with
            ``battery_voltage_v`` and ``turn_rate_radps``).
        grounds : mapping
            Ground parameters per ground class of the map, keyed by class name (see
            ``terrain.ground_names``) or by class id. Every class present in the map's
            ``ground`` layer needs an entry; extra entries are ignored.
        speed_mps : float
            Planning speed (m/s, > 0).
        unknown_ground : ground params, optional
            Parameters for cells of unknown ground (class ``-1``). Required when the map has
            such cells.
        max_slope_rad : float
            Cells steeper than this are impassable (default 20 degrees).
        battery_voltage_v, turn_rate_radps : float, optional
            Default to ``model.robot.battery_voltage_v`` and ``model.robot.turn_rate_radps``
            (or ``model.turn_rate_radps``).
        grade_samples, turn_samples : int
            Table sizes (``grade_samples`` odd, >= 3; ``turn_samples`` >= 2).

        Returns
        -------
        EnergyCost

        Raises
        ------
        UnknownNameError
            A ground class of the map has no parameters in ``grounds``.
        InvalidParameterError
            Unknown-ground cells without ``unknown_ground``; a model returning negative,
            non-finite or wrongly shaped energies; missing voltage / turn rate; bad sizes.

        Examples
        --------
        >>> import numpy as np
        >>> from terrain import TerrainMap
        >>> from energy import PhysicsEnergyModel, robot_preset, ground_preset
        >>> tmap = TerrainMap(np.zeros((8, 8)), 1.0, ground=np.zeros((8, 8), int), ground_names={0: "asphalt"})
        >>> cost = EnergyCost.from_model(tmap, PhysicsEnergyModel(robot_preset("husky")),
        ...                              {"asphalt": ground_preset("asphalt")}, speed_mps=0.5)
        >>> bool(cost.segment_energy_j([[0.5, 0.5]], [[6.5, 0.5]])[0] > 0)
        True
        """
        t0 = time.perf_counter()
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        speed = float(speed_mps)
        if not (math.isfinite(speed) and speed > 0):
            raise InvalidParameterError(f"speed_mps must be a finite number > 0, got {speed_mps!r}")
        slope = float(max_slope_rad)
        if not (math.isfinite(slope) and 0 < slope < math.pi / 2):
            raise InvalidParameterError(f"max_slope_rad must be in (0, pi/2), got {max_slope_rad!r}")
        if int(grade_samples) != grade_samples or grade_samples < 3 or grade_samples % 2 == 0:
            raise InvalidParameterError(f"grade_samples must be an odd integer >= 3, got {grade_samples!r}")
        if int(turn_samples) != turn_samples or turn_samples < 2:
            raise InvalidParameterError(f"turn_samples must be an integer >= 2, got {turn_samples!r}")
        robot = getattr(model, "robot", None)
        if battery_voltage_v is None:
            battery_voltage_v = getattr(robot, "battery_voltage_v", None)
            if battery_voltage_v is None:
                raise InvalidParameterError(
                    "battery_voltage_v is None and the model has no robot.battery_voltage_v; pass it"
                )
        if turn_rate_radps is None:
            turn_rate_radps = _model_turn_rate_radps(model)
            if turn_rate_radps is None:
                raise InvalidParameterError(
                    "turn_rate_radps is None and the model has no turn_rate_radps (nor robot.turn_rate_radps); pass it"
                )

        # Map the map's ground classes onto table rows.
        names = terrain.ground_names
        by_id: dict[int, Any] = {}
        for key, params in dict(grounds).items():
            if isinstance(key, str):
                for gid, gname in names.items():
                    if gname == key:
                        by_id[gid] = params
            elif isinstance(key, (int, np.integer)) and not isinstance(key, bool):
                by_id[int(key)] = params
            else:
                raise InvalidParameterError(f"grounds keys must be ground names or class ids, got {key!r}")
        ground = np.asarray(terrain.ground)
        present = [int(v) for v in np.unique(ground)]
        params_rows: list[Any] = []
        labels: list[str] = []
        lut = np.full(int(max(present + [0])) + 2, -1, dtype=np.int32)  # lut[gid + 1] -> row
        for gid in present:
            if gid == UNKNOWN_GROUND:
                if unknown_ground is None:
                    n_unknown = int(np.count_nonzero(ground == UNKNOWN_GROUND))
                    raise InvalidParameterError(
                        f"the map has {n_unknown} cells of unknown ground ({UNKNOWN_GROUND}) and "
                        "unknown_ground is None; pass unknown_ground=<ground params> for them"
                    )
                params = unknown_ground
                label = "unknown"
            else:
                if gid not in by_id:
                    label = names.get(gid, str(gid))
                    raise UnknownNameError(
                        f"ground class {label!r} (id {gid}) of the map has no parameters in grounds; "
                        f"grounds has {sorted(map(str, dict(grounds)))!r}"
                    )
                params = by_id[gid]
                label = names.get(gid, str(gid))
            lut[gid + 1] = len(params_rows)
            params_rows.append(params)
            labels.append(label)
        rows = lut[ground.astype(np.int64) + 1]

        grade_max = math.tan(slope)
        grades = np.linspace(-grade_max, grade_max, int(grade_samples))
        angles = np.linspace(0.0, math.pi, int(turn_samples))
        grade_table = np.empty((len(params_rows), grades.size))
        turn_table = np.empty((len(params_rows), angles.size))
        for i, params in enumerate(params_rows):
            e = np.asarray(model.energy_per_metre_j(speed, grades, params), dtype=np.float64)
            te = np.asarray(model.turn_energy_j(angles, params), dtype=np.float64)
            if e.shape != grades.shape or te.shape != angles.shape:
                raise InvalidParameterError(
                    f"model returned shapes {e.shape!r} / {te.shape!r} for {grades.shape!r} grades / "
                    f"{angles.shape!r} angles on ground {labels[i]!r}; expected the input shapes"
                )
            # The model's J per metre travelled (along the surface) -> J per horizontal map metre.
            grade_table[i] = e * np.sqrt(1.0 + grades**2)
            turn_table[i] = te
        cost = cls(
            terrain,
            rows,
            grade_table,
            turn_table,
            speed_mps=speed,
            max_slope_rad=slope,
            battery_voltage_v=float(battery_voltage_v),
            turn_rate_radps=float(turn_rate_radps),
            ground_labels=tuple(labels),
        )
        cost.prep_time_s = time.perf_counter() - t0
        return cost

    def _min_energy_per_metre(self, dg: float) -> float:
        """Lowest J/m any straight motion through a free cell can cost (admissible per-metre bound)."""
        free = ~self.blocked
        if not np.any(free):
            return 0.0
        table = self.grade_table_j_per_m
        n = table.shape[1]
        m = (n - 1) // 2  # index of grade 0
        # prefix[row, k] = min of table[row, m-k .. m+k]: lowest J/m at |grade| <= k*dg.
        left = np.minimum.accumulate(table[:, m::-1], axis=1)
        right = np.minimum.accumulate(table[:, m:], axis=1)
        prefix = np.minimum(left, right)
        if self._free_grade_index is None:
            grad = np.hypot(self.terrain["grad_x"], self.terrain["grad_y"])[free]
            self._free_grade_index = np.minimum(np.ceil(grad / dg * (1 + 1e-9)).astype(np.int64), m)
        value = float(np.min(prefix[self.ground_rows[free], self._free_grade_index]))
        return value if math.isfinite(value) else 0.0

    # ------------------------------------------------------------------ queries
    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape of the map."""
        return self.terrain.shape

    def _check_inside(self, pts: np.ndarray, name: str) -> None:
        inside = np.asarray(self.terrain.contains(pts[:, 0], pts[:, 1]))
        if not np.all(inside):
            bad = pts[~inside][0]
            raise OutOfBoundsError(
                f"{name} point {tuple(bad.tolist())!r} m lies outside the map bounds {self.terrain.bounds!r}"
            )

    def segment_energy_j(self, starts_xy_m: Any, ends_xy_m: Any) -> np.ndarray:
        """Energy (J) of driving each straight segment ``starts[i] -> ends[i]`` at the planning speed.

        Exact cell-by-cell integration; ``inf`` for a segment that crosses a blocked cell.

        Parameters
        ----------
        starts_xy_m, ends_xy_m : array_like, shape (N, 2) or (2,)
            Segment ends (m).

        Returns
        -------
        ndarray, shape (N,)

        Raises
        ------
        InvalidParameterError
            Wrong shapes or NaN/inf coordinates.
        OutOfBoundsError
            A point outside the map.
        """
        a = _as_points(starts_xy_m, "starts_xy_m")
        b = _as_points(ends_xy_m, "ends_xy_m")
        if a.shape != b.shape:
            raise InvalidParameterError(f"starts_xy_m {a.shape!r} and ends_xy_m {b.shape!r} must have equal shapes")
        self._check_inside(a, "starts_xy_m")
        self._check_inside(b, "ends_xy_m")
        return _walk_many(
            self._cells,
            self.grade_table_j_per_m,
            self._geo,
            np.array(a[:, 0]),  # fresh writable copies: one compiled signature for all callers
            np.array(a[:, 1]),
            np.array(b[:, 0]),
            np.array(b[:, 1]),
        )

    def segment_energy_one_j(self, xa: float, ya: float, xb: float, yb: float) -> float:
        """Energy (J) of one segment from scalars, without validation (compiled; for callbacks).

        Points outside the map, NaN, or a blocked crossing give ``inf``.
        """
        return _walk_forward(self._cells, self.grade_table_j_per_m, self._geo, xa, ya, xb, yb)

    def is_free(self, xy_m: Any) -> np.ndarray:
        """Whether points lie on free cells (inside the map, no obstacle, not too steep).

        Raises
        ------
        InvalidParameterError
            Wrong shape or NaN coordinates.
        OutOfBoundsError
            A point outside the map.
        """
        pts = _as_points(xy_m, "xy_m")
        self._check_inside(pts, "xy_m")
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        return ~self.blocked[r, c]

    def turn_energies_j(self, waypoints_m: Any) -> tuple[np.ndarray, np.ndarray]:
        """Heading change (rad, in [0, pi]) and turn energy (J) at every waypoint of a polyline.

        The first and last waypoints have no turn. Zero-length segments (repeated points)
        have no heading: the turn is taken between the neighbouring non-degenerate segments,
        at the waypoint where the new heading starts.

        Returns
        -------
        angles_rad, energies_j : ndarray, shape (K,)
        """
        pts = _as_points(waypoints_m, "waypoints_m")
        self._check_inside(pts, "waypoints_m")
        k = pts.shape[0]
        angles = np.zeros(k)
        if k < 3:
            return angles, np.zeros(k)
        seg = np.diff(pts, axis=0)
        nonzero = np.flatnonzero(np.hypot(seg[:, 0], seg[:, 1]) > 0)
        if nonzero.size >= 2:
            heading = np.arctan2(seg[nonzero, 1], seg[nonzero, 0])
            turn = np.abs((np.diff(heading) + math.pi) % (2 * math.pi) - math.pi)
            angles[nonzero[1:]] = turn  # waypoint index where segment nonzero[j] starts
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        rows = self.ground_rows[r, c]
        n_turn = self.turn_table_j.shape[1]
        f = angles / math.pi * (n_turn - 1)
        i0 = np.minimum(np.floor(f).astype(np.int64), n_turn - 2)
        w = f - i0
        energies = self.turn_table_j[rows, i0] * (1 - w) + self.turn_table_j[rows, i0 + 1] * w
        energies[angles == 0] = 0.0
        return angles, energies

    def path_energy_j(self, waypoints_m: Any) -> float:
        """Total energy (J) of a polyline: every segment plus the turns at its waypoints.

        ``inf`` when a segment crosses a blocked cell.

        Raises
        ------
        InvalidParameterError
            Fewer than 1 waypoint, wrong shape or NaN.
        OutOfBoundsError
            A waypoint outside the map.
        """
        pts = _as_points(waypoints_m, "waypoints_m")
        if pts.shape[0] < 2:
            return 0.0
        seg = self.segment_energy_j(pts[:-1], pts[1:])
        _, turns = self.turn_energies_j(pts)
        return float(seg.sum() + turns.sum())

    def surface_length_m(self, waypoints_m: Any) -> float:
        """Length (m) of a polyline along the terrain surface: per cell, horizontal length
        times ``sqrt(1 + grade**2)`` with the cell's grade in the direction of travel.

        Raises
        ------
        InvalidParameterError, OutOfBoundsError
            Bad shape / NaN, or a waypoint outside the map.
        """
        pts = _as_points(waypoints_m, "waypoints_m")
        self._check_inside(pts, "waypoints_m")
        gx, gy = self.terrain["grad_x"], self.terrain["grad_y"]
        total = 0.0
        for a, b in zip(pts[:-1], pts[1:]):
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            if length == 0.0:
                continue
            rows, cols, pieces = self.terrain.segment_cells(tuple(a), tuple(b))
            grade = (gx[rows, cols] * (b[0] - a[0]) + gy[rows, cols] * (b[1] - a[1])) / length
            total += float(np.sum(pieces * np.sqrt(1.0 + grade**2)))
        return total

    def relax_path(
        self,
        waypoints_m: Any,
        *,
        spacing_m: float | None = None,
        levels: int = 3,
        min_gain: float = 1e-3,
        step_m: float | None = None,
        max_sweeps: int = 300,
    ) -> np.ndarray:
        """Locally optimise a valid polyline's true energy (drive + turns), ends fixed.

        Coarse to fine, over ``levels`` passes: each pass cuts the segments into pieces of
        at most its spacing (``spacing_m``, default 8 cells, halved at every further pass:
        8, 4, 2 cells by default), so the route can bend where the ground changes; a
        compiled pattern search then moves each interior vertex in 8 directions while the
        energy drops, starting with a step of ``min(step_m, spacing / 4)`` (``step_m``
        default one cell) and halving it down to 1 % of a cell; finally vertices whose
        removal does not raise the energy are dropped. Every accepted move keeps the route
        valid (an invalid move costs inf). Coarse passes move long stretches at little cost;
        fine ones let the route follow ground and slope boundaries. A finer pass runs only
        while the previous one lowered the energy by at least ``min_gain`` (relative): on
        512 x 512 procedural maps the first pass does most of the work and the finer ones
        add 0.05–0.6 %, at two to four times its cost.

        Returns
        -------
        ndarray, shape (K', 2)
            A route whose :meth:`path_energy_j` is at most the input's (up to a relative
            1e-9 of rounding, which lets exactly collinear vertices go).

        Raises
        ------
        InvalidParameterError
            Bad shape or NaN, a route that crosses a blocked cell, bad settings.
        OutOfBoundsError
            A waypoint outside the map.
        """
        pts = _as_points(waypoints_m, "waypoints_m")
        before = self.path_energy_j(pts)
        if not math.isfinite(before):
            raise InvalidParameterError("waypoints_m crosses a blocked cell; relax_path needs a valid route")
        d = self.terrain.cell_size_m
        spacing = 8.0 * d if spacing_m is None else float(spacing_m)
        step = d if step_m is None else float(step_m)
        for name, v in (("spacing_m", spacing), ("step_m", step)):
            if not (math.isfinite(v) and v > 0):
                raise InvalidParameterError(f"{name} must be a finite number > 0, got {v!r}")
        for name, v in (("levels", levels), ("max_sweeps", max_sweeps)):
            if isinstance(v, bool) or not isinstance(v, Integral) or v < 1:
                raise InvalidParameterError(f"{name} must be an integer >= 1, got {v!r}")
        if pts.shape[0] < 2:
            return pts.copy()
        if not (isinstance(min_gain, Real) and math.isfinite(min_gain) and min_gain >= 0):
            raise InvalidParameterError(f"min_gain must be a finite number >= 0, got {min_gain!r}")
        out = pts
        energy = before
        for level in range(int(levels)):
            gap = spacing / 2**level
            seg = np.diff(out, axis=0)
            pieces = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / gap).astype(np.int64))
            frac = np.concatenate([np.arange(k) / k for k in pieces])
            base = np.repeat(np.arange(out.shape[0] - 1), pieces)
            dense = np.vstack([out[base] + frac[:, None] * seg[base], out[-1:]])
            xs = np.ascontiguousarray(dense[:, 0])
            ys = np.ascontiguousarray(dense[:, 1])
            m = _relax(
                self._cells, self.grade_table_j_per_m, self.turn_table_j, self._geo, xs, ys,
                min(step, gap / 4.0), 0.01 * d, int(max_sweeps),
            )
            out = np.column_stack([xs[:m], ys[:m]])
            previous, energy = energy, self.path_energy_j(out)
            if energy > previous * (1.0 - min_gain):
                break
        return out if self.path_energy_j(out) <= before * (1.0 + _KEEP_RTOL) else pts.copy()

    def lower_bound_j(self, a_xy_m: Any, b_xy_m: Any) -> np.ndarray:
        """Admissible lower bound (J) on the drive energy of any route from ``a`` to ``b``.

        ``min_energy_per_metre_j * |b - a|``: every route of length ``L >= |b - a|`` only
        crosses free cells, and on each of them a straight piece costs at least the lowest
        energy per metre at any grade that cell can present (``|grade| <= tan(slope)``).
        It never overestimates (the elevation change is deliberately not used: with
        per-cell gradients the integrated grade along a route is not exactly
        ``z(b) - z(a)``, so a grade term could overestimate).

        Returns
        -------
        ndarray, shape (N,)
        """
        a = _as_points(a_xy_m, "a_xy_m")
        b = _as_points(b_xy_m, "b_xy_m")
        return self.min_energy_per_metre_j * np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])

    def components(self) -> np.ndarray:
        """Label of the 4-connected region of free cells holding each cell (``0`` = blocked).

        Two points are joined by some valid polyline exactly when their cells share a label
        (a valid segment crosses a chain of edge-adjacent free cells, and a corner crossing
        needs both side cells free).
        """
        if self._components is None:
            from scipy import ndimage

            labels, _ = ndimage.label(~self.blocked)
            self._components = labels
        return self._components

    def __repr__(self) -> str:
        return (
            f"EnergyCost(shape={self.shape}, speed_mps={self.speed_mps}, max_slope_rad={self.max_slope_rad:.4f}, "
            f"grounds={list(self.ground_labels)}, blocked_cells={int(self.blocked.sum())})"
        )
