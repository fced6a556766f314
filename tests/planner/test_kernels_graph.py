"""Tests of planner.kernels.graph: the lattice weights of the serial and parallel variants agree exactly."""

from __future__ import annotations

import numpy as np

from planner.kernels import graph as graph_kernels

from kernel_samples import kernel_cost


def test_lattice_weight_variants_agree_exactly():
    arr = kernel_cost().arrays
    half = np.array([(0, 1), (1, 0), (1, 1), (1, -1), (1, 2), (2, 1), (2, -1), (1, -2)], dtype=np.int64)
    args = (arr.cells, arr.grade_table, arr.geo, 1, 0, 30, 36, half)
    serial = graph_kernels.lattice_weights_serial(*args)
    assert np.array_equal(serial, graph_kernels.lattice_weights_parallel(*args))
    assert np.array_equal(serial, graph_kernels.lattice_weights(*args))
