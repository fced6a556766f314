"""Tests of energy.diagnosis.gap: residuals, per-sample gaps and the whole-set gap summary; where the gap lies
(split by time, regime, side and space, ranked)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, TruthSimulator, charge_mah, robot_preset
from energy.diagnosis.gap import (
    DIMENSIONS,
    GapShare,
    GapSummary,
    WaterfallStep,
    checked_pairs,
    gap_summary,
    largest_slices,
    localise_gap,
    residual_currents_a,
    sample_gap_mah,
    sample_weights_s,
    shares_of,
    time_labels,
)
from energy.diagnosis.quantity import CURRENT, POWER
from energy.metrics import section_charges_mah, section_error_pct
from energy.sim import PAPER_GROUNDS
from terrain import flat_map, ramp_map
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError


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
    assert isinstance(s, GapSummary) and s.quantity is CURRENT
    assert s.measured == pytest.approx(5000.0)
    assert s.predicted == pytest.approx(4000.0)
    assert s.gap == pytest.approx(1000.0)
    assert s.error_pct == pytest.approx(20.0)
    assert s.rmse == pytest.approx(math.sqrt(0.5))
    assert s.section_error_pct == pytest.approx(20.0)
    assert (s.n_runs, s.n_samples, s.duration_s) == (1, 37, pytest.approx(3600.0))
    d = s.to_dict()
    assert list(d) == ["measured_mah", "predicted_mah", "gap_mah", "charge_error_pct", "section_error_pct",
                       "rmse_a", "n_runs", "n_samples", "duration_s"]  # diagnosis.json's keys, in its order
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
    assert s.gap == pytest.approx(s.measured - s.predicted)


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


# ---------------------------------------------------------------- where the gap lies
def motion_log(v_mps, omega_radps, left_a, right_a, *, dt_s=0.1, pose_xyh=None, ground=None, ground_label=None):
    v = np.asarray(v_mps, dtype=float)
    n = v.size
    t = np.arange(n) * dt_s
    return InteractionLog(t, v, omega_radps, left_a, right_a, t, np.full(n, 9.81), pose_xyh=pose_xyh,
                          ground=ground, meta=LogMeta(ground_label=ground_label))


def stop_turn_go(n_each=100):
    """Straight, pivot, arc, standstill blocks of ``n_each`` samples at 10 Hz."""
    v = np.concatenate([np.full(n_each, 0.8), np.zeros(n_each), np.full(n_each, 0.5), np.zeros(n_each)])
    w = np.concatenate([np.zeros(n_each), np.full(n_each, 0.6), np.full(n_each, 0.5), np.zeros(n_each)])
    return v, w


def measured(v, w):
    base = 1.0 + 2.0 * np.abs(v) + 4.0 * np.abs(w)
    return base, base + 0.2


def test_a_model_that_misses_only_while_pivoting_puts_all_the_gap_in_pivot():
    v, w = stop_turn_go()
    left, right = measured(v, w)
    log = motion_log(v, w, left, right)
    pred = np.column_stack([left, right])
    pivot = (np.abs(v) < 0.05) & (np.abs(w) > 0.1)
    pred[pivot] -= 2.0  # the model lacks turning resistance in pivots only
    before = pred.copy()
    rows = localise_gap([log], [pred])
    turning = shares_of(rows, "turning")
    assert turning[0].label == "pivot"
    assert turning[0].share_pct == pytest.approx(100.0)
    assert sum(r.share_pct for r in turning) == pytest.approx(100.0)
    assert turning[0].gap_mah == pytest.approx(gap_summary([log], [pred]).gap)
    assert turning[0].n_samples == 100 and turning[0].duration_s == pytest.approx(10.0)
    np.testing.assert_array_equal(pred, before)


def test_a_model_wrong_on_one_ground_localises_to_that_ground():
    v, w = stop_turn_go(50)
    left, right = measured(v, w)
    n = v.size
    per_sample = np.where(np.arange(n) < n // 2, "tiles", "snow")
    logs = [
        motion_log(v, w, left, right, ground_label="asphalt"),
        motion_log(v, w, left * 1.3, right * 1.3, ground_label="grass"),  # the model is 30 % low on grass
        motion_log(v, w, np.where(per_sample == "snow", left + 1.0, left), right, ground=per_sample),
    ]
    preds = [np.column_stack([left, right])] * 3
    ground = shares_of(localise_gap(logs, preds), "ground")
    assert [r.label for r in ground] == ["grass", "snow", "asphalt", "tiles"]
    q = charge_mah(logs[1].time_s, 0.3 * left) + charge_mah(logs[1].time_s, 0.3 * right)
    assert ground[0].gap_mah == pytest.approx(q)
    assert ground[2].gap_mah == 0.0 and ground[3].gap_mah == 0.0
    assert ground[1].n_runs == 1 and ground[1].n_samples == n // 2
    assert ground[0].share_pct + ground[1].share_pct == pytest.approx(100.0)


def test_a_one_amp_offset_on_the_left_shows_in_side_left_with_its_exact_charge():
    v, w = stop_turn_go()
    left, right = measured(v, w)
    log = motion_log(v, w, left + 1.0, right)
    pred = np.column_stack([left, right])
    side = shares_of(localise_gap(log, pred), "side")
    assert [r.label for r in side] == ["left", "right"]
    assert side[0].gap_mah == pytest.approx(charge_mah(log.time_s, np.ones(v.size)), rel=1e-12)
    assert side[0].share_pct == 100.0 and side[1].gap_mah == 0.0 and side[1].share_pct == 0.0
    assert side[0].n_samples == v.size and side[0].n_runs == 1


def test_time_sections_follow_the_metrics_sections_and_carry_the_run():
    log = motion_log(np.full(201, 0.5), np.zeros(201), np.ones(201), np.ones(201))  # 20 s
    labels = time_labels(log, 3)
    assert labels[0] == "run 3, 0-8 s" and labels[80] == "run 3, 8-16 s" and labels[-1] == "run 3, 16-20 s"
    pred = np.ones((201, 2))
    pred[110:120] = 0.0  # a miss between 11 and 12 s
    logs = [motion_log(np.full(201, 0.5), np.zeros(201), np.ones(201), np.ones(201)), log]
    time = shares_of(localise_gap(logs, [np.ones((201, 2)), pred]), "time")
    assert time[0].label == "run 1, 8-16 s" and time[0].share_pct == pytest.approx(100.0)
    assert len(time) == 6 and time[0].n_runs == 1
    assert sum(r.duration_s for r in time) == pytest.approx(40.0)


def test_every_dimension_adds_up_to_the_whole_gap_on_a_simulated_drive():
    ramp = ramp_map((30, 30), 1.0, grade=0.08, ground="coated_wood")
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, seed=2)
    logs = [sim.drive(ramp, [(3.0, 3.0), (20.0, 3.0), (20.0, 20.0), (4.0, 20.0)], seed=s) for s in (1, 2)]
    rng = np.random.default_rng(1)
    preds = [rng.uniform(0.5, 4.0, (len(log), 2)) for log in logs]
    rows = localise_gap(logs, preds, terrain=ramp)
    assert tuple(dict.fromkeys(r.dimension for r in rows)) == DIMENSIONS
    whole = gap_summary(logs, preds)
    for dim in DIMENSIONS:
        part = shares_of(rows, dim)
        assert sum(r.gap_mah for r in part) == pytest.approx(whole.gap, abs=1e-9), dim
        if dim == "side":  # each side covers all the time
            assert [r.duration_s for r in part] == [pytest.approx(whole.duration_s)] * 2
        else:
            assert sum(r.duration_s for r in part) == pytest.approx(whole.duration_s), dim
            assert sum(r.n_samples for r in part) == whole.n_samples, dim
            assert sum(r.share_pct for r in part) == pytest.approx(100.0), dim
        magnitudes = [abs(r.gap_mah) for r in part]
        assert magnitudes == sorted(magnitudes, reverse=True), dim
    grades = {r.label for r in shares_of(rows, "grade")}
    assert {"uphill", "level", "downhill"} <= grades
    assert all(r.label.startswith("cells (") for r in shares_of(rows, "space"))
    row = rows[0]
    assert isinstance(row, GapShare) and "mAh" in str(row)
    json.dumps([r.to_dict() for r in rows])


def test_a_miss_in_one_corner_of_the_map_tops_the_space_rows():
    tmap = flat_map((20, 20), 1.0)
    x = np.linspace(1.0, 19.0, 181)
    pose = np.column_stack([x, np.full(181, 2.0), np.zeros(181)])
    v = np.full(181, 0.5)
    log = motion_log(v, np.zeros(181), np.ones(181), np.ones(181), pose_xyh=pose)
    pred = np.ones((181, 2))
    pred[x >= 15.5] = 0.5
    space = shares_of(localise_gap([log], [pred], terrain=tmap), "space")
    assert space[0].label == "cells (0-4, 15-19)" and space[0].share_pct == pytest.approx(100.0)
    unknown = shares_of(localise_gap([log], [pred]), "space")
    assert [r.label for r in unknown] == ["unknown"]


def test_a_perfect_model_has_zero_shares_everywhere():
    v, w = stop_turn_go(20)
    left, right = measured(v, w)
    rows = localise_gap([motion_log(v, w, left, right)], [np.column_stack([left, right])])
    assert all(r.gap_mah == 0.0 and r.share_pct == 0.0 for r in rows)
    assert not any(math.isnan(r.share_pct) for r in rows)
    assert all(r.gap_interval_mah == (0.0, 0.0) and (r.gap_pct == 0.0 or r.measured_mah == 0.0) for r in rows)


def test_slices_of_opposite_sign_rank_by_their_net_gap_while_the_whole_gap_cancels():
    """Too little in pivots, as much too much while driving straight: the whole gap is 0, yet
    each of the two slices holds a net gap of its own, with its sign and its share of the
    slice's charge; nothing is said as a share of absolute gaps."""
    v, w = stop_turn_go()
    left, right = measured(v, w)
    log = motion_log(v, w, left, right)
    pivot = (np.abs(v) < 0.05) & (np.abs(w) >= 0.1)
    straight = (np.abs(v) >= 0.05) & (np.abs(w) < 0.1)
    pred = np.column_stack([left, right])
    pred[pivot] -= 1.0
    pred[straight] += 1.0  # as many samples as the pivot: the misses cancel
    rows = localise_gap([log], [pred])
    q = charge_mah(log.time_s, np.where(pivot, 2.0, 0.0))  # 1 A on each side
    assert abs(gap_summary([log], [pred]).gap) < 0.01 * q  # (up to the half-weight of the first sample)
    turning = shares_of(rows, "turning")
    assert {r.label: np.sign(r.gap_mah) for r in turning[:2]} == {"pivot": 1.0, "straight": -1.0}
    piv = next(r for r in turning if r.label == "pivot")
    assert piv.gap_mah == pytest.approx(q, rel=1e-9)
    assert piv.measured_mah == pytest.approx(charge_mah(log.time_s, np.where(pivot, left + right, 0.0)), rel=1e-9)
    assert piv.gap_pct == pytest.approx(100.0 * piv.gap_mah / piv.measured_mah)
    top = largest_slices(rows, 4)
    assert {(r.dimension, r.label) for r in top[:2]} <= {("turning", "pivot"), ("turning", "straight"),
                                                        ("speed", "pivot"), ("speed", "0.5-1 m/s")}
    assert abs(top[0].gap_mah) == pytest.approx(q, rel=1e-6)
    speed = {r.label: r for r in shares_of(rows, "speed")}
    assert speed["pivot"].gap_mah == pytest.approx(q, rel=1e-9)  # pivots are not lumped with standstill
    assert speed["standstill"].gap_mah == pytest.approx(0.0, abs=1e-12)


