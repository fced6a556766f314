"""Tests of energy.models.adaptation: in-run adaptation of a fitted current model (model.adapt)."""

import copy
import dataclasses

import numpy as np
import pytest
from interval_samples import fit_two_ground_estimator, interval_log

from energy import AdaptedCurrentModel, InteractionLog, LinearCurrentModel, LogMeta, load_current_model
from energy.models import ADAPT_METHODS, MIN_ADAPT_SAMPLES, ModelRecord, log_currents
from terrain import UnknownNameError
from terrawatt_base.errors import DataError, FileFormatError, InvalidParameterError, NotFittedError


def _log(seed: int, *, turn_extra_a: float = 0.0, offset_a: float = 0.0, turns_after_s: float = 0.0,
         duration_s: float = 60.0) -> InteractionLog:
    """A run whose currents follow a known relation; ``turn_extra_a`` adds current on the outer side of turns."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 0.1)
    v = 0.5 + 0.2 * np.sin(2 * np.pi * t / 7.0 + rng.uniform(0, 6))
    w = np.where(t >= turns_after_s, 0.6 * np.sign(np.sin(2 * np.pi * t / 6.0 + rng.uniform(0, 6))), 0.0)
    m = np.tanh(np.abs(w) / 0.3)
    left = 0.5 + 3.0 * np.abs(v) + 1.0 * np.abs(w) + turn_extra_a * m * (w < 0) + offset_a
    right = 0.8 + 2.0 * np.abs(v) + 1.5 * np.abs(w) + turn_extra_a * m * (w > 0) + offset_a
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    return InteractionLog(t, v, w, left, right, ta, np.full(ta.size, 9.81),
                          meta=LogMeta(source=f"g/pro_{seed:02d}.csv", ground_label="g"))


def _on_base(base, log: InteractionLog, *, offset_a: float = 0.0, turn_extra_a: float = 0.0) -> InteractionLog:
    """``log`` with currents = the base model's prediction + an offset + extra current on the outer side of turns."""
    pred = base.predict(log)
    w = log.omega_radps
    m = np.tanh(np.abs(w) / 0.3)
    return dataclasses.replace(log, current_left_a=pred[:, 0] + offset_a + turn_extra_a * m * (w < 0),
                               current_right_a=pred[:, 1] + offset_a + turn_extra_a * m * (w > 0))


def _head(log: InteractionLog, seconds: float) -> InteractionLog:
    return log.slice(float(log.time_s[0]), float(log.time_s[0] + seconds))


def _charge_error_pct(log: InteractionLog, pred: np.ndarray, t_from: float) -> float:
    sel = log.time_s >= t_from
    truth = np.trapezoid(np.column_stack([log.current_left_a, log.current_right_a])[sel], log.time_s[sel], axis=0)
    q = np.trapezoid(pred[sel], log.time_s[sel], axis=0)
    return float(np.max(np.abs(q - truth) / truth) * 100)


@pytest.fixture(scope="module")
def base():
    return LinearCurrentModel().fit([_log(1), _log(2)])


def test_adapt_returns_a_new_model_and_leaves_the_fitted_one_unchanged(base):
    run = _log(3, turn_extra_a=1.5)
    before = base.predict(run)
    coef_before = {k: np.copy(v) for k, v in vars(base).items() if isinstance(v, np.ndarray)}
    adapted = base.adapt(_head(run, 20.0))
    assert isinstance(adapted, AdaptedCurrentModel) and adapted is not base
    assert adapted.base is base and adapted.method == ADAPT_METHODS[0] == "partition"
    np.testing.assert_array_equal(base.predict(run), before)
    for k, v in coef_before.items():
        np.testing.assert_array_equal(getattr(base, k), v)
    assert adapted.adapted_on_s_ == pytest.approx(20.0, abs=0.11) and adapted.n_samples_ >= 199


