"""Tests of planner.kernels.reach: grid_dijkstra against a pure-numpy all-pairs reference on a tiny grid."""

from __future__ import annotations

import numpy as np
import pytest

from planner.kernels.reach import grid_dijkstra

NI, NJ = 3, 4
DI = np.array([0, 1, 0, -1, 1], dtype=np.int64)  # east, south, west, north, south-east
DJ = np.array([1, 0, -1, 0, 1], dtype=np.int64)


def _weights(seed: int) -> np.ndarray:
    """Random move energies (some moves absent), ``inf`` for moves off the grid."""
    rng = np.random.default_rng(seed)
    w = rng.uniform(1.0, 10.0, (NI * NJ, DI.size))
    w[rng.random(w.shape) < 0.2] = np.inf
    for u in range(NI * NJ):
        i, j = divmod(u, NJ)
        for k in range(DI.size):
            if not (0 <= i + DI[k] < NI and 0 <= j + DJ[k] < NJ):
                w[u, k] = np.inf
    return w


def _all_pairs(w: np.ndarray) -> np.ndarray:
    """Floyd-Warshall on the dense matrix of the moves: ``d[u, v]`` least energy from u to v."""
    n = NI * NJ
    d = np.full((n, n), np.inf)
    np.fill_diagonal(d, 0.0)
    for u in range(n):
        for k in range(DI.size):
            if np.isfinite(w[u, k]):
                v = u + DI[k] * NJ + DJ[k]
                d[u, v] = min(d[u, v], w[u, k])
    for m in range(n):
        d = np.minimum(d, d[:, m:m + 1] + d[m:m + 1, :])
    return d


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_forward_and_reversed_searches_equal_the_all_pairs_reference(seed):
    w = _weights(seed)
    d = _all_pairs(w)
    src = np.array([0, 5], dtype=np.int64)
    src_cost = np.array([0.0, 2.5])
    forward = grid_dijkstra(w, NI, NJ, DI, DJ, src, src_cost, False)
    backward = grid_dijkstra(w, NI, NJ, DI, DJ, src, src_cost, True)
    np.testing.assert_allclose(forward, np.min(src_cost[:, None] + d[src, :], axis=0), rtol=1e-12)
    np.testing.assert_allclose(backward, np.min(d[:, src] + src_cost[None, :], axis=1), rtol=1e-12)


def test_nodes_without_a_route_are_inf():
    w = np.full((NI * NJ, DI.size), np.inf)
    w[0, 0] = 4.0  # the only move: node 0 east to node 1
    dist = grid_dijkstra(w, NI, NJ, DI, DJ, np.array([0], dtype=np.int64), np.array([1.0]), False)
    assert dist[0] == 1.0 and dist[1] == 5.0 and np.isinf(dist[2:]).all()
