"""The stride-1 lattice's move energies from per-cell direction rates: ``lattice_weights`` at stride 1, faster.

At stride 1 every node sits at a cell centre and each of the 16 moves crosses a fixed set of
cells in fixed fractions of its length: a king move half of its start cell and half of its
end cell (a diagonal through their shared corner, so both side cells must be free, as in
:func:`~planner.kernels.walk.walk_pair`), a knight move a quarter of each of four cells.
So the energy of a move is ``sum(fraction * length * rate(cell, direction))``, where the
rate (J/m) of a cell in each of the 16 directions is the cell-walk's own interpolation
(:func:`~planner.kernels.walk.rate_per_metre`) at the cell's grade in that direction.
The rates of three rows are kept at a time (a rolling buffer per block of rows), so each
is computed once instead of once per move through the cell; the walk's per-segment
set-up (grid-line crossings) is not needed.

The result has the layout of :func:`~planner.kernels.graph.lattice_weights` with
``stride=1, offset=0, half=UNIT_HALF``; it equals it to rounding (the crossing fractions
are exact here and computed from the coordinates there; ``tests/test_reachability.py``
compares both on maps with obstacles, walls, offsets and undrivable grades).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .arrays import GEO_CELL, GEO_GRADE_MIN, GEO_INV_DGRADE
from .variants import compile_variants, use_parallel
from .walk import rate_per_metre

__all__ = [
    "UNIT_HALF",
    "CROSSINGS",
    "unit_lattice_weights",
    "unit_lattice_weights_serial",
    "unit_lattice_weights_parallel",
]

#: The 8 half-plane (row, col) moves of the lattice at every stride: ``planner.lattice.LATTICE_OFFSETS[:8]``.
UNIT_HALF = np.array([(0, 1), (1, 0), (1, 1), (1, -1), (1, 2), (2, 1), (2, -1), (1, -2)], dtype=np.int64)

# Cells each half-plane move crosses from node (i, j): (row offset, col offset, fraction of its length).
_CROSSINGS = {
    0: [(0, 0, 0.5), (0, 1, 0.5)],
    1: [(0, 0, 0.5), (1, 0, 0.5)],
    2: [(0, 0, 0.5), (1, 1, 0.5)],
    3: [(0, 0, 0.5), (1, -1, 0.5)],
    4: [(0, 0, 0.25), (0, 1, 0.25), (1, 1, 0.25), (1, 2, 0.25)],
    5: [(0, 0, 0.25), (1, 0, 0.25), (1, 1, 0.25), (2, 1, 0.25)],
    6: [(0, 0, 0.25), (1, 0, 0.25), (1, -1, 0.25), (2, -1, 0.25)],
    7: [(0, 0, 0.25), (0, -1, 0.25), (1, -1, 0.25), (1, -2, 0.25)],
}
_CROSS = np.zeros((8, 4, 3))
_N_CROSS = np.zeros(8, dtype=np.int64)
for _k, _cells in _CROSSINGS.items():
    _N_CROSS[_k] = len(_cells)
    for _m, _cell in enumerate(_cells):
        _CROSS[_k, _m] = _cell
#: The crossing tables the kernels take: per half-plane move, (row offset, col offset, fraction) of each
#: crossed cell, and the number of cells crossed.
CROSSINGS = (_CROSS, _N_CROSS)
#: Column of a rate buffer row flagging a blocked cell (the 16 rates come first).
_BLOCKED = 16


@numba.njit(cache=True, nogil=True)
def _fill_row(cells, table, geo, r, nj, ux, uy, out):  # pragma: no cover - compiled
    """Rates (J/m) of every cell of row ``r`` in the 8 half-plane directions and their reverses."""
    gmin = geo[GEO_GRADE_MIN]
    inv_dg = geo[GEO_INV_DGRADE]
    for c in range(nj):
        k = cells[r, c, 2]
        if k < 0.0:
            out[c, _BLOCKED] = 1.0
            continue
        out[c, _BLOCKED] = 0.0
        ki = int(k)
        gx = cells[r, c, 0]
        gy = cells[r, c, 1]
        for m in range(8):
            g = gx * ux[m] + gy * uy[m]
            out[c, m] = rate_per_metre(table, ki, g, gmin, inv_dg)
            out[c, 8 + m] = rate_per_metre(table, ki, -g, gmin, inv_dg)


def _unit_lattice_weights(cells, table, geo, ni, nj, half, cross, n_cross, n_blocks):  # pragma: no cover
    """Directed energies ``(ni * nj, 16)`` of the stride-1 moves (``inf``: no move), by blocks of rows."""
    w = np.full((ni * nj, 16), np.inf)
    d = geo[GEO_CELL]
    ux = np.empty(8)
    uy = np.empty(8)
    length = np.empty(8)
    for m in range(8):
        h = math.hypot(half[m, 0], half[m, 1])
        ux[m] = half[m, 1] / h
        uy[m] = half[m, 0] / h
        length[m] = h * d
    for b in numba.prange(n_blocks):
        r0 = b * ni // n_blocks
        r1 = (b + 1) * ni // n_blocks
        buf = np.empty((3, nj, _BLOCKED + 1))  # row r's rates at buf[r % 3]
        for r in range(r0, min(r0 + 2, ni)):
            _fill_row(cells, table, geo, r, nj, ux, uy, buf[r % 3])
        for i in range(r0, r1):
            if i + 2 < ni:
                _fill_row(cells, table, geo, i + 2, nj, ux, uy, buf[(i + 2) % 3])
            for j in range(nj):
                src = i * nj + j
                for m in range(8):
                    ti = i + half[m, 0]
                    tj = j + half[m, 1]
                    if ti < 0 or ti >= ni or tj < 0 or tj >= nj:
                        continue
                    if (m == 2 or m == 3) and (buf[i % 3, tj, _BLOCKED] > 0.0 or buf[(i + 1) % 3, j, _BLOCKED] > 0.0):
                        continue  # a diagonal through a corner touches both side cells
                    ef = 0.0
                    eb = 0.0
                    free = True
                    for q in range(n_cross[m]):
                        rate = buf[(i + int(cross[m, q, 0])) % 3, j + int(cross[m, q, 1])]
                        if rate[_BLOCKED] > 0.0:
                            free = False
                            break
                        seg = cross[m, q, 2] * length[m]
                        ef += seg * rate[m]
                        eb += seg * rate[8 + m]
                    if free:
                        w[src, m] = ef
                        w[ti * nj + tj, 8 + m] = eb  # the reverse move is offset m + 8 from the target
    return w


unit_lattice_weights_serial, unit_lattice_weights_parallel = compile_variants(_unit_lattice_weights)


def unit_lattice_weights(cells, table, geo, ni, nj):
    """Directed energies ``(ni * nj, 16)`` of the stride-1 lattice's moves from packed cost arrays
    (the layout of ``lattice_weights(..., stride=1, offset=0, half=UNIT_HALF)``; ``inf``: no move);
    the serial or parallel kernel by work size."""
    parallel = use_parallel(ni * nj * 8)
    kernel = unit_lattice_weights_parallel if parallel else unit_lattice_weights_serial
    n_blocks = max(1, min(ni, 8 * numba.get_num_threads())) if parallel else 1
    return kernel(cells, table, geo, ni, nj, UNIT_HALF, *CROSSINGS, n_blocks)