def test_regime_update_corrects_turns_seen_in_the_prefix(base):
    run = _on_base(base, _log(4), turn_extra_a=1.5)
    plain = _charge_error_pct(run, base.predict(run), 20.0)
    adapted = base.adapt(_head(run, 20.0), method="regime")
    assert plain > 10.0
    assert _charge_error_pct(run, adapted.predict(run), 20.0) < plain / 3
    outer = adapted.coefficients_[:, 3]
    assert np.all(outer > 0.2) and np.all(outer > np.abs(adapted.coefficients_[:, 2]))  # the outer side carries it


def test_straight_prefix_does_not_rescale_turns_unlike_the_gain(base):
    # +0.6 A on every sample (a higher idle current), turns only after 45 s: the first 40 s see straights only
    run = _on_base(base, _log(5, turns_after_s=45.0, duration_s=90.0), offset_a=0.6)
    head = _head(run, 40.0)
    regime = base.adapt(head, method="regime", prior_s=2.0)
    gain = base.adapt(head, method="gain")
    assert np.all(np.abs(regime.coefficients_[:, 2:]) < 0.05)  # no turn seen: no turn correction
    shift = (regime.predict(head) - base.predict(head)).mean(axis=0)
    assert np.all((shift > 0.5) & (shift < 0.6))  # the 0.6 A, shrunk a little by the prior
    # the gain, fitted on straights, scales the larger turning currents too
    assert _charge_error_pct(run, regime.predict(run), 40.0) < 0.5 * _charge_error_pct(run, gain.predict(run), 40.0)


def test_partition_keeps_a_pivot_correction_off_straight_driving_unlike_the_regime_update(base):
    # the first 20 s pivot in place drawing 1 A more than the model says; then straight driving as predicted
    t = np.arange(0.0, 60.0, 0.1)
    pivot = t < 20.0
    w = np.where(pivot, 0.6 * np.sign(np.sin(2 * np.pi * t / 6.0) + 1e-9), 0.0)
    v = np.where(pivot, 0.0, 0.5)
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    log = InteractionLog(t, v, w, np.ones_like(t), np.ones_like(t), ta, np.full(ta.size, 9.81),
                         meta=LogMeta(source="g/pivot.csv", ground_label="g"))
    log = _on_base(base, log, offset_a=0.0)
    extra = np.tanh(np.abs(w) / 0.3)[:, None]
    log = dataclasses.replace(log, current_left_a=log.current_left_a + extra[:, 0],
                              current_right_a=log.current_right_a + extra[:, 0])
    head = _head(log, 20.0)
    regime = base.adapt(head, method="regime")
    partition = base.adapt(head)  # the default
    straight = ~pivot
    moved = {k: (m.predict(log) - base.predict(log))[straight].mean(axis=0) for k, m in
             (("regime", regime), ("partition", partition))}
    assert np.all(moved["regime"] > 0.2)  # the shared offset carries the pivot's residual onto straights
    assert np.all(np.abs(moved["partition"]) < 0.02)  # straight driving keeps its prior: no correction
    turned = (partition.predict(head) - base.predict(head)).mean(axis=0)
    assert np.all((turned > 0.3) & (turned < 1.0))  # the pivots are corrected (20 s of data against a 20 s prior)
    assert np.all(np.abs(partition.coefficients_[:, 0]) < 0.02)  # the straight level


def test_regime_gain_scales_the_prediction_of_the_regime_the_prefix_drove(base):
    # a ground 30 % harder to drive on (every current scaled), turns only after 45 s: the first 40 s drive straight
    run = _log(8, turns_after_s=45.0, duration_s=90.0)
    pred = base.predict(run)
    run = dataclasses.replace(run, current_left_a=1.3 * pred[:, 0], current_right_a=1.3 * pred[:, 1])
    head = _head(run, 40.0)
    adapted = base.adapt(head, method="regime_gain", prior_s=2.0, shrink="none")
    straight, turning = adapted.coefficients_[:, 0], adapted.coefficients_[:, 1]
    assert np.all((straight > 0.27) & (straight < 0.3))  # the 30 %, shrunk a little by the ridge
    assert np.all(np.abs(turning) < 0.01)  # no turn seen: no turning gain
    np.testing.assert_allclose(adapted.predict(head), base.predict(head) * (1.0 + straight)[None, :], rtol=1e-9)
    m = np.tanh(np.abs(run.omega_radps) / 0.3)[:, None]  # the turns after 45 s keep the prediction's own scale
    np.testing.assert_allclose(adapted.predict(run), pred * (1.0 + (1.0 - m) * straight + m * turning), rtol=1e-9)
    back = AdaptedCurrentModel.from_record(adapted.to_record(), "regime_gain")
    np.testing.assert_array_equal(back.predict(run), adapted.predict(run))


