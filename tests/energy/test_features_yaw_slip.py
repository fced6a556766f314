"""The yaw-rate slip signal: the feature itself, its hostile inputs, and the estimator option."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from energy import EstimatorConfig, InteractionLog, VibrationCurrentEstimator, estimator_preset, load_current_model
from energy.features import YAW_SLIP_FEATURES, WindowSpec, yaw_slip_features
from terrain import DataError, InvalidParameterError

SPEC = WindowSpec.from_seconds(1.0, rate_hz=10.0)
TINY = dict(n_members=1, max_epochs=3, hidden_sizes=(8,), patience=None, validation_fraction=0.0)


def _streams(omega: float, gyro: float, n: int = 20):
    return np.arange(n) / 10.0, np.full(n, omega), np.arange(10 * n) / 100.0, np.full(10 * n, gyro)


def test_skid_fraction_and_deficit_of_a_steady_turn():
    out = yaw_slip_features(*_streams(1.0, 0.6), SPEC)
    assert out.shape == (2, len(YAW_SLIP_FEATURES))
    # 1 - (0.6 + 0.1^2) / (1 + 0.1^2): 40 % of the wheels' rotation lost, shrunk a little by the floor
    assert out[:, 0] == pytest.approx(1 - 0.61 / 1.01)
    assert out[:, 1] == pytest.approx(0.4)


def test_turning_the_other_way_gives_the_same_slip():
    left = yaw_slip_features(*_streams(0.8, 0.5), SPEC)
    right = yaw_slip_features(*_streams(-0.8, -0.5), SPEC)
    assert np.allclose(left, right)


def test_no_skid_and_no_turn():
    assert np.allclose(yaw_slip_features(*_streams(0.7, 0.7), SPEC), 0.0)
    stuck = yaw_slip_features(*_streams(1.0, 0.0), SPEC)
    assert stuck[:, 0] == pytest.approx(1 - 0.01 / 1.01) and stuck[:, 1] == pytest.approx(1.0)


def test_straight_driving_with_a_noisy_gyro_is_no_slip():
    rng = np.random.default_rng(1)
    t, w, tg, _ = _streams(0.0, 0.0, n=100)
    w = rng.normal(0.0, 0.01, t.size)  # wheel speeds nearly equal
    g = rng.normal(0.0, 0.05, tg.size)  # gyro noise and vibration
    out = yaw_slip_features(t, w, tg, g, SPEC)
    assert np.all(np.abs(out[:, 0]) < 0.05), out[:, 0].round(3)  # a plain ratio g/omega would be huge


def test_gyro_vibration_is_averaged_over_each_drive_period():
    t, w, tg, g = _streams(1.0, 0.6, n=40)
    shaky = g + 0.5 * np.sin(2 * np.pi * 30.0 * tg)  # 30 Hz: three periods per drive sample of 0.1 s
    assert np.allclose(yaw_slip_features(t, w, tg, shaky, SPEC), yaw_slip_features(t, w, tg, g, SPEC), atol=0.02)


def test_given_window_starts_are_used():
    t, w, tg, g = _streams(1.0, 0.6, n=30)
    out = yaw_slip_features(t, w, tg, g, SPEC, starts=np.array([0, 5, 20]))
    assert out.shape == (3, 2)


@pytest.mark.parametrize(
    "change, error, message",
    [({"omega_radps": np.ones(19)}, InvalidParameterError, "pairs of one length"),
     ({"gyro_z_radps": np.ones(7)}, InvalidParameterError, "pairs of one length"),
     ({"gyro_time_s": np.arange(200) / 100.0 + 0.5}, DataError, "outside the gyro record"),
     ({"gyro_time_s": np.array([0.0]), "gyro_z_radps": np.array([0.1])}, DataError, "at least 2 gyro samples"),
     ({"omega_radps": np.r_[np.nan, np.ones(19)]}, InvalidParameterError, "omega_radps"),
     ({"floor_radps": 0.0}, InvalidParameterError, "floor_radps"),
     ({"floor_radps": float("nan")}, InvalidParameterError, "floor_radps")],
)
def test_bad_inputs_are_refused(change, error, message):
    t, w, tg, g = _streams(1.0, 0.6)
    kwargs = dict(time_s=t, omega_radps=w, gyro_time_s=tg, gyro_z_radps=g, spec=SPEC) | change
    with pytest.raises(error, match=message):
        yaw_slip_features(**kwargs)


# ------------------------------------------------------------------ the estimator option
def _log(seed: int, slip: float, with_gyro: bool = True) -> InteractionLog:
    """60 s of turning and straight driving: the body turns (1 - slip) of the wheels' rate and
    the currents grow with the lost yaw rate."""
    rng = np.random.default_rng(seed)
    t = np.arange(600) / 10.0
    omega = 0.4 * np.sin(2 * np.pi * t / 15.0) * (np.sin(2 * np.pi * t / 7.0) > -0.3)
    v = np.full(t.size, 0.4)
    ta = np.arange(6000) / 100.0
    gyro = (1.0 - slip) * np.interp(ta, t, omega) + rng.normal(0.0, 0.02, ta.size)
    accel = 9.81 + rng.normal(0.0, 0.3, ta.size)
    lost = slip * np.abs(omega)
    cur = 2.0 + 8.0 * lost + rng.normal(0.0, 0.1, t.size)
    return InteractionLog(t, v, omega, cur, cur * 1.05, ta, accel, gyro_z_radps=gyro if with_gyro else None)


def test_config_option_is_validated_and_old_configs_read_without_it():
    assert EstimatorConfig().use_yaw_slip is False
    with pytest.raises(InvalidParameterError, match="use_yaw_slip"):
        EstimatorConfig(use_yaw_slip="yes")
    old = EstimatorConfig().to_dict()
    del old["use_yaw_slip"]
    assert EstimatorConfig.from_dict(old).use_yaw_slip is False


def test_the_estimator_takes_the_yaw_slip_and_keeps_it_in_the_file(tmp_path):
    logs = [_log(s, slip) for s, slip in enumerate((0.2, 0.5, 0.3))]
    base = estimator_preset("default").replace(**TINY)
    plain = VibrationCurrentEstimator(base, seed=0, n_threads=1).fit(logs)
    yaw = VibrationCurrentEstimator(base.replace(use_yaw_slip=True), seed=0, n_threads=1).fit(logs)
    assert yaw.networks_[0].config.n_window_inputs == plain.networks_[0].config.n_window_inputs + 2
    assert set(yaw.normalisers_) - set(plain.normalisers_) == {"yaw"}
    test = _log(7, 0.4)
    pred = yaw.predict(test)
    assert pred.shape == (len(test), 2) and np.all(np.isfinite(pred))
    loaded = load_current_model(yaw.save(tmp_path / "yaw.zip"))
    assert loaded.config_.use_yaw_slip and np.array_equal(loaded.predict(test), pred)


def test_a_log_without_gyro_is_refused_naming_the_option():
    logs = [_log(0, 0.3), _log(1, 0.4)]
    base = estimator_preset("default").replace(use_yaw_slip=True, **TINY)
    with pytest.raises(DataError, match="use_yaw_slip needs the gyro's yaw rate.*use_yaw_slip=False"):
        VibrationCurrentEstimator(base, seed=0, n_threads=1).fit([logs[0], _log(1, 0.4, with_gyro=False)])
    est = VibrationCurrentEstimator(base, seed=0, n_threads=1).fit(logs)
    with pytest.raises(DataError, match="gyro_z_radps"):
        est.predict(dataclasses.replace(logs[0], gyro_z_radps=None))
