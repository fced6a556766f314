"""Tests of energy.models.estimator: the vibration-conditioned current estimator (its net, trainer and config in test_models_{net,training,config}.py)."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import torch
from interval_samples import fit_two_ground_estimator

from energy import (
    EstimatorConfig,
    InteractionLog,
    LogMeta,
    VibrationCurrentEstimator,
    estimator_preset,
    load_current_model,
    read_borealtc,
)
from energy.features import window_starts
from energy.models import TrainConfig, train_network
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "borealtc"


def _log(seed: int, gain: float = 1.0, vibration_mps2: float = 0.3, duration_s: float = 40.0,
         drive_hz: float = 10.0, accel_hz: float = 100.0) -> InteractionLog:
    """Known relation: I_side = gain * (0.5 + 4 |v| + 3 (turning towards the other side)
    + 1 (turning towards this side)); vertical vibration of white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 1.0 / drive_hz)
    p1, p2 = rng.uniform(0, 2 * np.pi, 2)
    v = 0.45 + 0.35 * np.sin(2 * np.pi * t / 7.0 + p1)
    w = 0.6 * np.sin(2 * np.pi * t / 5.0 + p2)
    left = gain * (0.5 + 4.0 * v + 3.0 * np.maximum(-w, 0) + np.maximum(w, 0))
    right = gain * (0.5 + 4.0 * v + 3.0 * np.maximum(w, 0) + np.maximum(-w, 0))
    ta = np.arange(0.0, t[-1] + 0.5 / accel_hz, 1.0 / accel_hz)
    az = 9.81 + vibration_mps2 * rng.standard_normal(ta.size)
    return InteractionLog(t, v, w, left, right, ta, az, meta=LogMeta(source=f"synthetic-{seed}", ground_label="g"))


def _small(**changes) -> EstimatorConfig:
    base = dict(window_s=0.5, hidden_sizes=(32, 32), n_members=1, max_epochs=80, patience=15, learning_rate=3e-3,
                batch_size=32, train_stride_s=0.3, dropout=0.0, physics_prior=None)
    base.update(changes)
    return estimator_preset("default").replace(**base)


def _r2(truth: np.ndarray, pred: np.ndarray) -> float:
    return 1.0 - float(np.sum((truth - pred) ** 2) / np.sum((truth - truth.mean()) ** 2))


def _truth(log: InteractionLog) -> np.ndarray:
    return np.column_stack([log.current_left_a, log.current_right_a])


def test_estimator_learns_a_known_relation_and_tells_left_from_right():
    train = [_log(0), _log(1)]
    test = _log(2)
    est = VibrationCurrentEstimator(_small(), seed=0).fit(train)
    pred = est.predict(test)
    assert _r2(_truth(test), pred) > 0.9
    # in a left turn (omega > 0) the right side draws more; the model must know the sign
    turning = test.omega_radps > 0.4
    truth_gap = np.mean(test.current_right_a[turning] - test.current_left_a[turning])
    assert np.mean(pred[turning, 1] - pred[turning, 0]) > 0.7 * truth_gap > 0.5
    assert est.score(test) > 0.9


def test_absolute_inputs_cannot_tell_left_from_right():
    train = [_log(0), _log(1)]
    test = _log(2)

    def gaps(pred):  # right minus left, in left turns and in right turns
        left_turn, right_turn = test.omega_radps > 0.4, test.omega_radps < -0.4
        return (np.mean(pred[left_turn, 1] - pred[left_turn, 0]), np.mean(pred[right_turn, 1] - pred[right_turn, 0]))

    truth = gaps(_truth(test))
    assert truth[0] > 0.5 and truth[1] < -0.5
    signed = gaps(VibrationCurrentEstimator(_small(max_epochs=40), seed=0).fit(train).predict(test))
    assert signed[0] > 0.5 * truth[0] and signed[1] < 0.5 * truth[1]
    absolute = gaps(VibrationCurrentEstimator(_small(max_epochs=40, absolute_inputs=True), seed=0).fit(train).predict(test))
    assert abs(absolute[0] - absolute[1]) < 0.3 * (truth[0] - truth[1])  # mirror turns look alike


def test_vibration_features_identify_the_ground():
    # two grounds: the rough one doubles the current; only the vibration tells them apart
    train = [_log(0, 1.0, 0.1), _log(1, 2.0, 1.5), _log(3, 1.0, 0.1), _log(4, 2.0, 1.5)]
    tests = [_log(5, 1.0, 0.1), _log(6, 2.0, 1.5)]
    with_vib = VibrationCurrentEstimator(_small(), seed=0).fit(train)
    blind = VibrationCurrentEstimator(_small(local_spectrum=False, run_features="none"), seed=0).fit(train)
    assert with_vib.score(tests) > 0.85
    assert with_vib.score(tests) > blind.score(tests) + 0.2