def test_gain_method_is_measured_over_predicted_charge_of_the_prefix(base):
    run = _log(6, offset_a=0.4)
    head = _head(run, 15.0)
    adapted = base.adapt(head, method="gain")
    pred = base.predict(head)
    expect = np.trapezoid(np.column_stack([head.current_left_a, head.current_right_a]), head.time_s, axis=0) / \
        np.trapezoid(pred, head.time_s, axis=0)
    np.testing.assert_allclose(adapted.coefficients_[:, 0], expect)
    np.testing.assert_allclose(adapted.predict(run), base.predict(run) * expect[None, :])


def test_gain_offset_and_prior_strength(base):
    run = _log(7, offset_a=0.8)
    weak = base.adapt(_head(run, 30.0), method="gain_offset", prior_s=0.1)
    strong = base.adapt(_head(run, 30.0), method="gain_offset", prior_s=1e6)
    assert _charge_error_pct(run, weak.predict(run), 30.0) < 3.0
    np.testing.assert_allclose(strong.predict(run), base.predict(run), atol=1e-3)


def test_adapting_an_adapted_model_refits_on_the_base_without_stacking(base):
    run = _log(8, turn_extra_a=1.0)
    first = base.adapt(_head(run, 20.0))
    second = first.adapt(_head(run, 20.0))
    assert second.base_model is base
    np.testing.assert_allclose(second.predict(run), first.predict(run))


def test_correct_equals_predict_and_checks_its_input(base):
    run = _log(9, turn_extra_a=1.0)
    adapted = base.adapt(_head(run, 20.0))
    np.testing.assert_allclose(adapted.correct(run, base.predict(run)), adapted.predict(run))
    with pytest.raises(InvalidParameterError, match="base_prediction must have shape"):
        adapted.correct(run, np.zeros((3, 2)))
    with pytest.raises(InvalidParameterError, match="NaN"):
        adapted.correct(run, np.full((len(run), 2), np.nan))
    with pytest.raises(NotFittedError):
        AdaptedCurrentModel(base).correct(run, base.predict(run))


def test_predictions_are_clamped_at_zero_when_the_data_never_went_negative(base):
    run = _log(10, offset_a=-5.0)  # negative currents in the data: no clamp
    assert not base.adapt(_head(run, 20.0)).nonnegative_
    adapted = base.adapt(_head(_log(11, offset_a=-0.3), 20.0))
    assert adapted.nonnegative_ and np.all(adapted.predict(run) >= 0.0)


def test_save_and_load_round_trip(base, tmp_path):
    run = _log(12, turn_extra_a=1.0)
    adapted = base.adapt(_head(run, 20.0))
    loaded = load_current_model(adapted.save(tmp_path / "adapted.zip"))
    assert isinstance(loaded, AdaptedCurrentModel) and isinstance(loaded.base, LinearCurrentModel)
    np.testing.assert_allclose(loaded.predict(run), adapted.predict(run))
    clone = adapted.clone()
    assert not clone.is_fitted and clone.base is base