def _pivot_misses(n_runs, miss_runs):
    v, w = stop_turn_go(50)
    left, right = measured(v, w)
    pivot = (np.abs(v) < 0.05) & (np.abs(w) >= 0.1)
    logs, preds = [], []
    for k in range(n_runs):
        scale = 1.0 + 0.05 * k  # runs differ a little
        logs.append(motion_log(v, w, left * scale, right * scale))
        pred = np.column_stack([left, right]) * scale
        if k in miss_runs:
            pred[pivot] -= 1.0 + 0.2 * k
        preds.append(pred)
    return logs, preds


def test_the_interval_of_a_slice_resamples_runs_and_is_seeded():
    logs, preds = _pivot_misses(6, range(6))  # every run misses in its pivots
    rows = localise_gap(logs, preds)
    piv = next(r for r in shares_of(rows, "turning") if r.label == "pivot")
    lo, hi = piv.gap_interval_mah
    assert 0.0 < lo <= piv.gap_mah <= hi
    assert rows == localise_gap(logs, preds)  # seeded: the same intervals
    other = localise_gap(logs, preds, seed=1)
    assert next(r for r in shares_of(other, "turning") if r.label == "pivot").gap_interval_mah != (lo, hi)
    assert [r.gap_mah for r in other] == [r.gap_mah for r in rows]  # the gaps themselves do not depend on it
    one_run = localise_gap(*_pivot_misses(6, [0]))  # one run of six misses: it may well not recur
    piv1 = next(r for r in shares_of(one_run, "turning") if r.label == "pivot")
    assert piv1.gap_mah > 0 and piv1.gap_interval_mah[0] == pytest.approx(0.0, abs=1e-12)
    assert piv1.gap_interval_mah[1] > piv1.gap_mah


