"""Tests of planner.kernels.incremental: the reverse move table and in-place move updates against numpy references
(the D* Lite search itself is tested through planner.replan in test_replan.py)."""

from __future__ import annotations

import numpy as np

from planner.kernels.incremental import reverse_weights, set_moves

NJ = 4
DELTA = np.array([1, NJ, NJ + 1, -1], dtype=np.int64)  # east, south, south-east, west on a 3 x 4 node grid


def _forward(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    fw = rng.uniform(1.0, 5.0, (12, DELTA.size))
    fw[rng.random(fw.shape) < 0.3] = np.inf
    return fw


def _reverse_reference(fw: np.ndarray) -> np.ndarray:
    n = fw.shape[0]
    rw = np.full_like(fw, np.inf)
    for k, d in enumerate(DELTA):
        v = np.arange(n)
        ok = (v - d >= 0) & (v - d < n)
        rw[v[ok], k] = fw[v[ok] - d, k]
    return rw


def test_the_reverse_table_is_the_forward_one_seen_from_each_move_s_end():
    fw = _forward(0)
    np.testing.assert_array_equal(reverse_weights(fw, DELTA), _reverse_reference(fw))


def test_set_moves_writes_both_tables_and_returns_each_head_once():
    fw = _forward(1)
    rw = reverse_weights(fw, DELTA)
    nd = DELTA.size
    moves = np.array([1 * nd + 0, 1 * nd + 2, 5 * nd + 1, 6 * nd + 3], dtype=np.int64)  # ascending ids
    energies = np.array([7.0, np.inf, 2.5, 9.0])
    heads = set_moves(moves, energies, fw, rw, DELTA)
    assert heads.tolist() == [1, 5, 6]
    assert fw[1, 0] == 7.0 and np.isinf(fw[1, 2]) and fw[5, 1] == 2.5 and fw[6, 3] == 9.0
    np.testing.assert_array_equal(rw, _reverse_reference(fw))  # the reverse table follows
