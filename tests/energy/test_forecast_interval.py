"""Tests of the forecast interval: CurrentForecast, IntervalModel, the cross-validation ensemble, the Bayesian update."""

import dataclasses

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, VibrationCurrentEstimator, load_current_model
from terrawatt_base.errors import InvalidParameterError
from energy.evaluation.intervals import IntervalRecord, charge_record, coverage, plot_reliability
from energy.models import AdaptedCurrentModel, LinearCurrentModel, fit_interval, log_currents
from terrawatt_base.errors import DataError
from energy.models.config import estimator_preset
from energy.models.forecast import CurrentForecast, combine_ground_sds, normal_quantile
from energy.logs import rest_samples
from energy.models.uncertainty import IntervalModel, regime_design, run_coefficients


def _log(seed: int, ground: str = "g", *, offset_a: float = 0.0, gain: float = 1.0, vibration: float = 0.3,
         duration_s: float = 40.0) -> InteractionLog:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 0.1)
    p1, p2 = rng.uniform(0, 2 * np.pi, 2)
    v = 0.45 + 0.35 * np.sin(2 * np.pi * t / 7.0 + p1)
    w = 0.6 * np.sin(2 * np.pi * t / 5.0 + p2)
    left = gain * (0.5 + 4.0 * v + 3.0 * np.maximum(-w, 0) + np.maximum(w, 0)) + offset_a
    right = gain * (0.5 + 4.0 * v + 3.0 * np.maximum(w, 0) + np.maximum(-w, 0)) + offset_a
    noise = 0.1 * rng.standard_normal((2, t.size))
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    az = 9.81 + vibration * rng.standard_normal(ta.size)
    return InteractionLog(t, v, w, left + noise[0], right + noise[1], ta, az,
                          meta=LogMeta(source=f"{ground}/run{seed}", ground_label=ground, robot="husky_a200"))


def _small(**changes):
    base = dict(window_s=0.5, hidden_sizes=(16, 16), n_members=3, max_epochs=25, patience=8, learning_rate=3e-3,
                batch_size=64, train_stride_s=0.3, dropout=0.0, physics_prior=None)
    base.update(changes)
    return estimator_preset("default").replace(**base)


# ----------------------------------------------------------------- CurrentForecast
def test_run_spread_adds_linearly_and_sample_spread_in_quadrature():
    t = np.arange(0.0, 10.0 + 1e-9, 0.1)
    mean = np.full((t.size, 2), 2.0)
    run = np.column_stack([np.full(t.size, 0.5), np.full(t.size, 0.3)])
    white = np.full((t.size, 2), 1.0)
    q = CurrentForecast(t, mean, run, np.zeros_like(white)).charge()
    assert q.mean_as == pytest.approx([20.0, 20.0])
    assert q.sd_as == pytest.approx([5.0, 3.0])  # 0.5 A for 10 s, all of it shared
    assert q.total_sd_as == pytest.approx(8.0)  # the two sides' run parts add too
    qw = CurrentForecast(t, mean, np.zeros_like(run), white).charge()
    dt = np.gradient(t)
    assert qw.sd_as[0] == pytest.approx(np.sqrt(np.sum(dt**2)))  # ~ 1 A * sqrt(10 s * 0.1 s): averages out
    assert qw.sd_as[0] < 0.15 * 10.0  # the same 1 A shared by the run would give 10 A s
    lo, hi = q.interval(0.8)
    assert (hi - q.total_mean_as) == pytest.approx(normal_quantile(0.9) * 8.0)
    assert q.quantile(0.5) == pytest.approx(40.0)


def test_forecast_refuses_bad_spreads_and_point_forecasts_have_none():
    t = np.arange(5.0)
    with pytest.raises(InvalidParameterError, match=">= 0"):
        CurrentForecast(t, np.zeros((5, 2)), -np.ones((5, 2)), np.zeros((5, 2)))
    with pytest.raises(InvalidParameterError, match="shape"):
        CurrentForecast(t, np.zeros((4, 2)), np.zeros((5, 2)), np.zeros((5, 2)))
    assert not CurrentForecast.point(t, np.ones((5, 2))).has_interval
    assert combine_ground_sds([3.0, 4.0]) == pytest.approx(5.0)