def test_with_one_run_the_interval_resamples_its_time_sections():
    v = np.tile(np.concatenate([np.full(40, 0.6), np.zeros(40)]), 10)  # 80 s: 10 sections of 8 s
    w = np.tile(np.concatenate([np.zeros(40), np.full(40, 0.8)]), 10)
    left, right = measured(v, w)
    log = motion_log(v, w, left, right)
    pred = np.column_stack([left, right]) - 0.5  # the model is 0.5 A low everywhere
    rows = localise_gap([log], [pred])
    assert len(shares_of(rows, "time")) == 10
    for r in rows:
        lo, hi = r.gap_interval_mah
        assert math.isfinite(lo) and lo <= hi, r
    side = shares_of(rows, "side")[0]
    assert side.gap_interval_mah[0] > 0.0  # the same miss in every section: a short interval above 0


def test_largest_slices_leave_out_unknown_and_one_slice_dimensions():
    v, w = stop_turn_go(20)
    left, right = measured(v, w)
    log = motion_log(v, w, left, right, ground_label="grass")  # one ground; no map: grade and space unknown
    pred = np.column_stack([left, right]) * 0.7
    rows = localise_gap([log], [pred])
    top = largest_slices(rows, 50)
    dims = {r.dimension for r in top}
    assert not dims & {"ground", "grade", "space"}
    assert "unknown" not in {r.label for r in top}
    gaps = [abs(r.gap_mah) for r in top]
    assert gaps == sorted(gaps, reverse=True)
    assert len(largest_slices(rows)) == 10 and largest_slices(rows, 3) == top[:3]
    with pytest.raises(InvalidParameterError, match="n must be"):
        largest_slices(rows, 0)


