"""Tests of planner.kernels.graph: the lattice weights of the serial and parallel variants agree exactly; the indexed heap."""

from __future__ import annotations

import numpy as np
from kernel_samples import kernel_cost

from planner.kernels import graph as graph_kernels


def test_lattice_weight_variants_agree_exactly():
    arr = kernel_cost().arrays
    half = np.array([(0, 1), (1, 0), (1, 1), (1, -1), (1, 2), (2, 1), (2, -1), (1, -2)], dtype=np.int64)
    args = (arr.cells, arr.grade_table, arr.geo, 1, 0, 30, 36, half)
    serial = graph_kernels.lattice_weights_serial(*args)
    assert np.array_equal(serial, graph_kernels.lattice_weights_parallel(*args))
    assert np.array_equal(serial, graph_kernels.lattice_weights(*args))


def test_the_indexed_heap_pops_in_key_order_and_lowers_keys():
    rng = np.random.default_rng(0)
    n = 50
    keys = np.empty(n)
    nodes = np.empty(n, np.int32)
    where = np.full(n, -1, np.int32)
    size = 0
    drawn = rng.uniform(0.0, 100.0, n)
    for node, key in enumerate(drawn):
        size = graph_kernels.heap_set(keys, nodes, where, size, node, key)
    size = graph_kernels.heap_set(keys, nodes, where, size, 7, -1.0)  # decrease-key: node 7 is now the minimum
    drawn[7] = -1.0
    assert size == n
    popped = []
    while size > 0:
        key, node, size = graph_kernels.heap_pop(keys, nodes, where, size)
        popped.append((key, node))
        assert where[node] == -1
    assert [node for _, node in popped] == list(np.argsort(drawn, kind="stable"))
    assert [key for key, _ in popped] == sorted(drawn)