def test_forged_coefficients_are_a_file_format_error(base):
    adapted = base.adapt(_head(_log(13), 20.0))
    rec = adapted.to_record()
    bad = ModelRecord(rec.model_class, rec.params, {**rec.state, "coefficients": np.zeros((2, 7))})
    with pytest.raises(FileFormatError, match="coefficients"):
        AdaptedCurrentModel.from_record(bad)
    unknown = ModelRecord(rec.model_class, {**rec.params, "base": {**rec.params["base"], "model_class": "Nope"}}, rec.state)
    with pytest.raises(FileFormatError):
        AdaptedCurrentModel.from_record(unknown)


def test_too_little_data_is_a_data_error_naming_the_minimum(base):
    run = _log(14)
    before = base.predict(run)
    with pytest.raises(DataError, match=r"at least 5 s and 10 drive samples.*min_seconds.*got 1.9 s"):
        base.adapt(_head(run, 2.0))
    with pytest.raises(DataError, match="at least 30 s"):
        base.adapt(_head(run, 20.0), min_seconds=30.0)
    few = run.slice(0.0, 0.1 * (MIN_ADAPT_SAMPLES - 2))
    with pytest.raises(DataError, match="drive samples"):
        base.adapt(few, min_seconds=0.0)
    np.testing.assert_array_equal(base.predict(run), before)  # a failed adaptation changes nothing


def test_gain_on_a_base_that_predicts_no_charge_is_a_data_error():
    zero = _log(15, offset_a=0.0)
    flat = InteractionLog(zero.time_s, zero.v_mps, zero.omega_radps, np.zeros(len(zero)), np.zeros(len(zero)),
                          zero.accel_time_s, zero.accel_z_mps2, meta=zero.meta)
    model = LinearCurrentModel().fit(flat)
    with pytest.raises(DataError, match="method='regime'"):
        model.adapt(_head(zero, 20.0), method="gain")


@pytest.mark.parametrize(("options", "error", "match"), [
    ({"method": "retrain"}, UnknownNameError, "method"),
    ({"prior_s": 0.0}, InvalidParameterError, "prior_s"),
    ({"prior_s": float("nan")}, InvalidParameterError, "prior_s"),
    ({"turn_scale_radps": -1.0}, InvalidParameterError, "turn_scale_radps"),
    ({"min_seconds": -1.0}, InvalidParameterError, "min_seconds"),
    ({"method": 3}, UnknownNameError, "method"),
])
def test_bad_options(base, options, error, match):
    with pytest.raises(error, match=match):
        base.adapt(_head(_log(16), 20.0), **options)


def test_bad_models_and_logs(base):
    head = _head(_log(17), 20.0)
    with pytest.raises(InvalidParameterError, match="fitted CurrentModel"):
        LinearCurrentModel().adapt(head)
    with pytest.raises(InvalidParameterError, match="log_prefix"):
        base.adapt([])
    with pytest.raises(InvalidParameterError, match="log_prefix"):
        base.adapt("run.csv")
    with pytest.raises(InvalidParameterError, match=r"unknown adaptation option\(s\) \['methd'\]"):
        base.adapt(head, methd="gain")


def test_the_adaptive_loop_can_adapt_instead_of_refitting(base):
    from planner.missions import adapted_model, validation_error

    run = _on_base(base, _log(18), offset_a=0.8)
    drive, held = run.slice(0.0, 30.0), run.slice(30.0, 60.0)
    upd = adapted_model(base, [drive])
    assert upd is not None and validation_error(upd, [held]) < 0.5 * validation_error(base, [held])
    assert adapted_model(base, [run.slice(0.0, 2.0)]) is None  # too short: keep the serving model
    assert adapted_model(LinearCurrentModel(), [drive]) is None  # not fitted: nothing to adapt
    with pytest.raises(UnknownNameError):
        adapted_model(base, [drive], method="retrain")


# ------------------------------------------------------- the Bayesian update of an interval
@pytest.fixture(scope="module")
def two_ground_estimator():
    return fit_two_ground_estimator()


def test_bayes_update_learns_a_new_ground_offset_and_narrows_its_interval(two_ground_estimator):
    est, _ = two_ground_estimator
    new_runs = [interval_log(30 + s, "c", vibration=0.5, offset_a=2.0) for s in range(2)]
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