def test_physics_prior_carries_what_the_networks_have_not_learned():
    # currents of a Husky-like physics law: the fitted prior explains them almost alone
    from energy import PhysicsEnergyModel, ground_preset, robot_preset

    def physics_log(seed):
        base = _log(seed)
        model = PhysicsEnergyModel(robot_preset("husky"), ["coulomb_friction", "turning_resistance", "inertia"])
        res = model.power(base.v_mps, base.omega_radps, ground_preset("grass"),
                          accel_mps2=np.gradient(base.v_mps, base.time_s), time_s=base.time_s)
        cur = np.maximum(0.7 + res.motor_current_a * np.sign(res.motor_speed_radps), 0.0)
        return InteractionLog(base.time_s, base.v_mps, base.omega_radps, cur[:, 0], cur[:, 1],
                              base.accel_time_s, base.accel_z_mps2, meta=base.meta)

    train, test = [physics_log(0), physics_log(1)], physics_log(2)
    quick = dict(max_epochs=2, patience=None)
    with_prior = VibrationCurrentEstimator(_small(physics_prior="husky", **quick), seed=0).fit(train)
    assert with_prior.physics_ is not None and with_prior.physics_.is_fitted
    assert with_prior.score(test) > 0.9
    without = VibrationCurrentEstimator(_small(physics_prior=None, **quick), seed=0).fit(train)
    assert without.physics_ is None
    assert without.score(test) < with_prior.score(test) - 0.2
    with pytest.raises(UnknownNameError, match="physics_prior"):
        EstimatorConfig(physics_prior="tank")
    with pytest.raises(InvalidParameterError, match="absolute_currents"):
        EstimatorConfig(physics_prior="husky", absolute_currents=True)


def test_paper_preset_reproduces_the_source_network_shape():
    cfg = estimator_preset("paper")
    assert (cfg.window_s, cfg.rate_hz, cfg.n_spectrum_bins, cfg.hidden_sizes) == (0.1, 100.0, 8000, (100, 100, 100))
    est = VibrationCurrentEstimator(cfg.replace(max_epochs=1), seed=0).fit(_log(0, duration_s=20.0))
    net = est.networks_[0]
    assert net.n_inputs == 8020 and net.config.n_outputs == 20
    assert sum(isinstance(m, torch.nn.ReLU) for m in net.modules()) == 3
    assert (est.window_.length_samples, est.window_.length_s) == (10, pytest.approx(0.1))
    assert est.normalisers_["v"].absolute and est.normalisers_["current"].absolute


def _n_windows(log: InteractionLog, est: VibrationCurrentEstimator) -> int:
    grid = log.resample(est.rate_hz_, est.config_.resample_method)
    return window_starts(len(grid), est.window_).size


def test_paper_preset_trains_on_every_window_of_its_runs():
    # no early stopping in the paper: nothing is held out for validation
    assert estimator_preset("paper").validation_fraction == 0.0
    logs = [_log(0, duration_s=12.0), _log(1, duration_s=9.0)]
    est = VibrationCurrentEstimator(estimator_preset("paper").replace(max_epochs=1, n_spectrum_bins=400), seed=0).fit(logs)
    assert est.n_train_windows_ == sum(_n_windows(lg, est) for lg in logs) == 120 + 90
    assert est.history_[0].validation_loss == ()


def test_no_validation_tail_works_end_to_end(tmp_path):
    cfg = _small(max_epochs=3, patience=None, validation_fraction=0.0)
    est = VibrationCurrentEstimator(cfg, seed=0).fit(_log(0))
    assert est.n_train_windows_ == _n_windows(_log(0), est)
    assert est.history_[0].validation_loss == () and est.history_[0].best_epoch == 2
    held_out = VibrationCurrentEstimator(cfg.replace(validation_fraction=0.2), seed=0).fit(_log(0))
    assert held_out.n_train_windows_ < est.n_train_windows_
    again = VibrationCurrentEstimator.load(est.save(tmp_path / "m.pt"))
    assert again.config_.validation_fraction == 0.0
    assert np.array_equal(again.predict(_log(2)), est.predict(_log(2)))


