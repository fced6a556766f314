"""Tests of energy.metrics: charges, section errors, RMSE, moving median."""

import math

import numpy as np
import pytest

from energy import charge_mah, compare_currents
from energy.metrics import (
    CurrentErrors,
    cumulative_charge_mah,
    error_rate_pct,
    moving_median,
    rmse_a,
    section_charges_mah,
    section_error_pct,
)
from terrawatt_base.errors import DataError, InvalidParameterError


def test_charge_of_constant_current_is_current_times_time():
    t = np.linspace(0.0, 36.0, 50)
    assert charge_mah(t, np.full(50, 2.5)) == pytest.approx(2.5 * 36.0 / 3.6)


def test_charge_of_a_ramp_is_exact_with_trapezoids():
    t = np.array([0.0, 1.0, 3.0])
    i = np.array([0.0, 1.0, 3.0])  # I = t
    assert charge_mah(t, i) == pytest.approx(4.5 / 3.6)
    assert cumulative_charge_mah(t, i).tolist() == pytest.approx([0.0, 0.5 / 3.6, 4.5 / 3.6])


def test_sections_add_up_and_split_between_samples():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.05, 0.3, 200))
    i = rng.uniform(0.0, 5.0, 200)
    starts, q = section_charges_mah(t, i, 8.0)
    assert q.sum() == pytest.approx(charge_mah(t, i))
    assert np.all(np.diff(starts) == pytest.approx(8.0))
    assert starts[0] == t[0]
    assert starts[-1] < t[-1] <= starts[-1] + 8.0


@pytest.mark.parametrize("section_s", [8.0, 7.5, 2.5, 0.4])
def test_section_charges_of_a_ramp_are_exact_between_samples(section_s):
    # 0 -> 10 A over 10 s at 1 Hz: I = t, so a section [a, b) draws (b^2 - a^2) / 2 A*s
    t = np.arange(11.0)
    starts, q = section_charges_mah(t, t, section_s)
    ends = np.minimum(starts + section_s, 10.0)
    assert (q * 3.6).tolist() == pytest.approx(((ends**2 - starts**2) / 2.0).tolist(), rel=1e-12)
    assert q.sum() == pytest.approx(charge_mah(t, t), rel=1e-12)
    if section_s == 7.5:
        assert (q * 3.6).tolist() == pytest.approx([28.125, 21.875])  # not [28.25, 21.75] (cumulative interpolated)


def test_sections_of_constant_current_are_proportional_to_length():
    starts, q = section_charges_mah([0.0, 20.0], [3.6, 3.6], 8.0)
    assert starts.tolist() == [0.0, 8.0, 16.0]
    assert q.tolist() == pytest.approx([8.0, 8.0, 4.0])


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, "8"])
def test_section_length_is_validated(bad):
    with pytest.raises(InvalidParameterError, match="section_s"):
        section_charges_mah([0.0, 1.0], [1.0, 1.0], bad)


def test_series_are_validated():
    with pytest.raises(DataError, match="strictly increasing"):
        charge_mah([0.0, 1.0, 1.0], [1.0, 1.0, 1.0])
    with pytest.raises(DataError, match="at least 2"):
        charge_mah([0.0], [1.0])
    with pytest.raises(InvalidParameterError, match="shape"):
        charge_mah([0.0, 1.0], [1.0, 1.0, 1.0])
    with pytest.raises(DataError, match="finite"):
        charge_mah([0.0, 1.0], [1.0, math.nan])


def test_error_rate_matches_the_paper_definition():
    assert error_rate_pct(103.15, 100.0) == pytest.approx(3.15)
    assert error_rate_pct(96.85, 100.0) == pytest.approx(3.15)
    out = error_rate_pct([1.0, 2.0], [2.0, 0.0])
    assert out[0] == pytest.approx(50.0) and math.isnan(out[1])


def test_section_error_is_sum_of_absolute_errors_over_total_truth():
    assert section_error_pct([1.0, 3.0], [2.0, 2.0]) == pytest.approx(50.0)
    with pytest.raises(DataError, match="> 0"):
        section_error_pct([1.0], [0.0])
    with pytest.raises(InvalidParameterError, match="shape"):
        section_error_pct([1.0], [1.0, 2.0])


def test_rmse():
    assert rmse_a([1.0, 3.0], [2.0, 2.0]) == pytest.approx(1.0)
    with pytest.raises(InvalidParameterError, match="shape"):
        rmse_a([1.0], [])


def test_moving_median_removes_an_isolated_spike_and_keeps_steps():
    x = np.concatenate([np.zeros(50), np.ones(50)])
    x[20] = 100.0
    y = moving_median(x, 5)
    assert y[20] == 0.0
    assert y[10] == 0.0 and y[90] == 1.0
    two = moving_median(np.column_stack([x, 2 * x]), 5)
    assert two.shape == (100, 2) and two[20, 1] == 0.0
    with pytest.raises(InvalidParameterError, match="window_samples"):
        moving_median(x, 0)


def test_compare_currents_gives_consistent_numbers():
    t = np.linspace(0.0, 40.0, 401)
    truth = 2.0 + np.sin(t)
    pred = truth * 1.1
    e = compare_currents(t, truth, pred)
    assert isinstance(e, CurrentErrors)
    assert e.whole_run_error_pct == pytest.approx(10.0)
    assert e.section_error_pct == pytest.approx(10.0)  # every section is off by 10 %
    assert len(e.section_errors_pct) == 5
    assert all(x == pytest.approx(10.0) for x in e.section_errors_pct)
    assert e.rmse_a == pytest.approx(float(np.sqrt(np.mean((0.1 * truth) ** 2))))
    assert e.charge_predicted_mah == pytest.approx(1.1 * e.charge_true_mah)


def test_section_error_exceeds_whole_run_error_when_errors_cancel():
    t = np.linspace(0.0, 16.0, 161)
    truth = np.full(161, 2.0)
    pred = np.where(t < 8.0, 1.0, 3.0)
    e = compare_currents(t, truth, pred)
    assert e.whole_run_error_pct < 2.0
    assert e.section_error_pct > 45.0


def test_smoothing_option_filters_both_signals():
    t = np.arange(200) * 0.01
    truth = np.full(200, 1.0)
    pred = truth.copy()
    pred[100] = 50.0
    raw = compare_currents(t, truth, pred)
    smooth = compare_currents(t, truth, pred, smoothing_samples=11)
    assert raw.rmse_a > 1.0 and smooth.rmse_a == 0.0