# ------------------------------------------------------- the shrink of a point update by its evidence
def _with_currents(log: InteractionLog, currents: np.ndarray) -> InteractionLog:
    return dataclasses.replace(log, current_left_a=currents[:, 0], current_right_a=currents[:, 1])


def test_prior_shrink_keeps_a_noise_prefix_and_follows_a_large_offset_by_the_learned_share(two_ground_estimator):
    est, _ = two_ground_estimator
    drive = interval_log(40, "c", vibration=0.5).slice(0.0, 20.0)  # a ground the model never drove
    base = est.predict(drive)
    rng = np.random.default_rng(7)
    noise = _with_currents(drive, base + 0.1 * rng.standard_normal(base.shape))  # the prefix is pure noise
    offset = _with_currents(drive, base + 3.0)  # 3 A off on every sample
    quiet = AdaptedCurrentModel(est, scope="ground").fit(noise)
    clear = AdaptedCurrentModel(est, scope="ground").fit(offset)
    assert quiet.shrink == "prior"
    # the share is the learned one: what the ground's offset adds to the prefix's charge over everything that does
    iv, t = est.interval_, drive.time_s
    ground = np.trapezoid(iv.run_sd_a(drive, base, known=True, cov=iv.new_ground_cov), t, axis=0) ** 2
    run = np.trapezoid(iv.run_sd_a(drive, base, known=True), t, axis=0) ** 2
    noise_var = np.sum(iv.sample_sd(drive) ** 2 * np.gradient(t)[:, None], axis=0) * iv.correlation_s
    np.testing.assert_allclose(clear.shrink_, ground / (ground + run + noise_var), rtol=1e-9)
    np.testing.assert_array_equal(quiet.shrink_, clear.shrink_)  # not read off one prefix's residual
    assert np.all((clear.shrink_ > 0.1) & (clear.shrink_ < 1.0))
    later = interval_log(41, "c", vibration=0.5)
    moved = clear.predict(later) - est.predict(later)
    assert np.all(np.abs(quiet.predict(later) - est.predict(later)).mean(axis=0) < 0.05)  # noise: the forecast stays
    plain = AdaptedCurrentModel(est, scope="ground", shrink="none").fit(offset)
    assert np.all(moved.mean(axis=0) > 1.0)  # an offset: followed, by the share it carries
    np.testing.assert_allclose(moved, (plain.predict(later) - est.predict(later)) * clear.shrink_, atol=1e-9)
    same_run = AdaptedCurrentModel(est, scope="run").fit(offset)
    assert np.all(same_run.shrink_ > clear.shrink_)  # a run's own offset carries to the rest of that run


def test_prior_shrink_learns_nothing_of_a_ground_the_model_drove(two_ground_estimator):
    est, train = two_ground_estimator
    prefix = _with_currents(train[1].slice(0.0, 20.0), est.predict(train[1].slice(0.0, 20.0)) + 3.0)
    other_runs = AdaptedCurrentModel(est, scope="ground").fit(prefix)
    np.testing.assert_array_equal(other_runs.shrink_, [0.0, 0.0])  # its offset is known: zero
    np.testing.assert_allclose(other_runs.predict(train[2]), est.predict(train[2]))
    # the rest of the prefix's own run: its offset carries by the run part's share of the prefix's evidence
    same_run = AdaptedCurrentModel(est, scope="run").fit(prefix)
    _, noise, run, ground = same_run.evidence_
    np.testing.assert_array_equal(ground, [0.0, 0.0])
    np.testing.assert_allclose(same_run.shrink_, run / (run + noise), rtol=1e-9)
    assert np.all(same_run.shrink_ > 0.1)