def test_bad_localisation_input_is_named():
    v, w = stop_turn_go(5)
    log = motion_log(v, w, *measured(v, w))
    good = np.ones((v.size, 2))
    with pytest.raises(DataError, match="logs is empty"):
        localise_gap([], [])
    with pytest.raises(InvalidParameterError, match="one array per log: 1 log"):
        localise_gap([log], [good, good])
    with pytest.raises(InvalidParameterError, match=r"predictions\[0\] must have shape \(20, 2\)"):
        localise_gap([log], [good.T])
    with pytest.raises(DataError, match="must be finite"):
        localise_gap([log], [np.full((v.size, 2), np.inf)])
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        localise_gap([log], [good], terrain="map.tif")
    with pytest.raises(InvalidParameterError, match="section_s must be a real number"):
        localise_gap([log], [good], section_s="8")
    with pytest.raises(InvalidParameterError, match="n_bootstrap"):
        localise_gap([log], [good], n_bootstrap=0)
    with pytest.raises(UnknownNameError, match="dimension must be one of"):
        shares_of(localise_gap([log], [good]), "weather")


# ---------------------------------------------------------------------- the battery power: the same summary
def _power_log(power_w: np.ndarray, v: np.ndarray) -> InteractionLog:
    t = np.arange(power_w.size, dtype=float)  # 1 s steps
    ta = np.arange(0.0, t[-1] + 0.05, 0.1)
    return InteractionLog(t, v, np.zeros(t.size), np.ones(t.size), np.ones(t.size), ta, np.full(ta.size, 9.81),
                          meta=LogMeta(source="p.csv"), battery_voltage_v=np.full(t.size, 24.0),
                          battery_current_a=power_w / 24.0)


