"""Tests of planner.tables: the grade and turn grids and their size checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.tables import DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES, check_table_sizes, grade_grid, turn_grid
from terrawatt_base.errors import InvalidParameterError


def test_grade_grid_is_symmetric_with_zero_in_the_middle():
    g = grade_grid(math.atan(0.5), 5)
    np.testing.assert_allclose(g, [-0.5, -0.25, 0.0, 0.25, 0.5])


def test_turn_grid_spans_zero_to_pi():
    np.testing.assert_allclose(turn_grid(3), [0.0, math.pi / 2, math.pi])


def test_table_sizes_are_checked():
    assert check_table_sizes(3, 2) == (3, 2)
    assert check_table_sizes(DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES) == (DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES)
    with pytest.raises(InvalidParameterError, match="grade_samples must be an odd integer >= 3, got 4"):
        check_table_sizes(4, 2)
    with pytest.raises(InvalidParameterError, match="grade_samples"):
        check_table_sizes(1, 2)
    with pytest.raises(InvalidParameterError, match="turn_samples"):
        check_table_sizes(3, 1)