def test_prior_shrink_without_a_learned_ground_spread_reads_the_evidence(two_ground_estimator):
    est, _ = two_ground_estimator
    one_ground = copy.copy(est)  # as if trained on one ground: no ground spread learned
    one_ground.interval_ = dataclasses.replace(est.interval_, new_ground_cov=None, n_grounds=0)
    far = interval_log(40, "c", vibration=0.5, offset_a=3.0).slice(0.0, 20.0)
    prior = AdaptedCurrentModel(one_ground, scope="ground").fit(far)
    evidence = AdaptedCurrentModel(one_ground, scope="ground", shrink="evidence").fit(far)
    np.testing.assert_array_equal(prior.shrink_, evidence.shrink_)
    assert np.all(prior.shrink_ > 0.8)  # a clear offset on a new ground is followed, not ignored


def test_evidence_shrink_keeps_a_residual_within_noise_and_follows_a_clear_one(two_ground_estimator):
    est, train = two_ground_estimator
    known = train[1].slice(0.0, 20.0)  # a ground the model was fitted on: the residual is noise
    plain = AdaptedCurrentModel(est, method="regime", shrink="none").fit(known)
    shrunk = AdaptedCurrentModel(est, method="regime", shrink="evidence", scope="ground").fit(known)
    assert np.all(plain.shrink_ == 1.0)
    assert np.all(shrunk.shrink_ < 0.5)
    assert np.all(np.abs(shrunk.coefficients_) <= np.abs(plain.coefficients_) + 1e-12)
    far = interval_log(40, "c", vibration=0.5, offset_a=3.0).slice(0.0, 20.0)  # 3 A off on every sample
    clear = AdaptedCurrentModel(est, method="regime", shrink="evidence", scope="ground").fit(far)
    assert np.all(clear.shrink_ > 0.8)
    run = AdaptedCurrentModel(est, method="regime", shrink="evidence", scope="run").fit(far)
    assert np.all(run.shrink_ >= clear.shrink_)  # a run's own offset carries to the rest of that run


def test_a_file_from_before_the_shrink_choices_keeps_its_update(two_ground_estimator, tmp_path):
    est, train = two_ground_estimator
    adapted = AdaptedCurrentModel(est, method="gain", shrink="evidence", scope="ground").fit(train[0].slice(0.0, 20.0))
    rec = adapted.to_record()
    for old, now in ((True, "evidence"), (False, "none")):
        back = AdaptedCurrentModel.from_record(dataclasses.replace(rec, params={**rec.params, "shrink": old}), "old")
        assert back.shrink == now
    np.testing.assert_allclose(back.predict(train[2]), adapted.predict(train[2]))


def test_shrink_moves_a_gain_from_one_and_is_saved(two_ground_estimator, tmp_path):
    est, train = two_ground_estimator
    prefix = train[0].slice(0.0, 20.0)
    plain = AdaptedCurrentModel(est, method="gain", shrink="none").fit(prefix)
    shrunk = AdaptedCurrentModel(est, method="gain", shrink="evidence", scope="ground").fit(prefix)
    np.testing.assert_allclose(shrunk.coefficients_[:, 0] - 1.0, (plain.coefficients_[:, 0] - 1.0) * shrunk.shrink_)
    path = tmp_path / "shrunk.zip"
    shrunk.save(path)
    back = load_current_model(path)
    np.testing.assert_array_equal(back.shrink_, shrunk.shrink_)
    np.testing.assert_allclose(back.predict(train[2]), shrunk.predict(train[2]))


def test_shrink_is_ignored_without_an_interval_and_by_bayes(base, two_ground_estimator):
    run = _log(3, offset_a=1.0)
    assert np.all(base.adapt(_head(run, 20.0)).shrink_ == 1.0)  # a model without an interval
    est, train = two_ground_estimator
    bayes = AdaptedCurrentModel(est, method="bayes", shrink="prior").fit(train[1].slice(0.0, 20.0))
    assert np.all(bayes.shrink_ == 1.0)
    with pytest.raises(UnknownNameError, match="shrink"):
        base.adapt(_head(run, 20.0), shrink=True)  # one of ADAPT_SHRINKS, not a flag
