"""energy.logs.gaps: the gap rule of sampled streams."""

from __future__ import annotations

import numpy as np
import pytest

from energy.logs.gaps import DEFAULT_GAP_FACTOR, check_gap_factor, gap_steps, median_period_s, merged_gaps
from terrain import InvalidParameterError


def test_the_default_gap_factor_is_five_periods():
    assert DEFAULT_GAP_FACTOR == 5.0 and check_gap_factor(DEFAULT_GAP_FACTOR) == 5.0


def test_check_gap_factor_gives_a_float():
    value = check_gap_factor(2)
    assert value == 2.0 and isinstance(value, float)


@pytest.mark.parametrize(
    ("bad", "match"),
    [(1.0, r"gap_factor must be > 1, got 1\.0"), (0.5, "gap_factor must be > 1"),
     (float("nan"), "gap_factor must be finite"), ("5", "gap_factor must be a real number")],
)
def test_check_gap_factor_refuses(bad, match):
    with pytest.raises(InvalidParameterError, match=match):
        check_gap_factor(bad)


def test_median_period_ignores_one_long_step():
    assert median_period_s(np.array([0.0, 0.1, 0.2, 5.0, 5.1])) == pytest.approx(0.1)
    assert median_period_s(np.array([1.0, 3.0])) == 2.0


def test_gap_steps_are_the_steps_above_the_factor_times_the_median():
    t = np.array([0.0, 0.1, 0.2, 0.7, 0.8, 0.851, 0.9])  # steps 0.1 0.1 0.5 0.1 0.051 0.049: median 0.1
    assert gap_steps(t, 5.0).tolist() == []  # 0.5 is not more than 5 x 0.1
    assert gap_steps(t, 4.0).tolist() == [2]
    assert gap_steps(np.arange(10.0), 1.5).tolist() == []
    assert gap_steps(np.array([0.0, 100.0]), 1.5).dtype == np.intp


def test_streams_of_fewer_than_three_samples_have_no_gap():
    assert gap_steps(np.array([0.0, 50.0]), 2.0).size == 0
    assert gap_steps(np.array([1.0]), 2.0).size == 0


def test_gaps_of_several_streams_are_merged_where_they_overlap():
    drive = np.r_[np.arange(0.0, 1.05, 0.1), np.arange(3.0, 4.05, 0.1)]  # gap 1.0 -> 3.0
    imu = np.r_[np.arange(0.0, 1.505, 0.01), np.arange(2.5, 4.005, 0.01)]  # gap 1.5 -> 2.5, inside it
    other = np.r_[np.arange(0.0, 2.85, 0.1), np.arange(3.5, 4.05, 0.1)]  # gap 2.8 -> 3.5: overlaps the first
    gaps = merged_gaps((drive, imu, other), 5.0)
    assert len(gaps) == 1
    assert gaps[0] == pytest.approx((1.0, 3.5))
    assert merged_gaps((np.arange(0.0, 1.0, 0.1),), 5.0) == []


def test_separate_gaps_stay_separate_and_in_time_order():
    late = np.r_[np.arange(0.0, 5.05, 0.1), np.arange(8.0, 9.05, 0.1)]
    early = np.r_[np.arange(0.0, 1.05, 0.1), np.arange(2.0, 9.05, 0.1)]
    gaps = merged_gaps((late, early), 5.0)
    assert gaps == [pytest.approx((1.0, 2.0)), pytest.approx((5.0, 8.0))]
