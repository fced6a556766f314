"""planner.registry.cells: masks, (rows, cols) pairs and regions as flat cell indices."""

from __future__ import annotations

import numpy as np
import pytest

from planner.registry import FlaggedRegion
from planner.registry.cells import check_rows_cols, flat_cells, unflat
from terrain import GridMismatchError, InvalidParameterError, OutOfBoundsError

SHAPE = (3, 4)


def test_rows_and_cols_become_int64_arrays():
    r, c = check_rows_cols(SHAPE, [0, 2], np.array([3, 1], np.int8))
    assert r.dtype == c.dtype == np.int64
    assert r.tolist() == [0, 2] and c.tolist() == [3, 1]
    r, c = check_rows_cols(SHAPE, 1, 2)  # scalars are one cell
    assert (r.tolist(), c.tolist()) == ([1], [2])


@pytest.mark.parametrize(
    ("rows", "cols", "match"),
    [
        ([[0, 1]], [0, 1], r"rows must be 1-D, got shape \(1, 2\)"),
        ([0.0, 1.0], [0, 1], "rows must hold integer cell indices, got dtype float64"),
        ([0, 1], [True, False], "cols must hold integer cell indices, got dtype bool"),
        ([0, 1], [0], "rows and cols must have the same length, got 2 and 1"),
    ],
)
def test_bad_index_arrays_are_refused(rows, cols, match):
    with pytest.raises(InvalidParameterError, match=match):
        check_rows_cols(SHAPE, rows, cols)


def test_the_first_cell_outside_the_grid_is_named():
    with pytest.raises(OutOfBoundsError, match=r"cell \(row=3, col=0\) at index 1 lies outside the grid \(3, 4\)"):
        check_rows_cols(SHAPE, [0, 3, -1], [0, 0, 0])


def test_a_mask_a_tuple_and_a_region_give_the_same_sorted_unique_flat_indices():
    mask = np.zeros(SHAPE, bool)
    mask[0, 1] = mask[2, 3] = True
    region = FlaggedRegion(1, np.array([2, 0]), np.array([3, 1]), 2, (0, 1, 2, 3), (0, 1), None, None, 0.0, 0, (0,))
    expected = [1, 11]
    assert flat_cells(SHAPE, mask).tolist() == expected
    assert flat_cells(SHAPE, (np.array([2, 0, 2]), np.array([3, 1, 3]))).tolist() == expected
    assert flat_cells(SHAPE, region).tolist() == expected


def test_bad_cell_selections_are_refused_naming_the_argument():
    with pytest.raises(InvalidParameterError, match="region as a tuple must be \\(rows, cols\\), got 3 items"):
        flat_cells(SHAPE, ([0], [0], [0]), "region")
    with pytest.raises(InvalidParameterError, match="region must be a boolean mask, .* got an array of dtype int64"):
        flat_cells(SHAPE, np.ones(SHAPE, np.int64), "region")
    with pytest.raises(GridMismatchError, match=r"region mask has shape \(4, 3\); this registry's grid is \(3, 4\)"):
        flat_cells(SHAPE, np.ones((4, 3), bool), "region")
    with pytest.raises(OutOfBoundsError, match="outside the grid"):
        flat_cells(SHAPE, ([0], [4]))


def test_unflat_inverts_flat_indices():
    rows, cols = unflat(SHAPE, np.array([0, 5, 11]))
    assert rows.dtype == cols.dtype == np.int64
    assert rows.tolist() == [0, 1, 2] and cols.tolist() == [0, 1, 3]
    r, c = check_rows_cols(SHAPE, [2, 1, 0], [1, 3, 2])
    assert [a.tolist() for a in unflat(SHAPE, flat_cells(SHAPE, (r, c)))] == [[0, 1, 2], [2, 3, 1]]