def test_models_without_an_interval_give_a_point_forecast():
    logs = [_log(s) for s in range(2)]
    lin = LinearCurrentModel().fit(logs)
    fc = lin.predict_distribution(logs[0])
    assert not lin.gives_interval and not fc.has_interval
    np.testing.assert_allclose(fc.mean_a, lin.predict(logs[0]))
    assert lin.training_summary.grounds == {"g": pytest.approx(2 * logs[0].duration_s)}
    assert lin.training_summary.robots == ("husky_a200",)


# ------------------------------------------------------------------ IntervalModel
def test_interval_model_learns_the_run_to_run_spread_of_offsets():
    rng = np.random.default_rng(0)
    logs, residuals = [], []
    for s in range(40):
        lg = _log(s, duration_s=20.0)
        off = rng.normal(0.0, 0.8)  # a run-level offset of 0.8 A sd, plus per-sample noise
        logs.append(lg)
        residuals.append(off + 0.2 * rng.standard_normal((len(lg), 2)))
    level = np.full((len(logs[0]), 2), 3.0)
    iv = IntervalModel.fit(logs, residuals, [np.full((len(lg), 2), 3.0) for lg in logs], cross_validated=True)
    # the offset shows in the run spread of a straight-and-turning run; the sample noise in sample_sd
    sd = iv.run_sd_a(logs[0], level, known=True)
    assert np.median(sd) == pytest.approx(0.8, rel=0.3)
    assert 0.15 < iv.sample_sd_a[:, 1:].max() < 0.3  # 0.2 A, plus what the ridge leaves of the offset
    assert iv.new_ground_cov is None  # one ground: nothing to learn a new ground's spread from
    back = IntervalModel.from_plain(iv.to_plain())
    np.testing.assert_allclose(back.run_sd_a(logs[0], level, known=True), sd)
    bad = iv.to_plain() | {"sample_sd_a": -np.ones((2, 3))}
    with pytest.raises(ValueError):
        IntervalModel.from_plain(bad)


def test_run_coefficients_reproduce_a_known_offset_and_a_known_gain():
    lg = _log(3)
    level = np.column_stack([lg.current_left_a, lg.current_right_a])
    gain = run_coefficients(lg, 0.25 * level, level, 0.3)  # measured = 1.25 x predicted
    moving = ~rest_samples(lg)
    refit = np.column_stack([regime_design(lg, k, 0.3, level[:, k]) @ gain[k] for k in range(2)])
    assert np.mean(np.abs(refit[moving] - 0.25 * level[moving])) < 0.05 * np.mean(level)
    assert np.all(gain[:, 0] > 0.1)  # the gain column carries a good part of it
    coef = run_coefficients(lg, np.full((len(lg), 2), 1.5), level, 0.3)
    fitted = np.column_stack([regime_design(lg, k, 0.3, level[:, k]) @ coef[k] for k in range(2)])
    assert np.median(fitted) == pytest.approx(1.5, rel=0.05)
    # standing still is the rest level's, not a regime of driving
    # the ridge spreads a constant over correlated columns: close to it on most samples, exact nowhere
    assert np.mean(np.abs(fitted[moving] - 1.5)) < 0.15 and np.all(fitted[~moving] == 0.0)


# ------------------------------------------------------- estimator with an interval
@pytest.fixture(scope="module")
def two_ground_estimator():
    logs = [_log(s, "a", vibration=0.2) for s in range(4)] + [_log(10 + s, "b", vibration=1.0, gain=1.4) for s in range(4)]
    est = VibrationCurrentEstimator(_small(physics_prior="husky"), seed=0, n_threads=1).fit(logs)
    return est, logs


def test_cross_validation_ensemble_gives_an_interval_wider_on_a_new_ground(two_ground_estimator, tmp_path):
    est, logs = two_ground_estimator
    assert est.gives_interval and est.interval_.cross_validated
    assert list(est.member_folds_) == [0, 1, 2, 0, 1, 2, 0, 1]
    assert est.interval_.new_ground_cov is not None
    known = est.predict_distribution(logs[0])
    np.testing.assert_allclose(known.mean_a, est.predict(logs[0]))
    assert known.has_interval
    new = est.predict_distribution(dataclasses.replace(logs[0], meta=dataclasses.replace(logs[0].meta, ground_label="c")))
    assert new.charge().total_sd_as > known.charge().total_sd_as
    path = est.save(tmp_path / "m.zip")
    back = load_current_model(path)
    assert back.gives_interval
    np.testing.assert_allclose(back.predict_distribution(logs[0]).run_sd_a, known.run_sd_a, rtol=1e-6)
    assert back.training_summary.grounds.keys() == {"a", "b"}
    assert back.ground_vibration("A") is not None and back.ground_vibration("c") is None