def test_predict_holds_the_ends_outside_the_imu_overlap():
    log = _log(2)
    late = (log.accel_time_s >= 5.0) & (log.accel_time_s <= 30.0)  # IMU from 5 s to 30 s of 40 s
    short_imu = InteractionLog(log.time_s, log.v_mps, log.omega_radps, log.current_left_a, log.current_right_a,
                               log.accel_time_s[late], log.accel_z_mps2[late], meta=log.meta)
    est = VibrationCurrentEstimator(_small(max_epochs=2, patience=None, clip_output=False), seed=0).fit(_log(0))
    pred = est.predict(short_imu)
    before, after = short_imu.time_s < 5.0, short_imu.time_s > 30.0
    assert before.sum() == 50 and after.sum() == 99
    assert np.ptp(pred[before], axis=0).max() == 0.0 and np.ptp(pred[after], axis=0).max() == 0.0  # held
    inside = pred[~before & ~after]
    assert pred[before][0] == pytest.approx(inside[0], abs=1e-9)  # the nearest grid prediction
    assert pred[after][0] == pytest.approx(inside[-1], abs=1e-9)
    assert np.ptp(inside, axis=0).min() > 0.1  # inside the overlap the motion matters


def test_default_works_at_the_drive_rate_with_windows_in_seconds():
    log = _log(0, drive_hz=6.5, duration_s=30.0)
    est = VibrationCurrentEstimator(_small(window_s=1.0, train_stride_s=0.1, max_epochs=2, patience=None), seed=0).fit(log)
    assert est.rate_hz_ == pytest.approx(6.5)
    assert est.window_.length_samples in (6, 7)  # 1 s at 6.5 Hz, rounded
    assert est.window_.length_s == pytest.approx(1.0, abs=0.08) and est.window_.stride_samples == 1
    assert est.band_edges_hz_.size == est.config_.n_bands + 1


def test_output_clipped_to_training_range_only_when_asked():
    train = _log(0)
    extreme = _log(1)
    extreme = InteractionLog(extreme.time_s, extreme.v_mps * 5.0, extreme.omega_radps, extreme.current_left_a,
                             extreme.current_right_a, extreme.accel_time_s, extreme.accel_z_mps2)
    clipped = VibrationCurrentEstimator(_small(), seed=0).fit(train)
    pred = clipped.predict(extreme)
    lo, hi = clipped.current_range_a_
    assert np.all(pred >= lo - 1e-12) and np.all(pred <= hi + 1e-12)
    free = VibrationCurrentEstimator(_small(clip_output=False), seed=0).fit(train)
    assert np.any(free.predict(extreme) > hi)


def test_early_stopping_restores_best_epoch_and_ensemble_has_members():
    est = VibrationCurrentEstimator(_small(n_members=3, max_epochs=300, patience=3, learning_rate=0.05), seed=1).fit(_log(0))
    assert len(est.networks_) == len(est.history_) == 3
    for h in est.history_:
        assert len(h.validation_loss) == len(h.train_loss)
        assert h.best_epoch == int(np.argmin(h.validation_loss))
        assert h.stopped_early == (len(h.train_loss) < 300)
    assert any(h.stopped_early for h in est.history_)


def test_different_seeds_give_different_models():
    a = VibrationCurrentEstimator(_small(max_epochs=5, patience=None), seed=0).fit(_log(0)).predict(_log(1))
    b = VibrationCurrentEstimator(_small(max_epochs=5, patience=None), seed=1).fit(_log(0)).predict(_log(1))
    assert not np.array_equal(a, b)


def test_thread_setting_is_restored():
    original = torch.get_num_threads()
    known = 3 if original != 3 else 2  # a count the estimator's own setting (1) differs from
    torch.set_num_threads(known)
    try:
        est = VibrationCurrentEstimator(_small(max_epochs=1, patience=None), seed=0, n_threads=1).fit(_log(0))
        assert torch.get_num_threads() == known
        est.predict(_log(1))
        assert torch.get_num_threads() == known
    finally:
        torch.set_num_threads(original)