def test_the_power_gap_summary_of_a_constant_shortfall():
    measured = np.full(37, 100.0)  # 36 s at 100 W = 1 Wh
    still = (np.arange(37) < 10).astype(float)  # standing still for the first 10 samples
    log = _power_log(measured, np.where(still > 0, 0.0, 0.5))
    s = gap_summary([log], [measured - 10.0], quantity=POWER, stopped=[still], section_s=8.0)
    assert isinstance(s, GapSummary) and s.quantity is POWER and (s.n_runs, s.n_samples) == (1, 37)
    assert s.measured == pytest.approx(1.0) and s.predicted == pytest.approx(0.9) and s.gap == pytest.approx(0.1)
    assert s.error_pct == pytest.approx(10.0) and s.rmse == pytest.approx(10.0)
    assert s.section_error_pct == pytest.approx(10.0)
    assert s.stopped_time_pct == pytest.approx(100.0 * 9.5 / 36.0)  # trapezoid weights: half a second at the ends
    assert s.stopped_gap_pct == pytest.approx(s.stopped_time_pct)
    d = json.loads(json.dumps(s.to_dict()))
    assert list(d) == ["measured_wh", "predicted_wh", "gap_wh", "energy_error_pct", "section_error_pct", "rmse_w",
                       "stopped_gap_pct", "stopped_time_pct", "n_runs", "n_samples"]  # diagnosis.json's "power" keys
    assert "0.1 Wh" in str(s) and "W over 1 run" in str(s)


def test_a_perfect_power_prediction_has_no_gap_and_no_stopped_share():
    measured = np.linspace(50.0, 150.0, 20)
    log = _power_log(measured, np.full(20, 0.5))
    s = gap_summary([log], [measured[:, None]], quantity=POWER, stopped=[np.zeros(20)])
    assert s.gap == pytest.approx(0.0, abs=1e-12) and s.rmse == pytest.approx(0.0, abs=1e-9)
    assert s.stopped_gap_pct == 0.0  # no standstill
    assert math.isnan(gap_summary([log], [np.ones((20, 2))]).stopped_gap_pct)  # the current's summary has no standstill
    with pytest.raises(InvalidParameterError, match=r"predictions\[0\] must have shape \(20, 1\) \(the power"):
        gap_summary([log], [np.ones((20, 2))], quantity=POWER)
    with pytest.raises(DataError, match="the logs carry no battery power"):
        gap_summary([_power_log(np.zeros(20), np.zeros(20))], [np.zeros(20)], quantity=POWER)
    with pytest.raises(InvalidParameterError, match="quantity must be a Quantity"):
        gap_summary([log], [measured], quantity="power")


def test_a_waterfall_step_as_json_under_its_quantitys_keys():
    w = WaterfallStep(CURRENT, "+ mass", 2.5, 4.0, 0.3, 60.0)
    assert w.to_dict() == {"label": "+ mass", "charge_error_pct": 2.5, "section_error_pct": 4.0, "rmse_a": 0.3,
                           "shrink_pct": 60.0}
    p = WaterfallStep(POWER, "+ control", -0.5, 1.0, 2.5, 99.0)
    assert list(p.to_dict()) == ["label", "energy_error_pct", "section_error_pct", "rmse_w", "shrink_pct"]