def test_bayes_update_learns_a_new_ground_offset_and_narrows_its_interval(two_ground_estimator):
    est, _ = two_ground_estimator
    new_runs = [_log(30 + s, "c", vibration=0.5, offset_a=2.0) for s in range(2)]
    prefix = new_runs[0].slice(0.0, 20.0)
    before = est.predict_distribution(new_runs[1]).charge()
    ad = AdaptedCurrentModel(est, method="bayes", scope="ground").fit(prefix)
    after = ad.predict_distribution(new_runs[1]).charge()
    true = float(np.sum(np.trapezoid(log_currents(new_runs[1]), new_runs[1].time_s, axis=0)))
    assert abs(after.total_mean_as - true) < 0.5 * abs(before.total_mean_as - true)
    assert after.total_sd_as < before.total_sd_as
    same_run = AdaptedCurrentModel(est, method="bayes", scope="run").fit(prefix)
    assert same_run.coefficients_.shape == (2, 8)
    with pytest.raises(DataError, match="interval"):
        AdaptedCurrentModel(LinearCurrentModel().fit(new_runs), method="bayes").fit(prefix)


# ----------------------------------------------------------------- calibration
def test_coverage_counts_records_inside_each_central_interval():
    z90 = normal_quantile(0.9)
    recs = [IntervalRecord("g", "x", f"r{i}", true_as=10.0 + z, mean_as=10.0, sd_as=1.0)
            for i, z in enumerate([0.1, -0.5, 1.0, -z90 + 0.01, 3.0])]
    cov = coverage(recs)["g"]
    assert cov["50 %"] == pytest.approx(2 / 5)  # |z| <= 0.674
    assert cov["80 %"] == pytest.approx(4 / 5)
    assert cov["95 %"] == pytest.approx(4 / 5)
    ax = plot_reliability(recs)
    assert len(ax.lines) == 2


def test_charge_record_scores_a_model_forecast(two_ground_estimator):
    est, logs = two_ground_estimator
    rec = charge_record(est, logs[1], group="known", run="r1")
    assert rec.sd_as > 0 and rec.true_as > 0
    assert abs(rec.z) < 5


def test_fit_interval_gives_any_model_a_cross_validated_interval(tmp_path):
    logs = [_log(s, "a", offset_a=0.3 * (s % 3)) for s in range(6)] + [_log(20 + s, "b", gain=1.3) for s in range(6)]
    lin = fit_interval(LinearCurrentModel(), logs, folds=3)
    assert lin.gives_interval and lin.interval_.cross_validated and lin.interval_.new_ground_cov is not None
    known = lin.predict_distribution(logs[0]).charge()
    assert known.total_sd_as > 0
    np.testing.assert_allclose(lin.predict_distribution(logs[0]).mean_a, lin.predict(logs[0]))
    unseen = dataclasses.replace(logs[0], meta=dataclasses.replace(logs[0].meta, ground_label="c"))
    assert lin.predict_distribution(unseen).charge().total_sd_as > known.total_sd_as
    back = load_current_model(lin.save(tmp_path / "lin.zip"))
    assert back.gives_interval
    assert back.predict_distribution(logs[0]).charge().total_sd_as == pytest.approx(known.total_sd_as)
    adapted = back.adapt(logs[1].slice(0.0, 20.0), method="bayes")
    again = load_current_model(adapted.save(tmp_path / "adapted.zip"))  # the base's interval travels with it
    assert again.gives_interval
    np.testing.assert_allclose(again.predict_distribution(logs[2]).run_sd_a, adapted.predict_distribution(logs[2]).run_sd_a)
    with pytest.raises(DataError, match="at least 2"):
        fit_interval(LinearCurrentModel(), logs[:1])
    with pytest.raises(InvalidParameterError):
        fit_interval(adapted, logs)
