"""Tests of planner.kernels.paths: line-of-sight pulls and vertex relaxation on small maps with known answers."""

from __future__ import annotations

import numpy as np
from edge_cost_samples import LinearModel, flat_terrain

from planner import CostSpec, EnergyCost
from planner.kernels.paths import drop_unpaid_vertices, string_pull_indices


def _cost(obstacle=None) -> EnergyCost:
    return CostSpec(energy_model=LinearModel(a=50.0, c=30.0), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain(obstacle=obstacle))


def test_on_open_ground_the_pull_keeps_only_the_ends():
    arr = _cost().arrays
    xs = np.array([1.5, 5.5, 9.5, 14.5, 20.5])
    ys = np.array([1.5, 6.5, 2.5, 8.5, 3.5])
    assert list(string_pull_indices(arr.cells, arr.grade_table, arr.geo, xs, ys)) == [0, 4]


def test_a_wall_keeps_the_vertex_that_goes_around_it():
    obstacle = np.zeros((20, 30), bool)
    obstacle[0:15, 15] = True
    arr = _cost(obstacle).arrays
    xs = np.array([5.5, 10.5, 15.5, 20.5, 25.5])
    ys = np.array([5.5, 17.5, 17.5, 17.5, 5.5])
    kept = list(string_pull_indices(arr.cells, arr.grade_table, arr.geo, xs, ys))
    assert kept[0] == 0 and kept[-1] == 4 and len(kept) > 2


def test_collinear_vertices_are_dropped_and_a_corner_the_walls_need_is_kept():
    obstacle = np.zeros((20, 30), bool)
    obstacle[3:10, 3:13] = True  # blocks the diagonal short cut of the corner
    arr = _cost(obstacle).arrays
    xs = np.array([1.5, 5.5, 9.5, 13.5, 13.5])
    ys = np.array([2.5, 2.5, 2.5, 2.5, 10.5])
    n = drop_unpaid_vertices(arr.cells, arr.grade_table, arr.turn_table, arr.geo, xs, ys, 5, 1e-9)
    assert n == 3  # the start, the corner and the end, compacted to the front
    np.testing.assert_array_equal(np.column_stack([xs[:3], ys[:3]]), [[1.5, 2.5], [13.5, 2.5], [13.5, 10.5]])


def test_on_open_ground_even_the_corner_is_not_worth_its_detour():
    arr = _cost().arrays
    xs = np.array([1.5, 5.5, 13.5, 13.5])
    ys = np.array([2.5, 2.5, 2.5, 10.5])
    assert drop_unpaid_vertices(arr.cells, arr.grade_table, arr.turn_table, arr.geo, xs, ys, 4, 1e-9) == 2