def test_seed_follows_the_one_seed_rule():
    for bad in (-1, 2**32, 1.5, True, "7"):
        with pytest.raises(InvalidParameterError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
            VibrationCurrentEstimator(_small(max_epochs=1, patience=None), seed=bad).fit(_log(0))
    est = VibrationCurrentEstimator(_small(max_epochs=1, patience=None), seed=None).fit(_log(0))  # fresh entropy
    assert est.is_fitted
    assert VibrationCurrentEstimator(_small(max_epochs=1, patience=None), seed=2**32 - 1).fit(_log(0)).is_fitted
    with pytest.raises(InvalidParameterError, match="seed"):
        train_network(torch.nn.Linear(1, 1), None, None, TrainConfig(), seed=-5)


def test_refit_starts_from_scratch():
    est = VibrationCurrentEstimator(_small(max_epochs=3, patience=None), seed=0)
    est.fit(_log(0))
    first = est.predict(_log(2))
    est.fit([_log(1, gain=3.0)])
    assert np.mean(est.predict(_log(2))) > np.mean(first)
    assert est.fit(_log(0)).predict(_log(2)) == pytest.approx(first)


def test_bad_parameters_and_short_logs_raise():
    with pytest.raises(UnknownNameError, match="estimator preset"):
        VibrationCurrentEstimator("fancy").fit(_log(0))
    with pytest.raises(InvalidParameterError, match="seed"):
        VibrationCurrentEstimator(_small(), seed=-1).fit(_log(0))
    with pytest.raises(InvalidParameterError, match="InteractionLog"):
        VibrationCurrentEstimator(_small()).fit([])
    with pytest.raises(DataError, match="shorter than one window"):
        VibrationCurrentEstimator(_small(window_s=5.0, patience=None, validation_fraction=0.0)).fit(_log(0, duration_s=3.0))
    with pytest.raises(UnknownNameError, match="run_features"):
        EstimatorConfig(run_features="wavelets")
    with pytest.raises(InvalidParameterError, match="validation_fraction"):
        EstimatorConfig(patience=5, validation_fraction=0.0)
    with pytest.raises(InvalidParameterError, match="hidden_sizes"):
        EstimatorConfig(hidden_sizes=())
    with pytest.raises(UnknownNameError, match="loss"):
        TrainConfig(loss="l1")
    est = VibrationCurrentEstimator(_small(max_epochs=1, patience=None)).fit(_log(0))
    assert est.is_fitted and len(est.networks_) == len(est.history_) == 1
    assert len(est.history_[0].train_loss) == 1
    failed = VibrationCurrentEstimator(_small(window_s=5.0, patience=None, validation_fraction=0.0))
    with pytest.raises(DataError):
        failed.fit(_log(0, duration_s=3.0))
    assert not failed.is_fitted  # nothing half-fitted left behind


def test_fits_a_real_borealtc_run():
    if not DATA.is_dir():
        pytest.skip("BorealTC sample not found beside the repository (../shared/data/borealtc)")
    logs = read_borealtc(DATA, grounds=["FLOORING"])
    short = sorted(logs, key=lambda lg: lg.duration_s)[:3]
    est = VibrationCurrentEstimator(_small(window_s=1.0, max_epochs=30), seed=0).fit(short[:2])
    assert est.rate_hz_ == pytest.approx(6.5, rel=0.01)
    pred = est.predict(short[2])
    assert pred.shape == (len(short[2]), 2) and np.all(np.isfinite(pred))
    assert np.all(pred >= 0.0)  # clipped to the (non-negative) training range


def _stopping(seed: int) -> InteractionLog:
    """_log with the robot standing still (speeds exactly 0) for 6 s in the middle, where the sensor logs
    0.3 A left and 0.6 A right."""
    log = _log(seed)
    t = log.time_s
    still = (t >= 17.0) & (t < 23.0)
    v, w = np.where(still, 0.0, log.v_mps), np.where(still, 0.0, log.omega_radps)
    left = np.where(still, 0.3, log.current_left_a)
    right = np.where(still, 0.6, log.current_right_a)
    return InteractionLog(t, v, w, left, right, log.accel_time_s, log.accel_z_mps2, meta=log.meta)


@pytest.mark.parametrize("prior", [None, "husky"])
def test_standing_still_is_predicted_at_the_rest_level_not_by_the_networks(prior, tmp_path):
    from energy.logs import rest_samples

    train, test = [_stopping(0), _stopping(1)], _stopping(2)
    est = VibrationCurrentEstimator(_small(physics_prior=prior, max_epochs=3, patience=None), seed=0).fit(train)
    np.testing.assert_allclose(est.rest_current_a_, [0.3, 0.6], atol=1e-9)
    rest = rest_samples(test)
    assert 40 <= rest.sum() < 60  # the 6 s stop at 10 Hz, less its first and last samples
    np.testing.assert_allclose(est.predict(test)[rest], np.tile([0.3, 0.6], (rest.sum(), 1)), atol=1e-9)
    est.save(tmp_path / "m.zip")
    np.testing.assert_array_equal(load_current_model(tmp_path / "m.zip").predict(test), est.predict(test))


# ------------------------------------------------------- estimator with an interval
@pytest.fixture(scope="module")
def two_ground_estimator():
    return fit_two_ground_estimator()


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

