"""Tests of planner.kernels.corridor: the corridor lattice is the 1-cell lattice restricted to the corridor's cells."""

from __future__ import annotations

import numpy as np
from kernel_samples import kernel_cost

from planner.kernels import UNIT_HALF, lattice_weights
from planner.kernels.corridor import corridor_weights, corridor_weights_parallel, corridor_weights_serial


def _corridor(mask: np.ndarray):
    rows, cols = np.nonzero(mask)
    index = np.full(mask.shape, -1, dtype=np.int64)
    index[rows, cols] = np.arange(rows.size)
    return rows.astype(np.int64), cols.astype(np.int64), index


def test_a_corridor_of_every_cell_is_the_whole_lattice():
    arr = kernel_cost().arrays
    nr, nc = arr.cells.shape[:2]
    rows, cols, index = _corridor(np.ones((nr, nc), bool))
    got = corridor_weights(arr.cells, arr.grade_table, arr.geo, rows, cols, index, UNIT_HALF)
    ref = lattice_weights(arr.cells, arr.grade_table, arr.geo, 1, 0, nr, nc, UNIT_HALF)
    assert np.array_equal(got, ref)


def test_a_band_keeps_the_moves_inside_it_and_drops_the_others():
    arr = kernel_cost().arrays
    nr, nc = arr.cells.shape[:2]
    mask = np.zeros((nr, nc), bool)
    mask[10:16, :] = True
    rows, cols, index = _corridor(mask)
    args = (arr.cells, arr.grade_table, arr.geo, rows, cols, index, UNIT_HALF)
    got = corridor_weights_serial(*args)
    assert np.array_equal(got, corridor_weights_parallel(*args))
    ref = lattice_weights(arr.cells, arr.grade_table, arr.geo, 1, 0, nr, nc, UNIT_HALF)
    full_nodes = rows * nc + cols
    offsets = np.vstack([UNIT_HALF, -UNIT_HALF])
    for k, (di, dj) in enumerate(offsets):
        tr, tc = rows + di, cols + dj
        inside = (tr >= 0) & (tr < nr) & (tc >= 0) & (tc < nc)
        inside[inside] = mask[tr[inside], tc[inside]]
        np.testing.assert_array_equal(got[inside, k], ref[full_nodes[inside], k])
        assert np.isinf(got[~inside, k]).all()
