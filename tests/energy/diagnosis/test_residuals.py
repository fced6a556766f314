"""Tests of energy.diagnosis.residuals: residuals, per-sample gaps and the whole-set gap summary."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, charge_mah
from energy.metrics import section_charges_mah, section_error_pct
from energy.diagnosis.residuals import (
    GapSummary,
    checked_pairs,
    gap_summary,
    residual_currents_a,
    sample_gap_mah,
    sample_weights_s,
)
from terrawatt_base.errors import DataError, InvalidParameterError


def make_log(time_s, left_a, right_a, v_mps=None, omega_radps=None) -> InteractionLog:
    t = np.asarray(time_s, dtype=float)
    n = t.size
    v = np.full(n, 0.5) if v_mps is None else v_mps
    w = np.zeros(n) if omega_radps is None else omega_radps
    return InteractionLog(t, v, w, left_a, right_a, t, np.full(n, 9.81), meta=LogMeta(ground_label="asphalt"))


@pytest.fixture
def uneven_log() -> InteractionLog:
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.005, 0.02, 400))
    return make_log(t, 2.0 + rng.normal(0, 0.3, 400), 1.5 + rng.normal(0, 0.3, 400))


def test_residual_is_measured_minus_predicted_and_leaves_inputs_alone(uneven_log):
    pred = np.column_stack([np.full(400, 1.0), np.full(400, 2.0)])
    before = pred.copy()
    res = residual_currents_a(uneven_log, pred)
    assert res.shape == (400, 2)
    np.testing.assert_allclose(res[:, 0], uneven_log.current_left_a - 1.0)
    np.testing.assert_allclose(res[:, 1], uneven_log.current_right_a - 2.0)
    np.testing.assert_array_equal(pred, before)
    res[:] = 0.0  # a new array, not a view of the log
    assert uneven_log.current_left_a[0] != 0.0


def test_sample_weights_integrate_like_charge_mah(uneven_log):
    w = sample_weights_s(uneven_log.time_s)
    assert math.isclose(w.sum(), uneven_log.duration_s, rel_tol=1e-12)
    q = float(np.sum(w * uneven_log.current_left_a)) / 3.6
    assert math.isclose(q, charge_mah(uneven_log.time_s, uneven_log.current_left_a), rel_tol=1e-12)


def test_sample_gaps_add_up_to_the_integrated_gap(uneven_log):
    rng = np.random.default_rng(4)
    pred = rng.uniform(0.0, 3.0, (400, 2))
    g = sample_gap_mah(uneven_log, pred)
    t = uneven_log.time_s
    expected = (charge_mah(t, uneven_log.current_left_a) - charge_mah(t, pred[:, 0])
                + charge_mah(t, uneven_log.current_right_a) - charge_mah(t, pred[:, 1]))
    assert math.isclose(g.sum(), expected, rel_tol=1e-10)


def test_gap_summary_of_a_one_amp_offset_on_one_side():
    t = np.arange(37) * 100.0  # one hour
    log = make_log(t, np.full(37, 3.0), np.full(37, 2.0))
    pred = np.column_stack([np.full(37, 2.0), np.full(37, 2.0)])  # left misses 1 A
    s = gap_summary([log], [pred])
    assert isinstance(s, GapSummary)
    assert s.measured_mah == pytest.approx(5000.0)
    assert s.predicted_mah == pytest.approx(4000.0)
    assert s.gap_mah == pytest.approx(1000.0)
    assert s.charge_error_pct == pytest.approx(20.0)
    assert s.rmse_a == pytest.approx(math.sqrt(0.5))
    assert s.section_error_pct == pytest.approx(20.0)
    assert (s.n_runs, s.n_samples, s.duration_s) == (1, 37, pytest.approx(3600.0))
    d = s.to_dict()
    assert set(d) == {"measured_mah", "predicted_mah", "gap_mah", "charge_error_pct", "section_error_pct",
                      "rmse_a", "n_runs", "n_samples", "duration_s"}
    json.dumps(d)
    assert "1000 mAh" in str(s)


def test_gap_summary_section_error_is_the_median_over_runs(uneven_log):
    rng = np.random.default_rng(5)
    logs = [uneven_log, make_log(np.arange(300) * 0.05, np.full(300, 2.0), np.full(300, 1.0))]
    preds = [rng.uniform(1.0, 2.5, (len(log), 2)) for log in logs]
    s = gap_summary(logs, preds, section_s=1.0)
    per_run = []
    for log, p in zip(logs, preds):
        truth = np.concatenate([section_charges_mah(log.time_s, c, 1.0)[1]
                                for c in (log.current_left_a, log.current_right_a)])
        model = np.concatenate([section_charges_mah(log.time_s, p[:, k], 1.0)[1] for k in (0, 1)])
        per_run.append(section_error_pct(model, truth))
    assert s.section_error_pct == pytest.approx(float(np.median(per_run)))
    assert s.n_runs == 2 and s.n_samples == 700
    assert s.gap_mah == pytest.approx(s.measured_mah - s.predicted_mah)


def test_a_single_log_with_a_single_prediction_is_accepted(uneven_log):
    logs, preds = checked_pairs(uneven_log, np.ones((400, 2)))
    assert logs == (uneven_log,) and preds[0].shape == (400, 2)


def test_bad_input_is_named():
    log = make_log(np.arange(10) * 0.1, np.ones(10), np.ones(10))
    good = np.ones((10, 2))
    with pytest.raises(DataError, match="logs is empty"):
        gap_summary([], [])
    with pytest.raises(InvalidParameterError, match="one array per log: 2 log"):
        gap_summary([log, log], [good])
    with pytest.raises(InvalidParameterError, match=r"predictions\[0\] must have shape \(10, 2\)"):
        gap_summary([log], [np.ones((9, 2))])
    with pytest.raises(InvalidParameterError, match=r"predicted_a must have shape \(10, 2\)"):
        residual_currents_a(log, np.ones(10))
    bad = good.copy()
    bad[3, 1] = np.nan
    with pytest.raises(DataError, match=r"predictions\[0\] must be finite; 1 NaN/inf value\(s\), first in row 3"):
        gap_summary([log], [bad])
    with pytest.raises(InvalidParameterError, match=r"logs\[1\] must be an InteractionLog"):
        gap_summary([log, "run.csv"], [good, good])
    with pytest.raises(InvalidParameterError, match="logs must be an InteractionLog or a sequence"):
        gap_summary(42, [good])
    with pytest.raises(InvalidParameterError, match="predictions must be a sequence"):
        gap_summary([log], good)
    with pytest.raises(InvalidParameterError, match="section_s must be > 0"):
        gap_summary([log], [good], section_s=0.0)
    one = make_log([0.0], [1.0], [1.0])
    with pytest.raises(DataError, match="at least 2 samples"):
        gap_summary([one], [np.ones((1, 2))])
    silent = make_log(np.arange(10) * 0.1, np.zeros(10), np.zeros(10))
    with pytest.raises(DataError, match="the logs carry no drive current"):
        gap_summary([silent], [good])
    with pytest.raises(DataError, match="at least 2 finite samples"):
        sample_weights_s([1.0])
    with pytest.raises(DataError, match="strictly increasing"):
        sample_weights_s([0.0, 1.0, 1.0])
