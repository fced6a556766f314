"""Tests of energy.models.uncertainty: IntervalModel (run-to-run and sample spread) and the per-run regime coefficients."""

import numpy as np
import pytest
from interval_samples import interval_log

from energy.logs import rest_samples
from energy.models.uncertainty import IntervalModel, regime_design, run_coefficients
from energy.power import trapezoid


def test_interval_model_learns_the_run_to_run_spread_of_offsets():
    rng = np.random.default_rng(0)
    logs, residuals = [], []
    for s in range(40):
        lg = interval_log(s, duration_s=20.0)
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
    lg = interval_log(3)
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



def test_a_forecast_is_a_student_t_with_as_many_degrees_of_freedom_as_grounds_or_runs_taught_it():
    from interval_samples import fit_two_ground_estimator, interval_log

    from energy.models.uncertainty import IntervalModel

    est, train = fit_two_ground_estimator()
    assert est.interval_.n_grounds == 2 and est.interval_.new_ground_dof == 2.0
    assert est.predict_distribution(train[0]).dof == 4.0  # a ground it trained on: as many as its runs (4 of "a")
    new = est.predict_distribution(interval_log(50, "c"))
    assert new.dof == 2.0 and new.charge().dof == 2.0
    assert est.adapt(interval_log(51, "c").slice(0.0, 20.0)).predict_distribution(interval_log(52, "c")).dof == 2.0
    plain = est.interval_.to_plain()
    assert IntervalModel.from_plain(plain).n_grounds == 2
    assert IntervalModel.from_plain(plain).run_counts == {"*": 8, "a": 4, "b": 4}
    del plain["n_grounds"], plain["run_counts"]  # a model file from before the counts: Gaussian forecasts
    old = IntervalModel.from_plain(plain)
    assert old.new_ground_dof == np.inf and old.run_dof("a") == np.inf and old.run_counts is None
    with pytest.raises(ValueError, match="one count per run covariance"):
        IntervalModel.from_plain(est.interval_.to_plain() | {"run_counts": {"*": 8}})
    with pytest.raises(ValueError):
        IntervalModel.from_plain(est.interval_.to_plain() | {"run_counts": {"*": 0, "a": 4, "b": 4}})


def _offset_runs(halves_agree: bool, n: int = 30, seed: int = 5):
    """Runs whose residual is a run offset (1 A sd) on top of 0.2 A noise: the same along the run, or one per half."""
    rng = np.random.default_rng(seed)
    logs, residuals = [], []
    for s in range(n):
        lg = interval_log(s, duration_s=20.0)
        first = lg.time_s < 10.0
        a, b = rng.normal(0.0, 1.0, 2)
        off = np.where(first, a, a if halves_agree else b)
        logs.append(lg)
        residuals.append(off[:, None] + 0.2 * rng.standard_normal((len(lg), 2)))
    return logs, residuals, [np.full((len(lg), 2), 3.0) for lg in logs]


def test_the_carry_of_a_run_offset_along_the_run_is_learned_from_its_halves():
    steady = IntervalModel.fit(*_offset_runs(True), cross_validated=True)
    drifting = IntervalModel.fit(*_offset_runs(False), cross_validated=True)
    assert steady.run_carry == pytest.approx(1.0, abs=0.05)  # the first half says all of the second
    assert drifting.run_carry < 0.35  # 30 runs: a correlation of 0 measured within ~2 standard errors
    logs, residuals, preds = _offset_runs(True, n=2)
    assert IntervalModel.fit(logs, residuals, preds, cross_validated=True).run_carry is None  # too few runs
    noise_only = [0.2 * np.random.default_rng(s).standard_normal(r.shape) for s, r in enumerate(residuals * 5)]
    quiet = IntervalModel.fit(logs * 5, noise_only, preds * 5, cross_validated=True)
    assert quiet.run_carry is None or quiet.run_carry < 0.5  # nothing run-level to carry


def test_the_carry_is_saved_and_a_file_without_it_or_a_forged_one_is_handled():
    iv = IntervalModel.fit(*_offset_runs(True, n=6), cross_validated=True)
    assert iv.run_carry is not None
    assert IntervalModel.from_plain(iv.to_plain()).run_carry == iv.run_carry
    old = {k: v for k, v in iv.to_plain().items() if k != "run_carry"}
    assert IntervalModel.from_plain(old).run_carry is None  # a file from before: the base spread within a run
    for bad in (1.5, -0.1, float("nan"), "x"):
        with pytest.raises(ValueError):
            IntervalModel.from_plain(iv.to_plain() | {"run_carry": bad})


def test_a_carry_is_never_learned_from_non_finite_residuals():
    logs, residuals, preds = _offset_runs(True, n=6)
    iv = IntervalModel.fit(logs, residuals, preds, cross_validated=True)
    broken = [r.copy() for r in residuals]
    broken[2][5, 0] = np.nan
    assert iv.carry_along_runs(logs, broken) is None  # a file must stay loadable: no NaN saved as the carry


def test_a_run_spread_from_few_runs_forecasts_their_residual_charges():
    # three runs offset by +-0.8 A (second moment 0.64 A²) and per-sample noise: the regime coefficients of so few
    # runs are shrunk to their diagonal and the ridge splits the offset between columns, so the covariance alone
    # forecasts a spread that no run showed (0.49 A here); scaled at the charge level it is the runs' own 0.8 A
    rng = np.random.default_rng(1)
    logs, residuals = [], []
    for s, off in enumerate([0.8, -0.8, 0.8]):
        lg = interval_log(s, duration_s=30.0)
        logs.append(lg)
        residuals.append(off + 0.2 * rng.standard_normal((len(lg), 2)))
    preds = [np.full((len(lg), 2), 3.0) for lg in logs]
    iv = IntervalModel.fit(logs, residuals, preds, cross_validated=True)
    new = interval_log(9, duration_s=30.0)
    assert np.median(iv.run_sd_a(new, np.full((len(new), 2), 3.0), known=True)) == pytest.approx(0.8, rel=0.05)
    # what it promises: the training runs' residual charges, less the noise's share, are what their spread forecasts
    forecast = sum(float(np.sum(trapezoid(iv.run_sd_a(lg, p, known=True), lg.time_s, axis=0) ** 2))
                   for lg, p in zip(logs, preds))
    seen = sum(float(np.sum(trapezoid(r, lg.time_s, axis=0) ** 2 - iv.noise_charge_var(lg)))
               for lg, r in zip(logs, residuals))
    assert forecast == pytest.approx(seen, rel=1e-9)
    # runs whose charges show nothing above the noise keep the covariance as fitted (never a spread of zero)
    flat = [np.zeros((len(lg), 2)) for lg in logs]
    assert iv.charge_scale(range(3), logs, flat, preds, np.stack([np.eye(4)] * 2)) == 1.0
    assert iv.charge_scale(range(3), logs, residuals, preds, np.stack([np.eye(4)] * 2)) < 1.0

