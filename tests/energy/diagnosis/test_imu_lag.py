"""The IMU-lag candidate: a clock offset between the IMU and the drive streams, for models that read the IMU."""

import types

import numpy as np
import pytest

from energy import CurrentModel, InteractionLog, LinearCurrentModel, LogMeta, PhysicsCurrentModel
from energy.diagnosis import CorrectedCurrentModel, FitSettings, diagnose, effect
from energy.diagnosis.effects_measurement import reads_vibration

TRUE_LAG_S = 0.17


class VibrationToyModel(CurrentModel):
    """A current from the speed and the IMU: ``I = c0 v + c1 |a_z - g|`` at the drive times (a stand-in for the
    estimator; with the speed in it, shifting the IMU is not the same as shifting the whole prediction)."""

    config = types.SimpleNamespace(band_hz=(1.0, 12.0))

    def _fit(self, logs):
        x = np.concatenate([self._x(log) for log in logs])
        y = np.concatenate([np.column_stack([log.current_left_a, log.current_right_a]) for log in logs])
        self.coef_ = np.linalg.lstsq(x, y, rcond=None)[0]

    @staticmethod
    def _x(log):
        return np.column_stack([log.v_mps, np.abs(np.interp(log.time_s, log.accel_time_s, log.accel_z_mps2) - 9.81)])

    def _predict(self, log):
        return self._x(log) @ self.coef_

    def _state(self):
        return {"coef": self.coef_.tolist()}

    def _load_state(self, state):
        self.coef_ = np.asarray(state["coef"])


def _envelope(s, k):
    return 1.0 + np.sin(1.3 * s + k) ** 2 * (1.0 + np.sin(4.1 * s + 2 * k))


def _logs(lag_s, n_logs=5, seed=0):
    """Vibration bursts drive the current; the IMU clock runs ``lag_s`` late."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n_logs):
        t = np.arange(0.0, 20.0, 0.05)
        ta = np.arange(0.0, 20.0, 0.01)
        az = 9.81 + _envelope(ta - lag_s, k)  # what the IMU logged at ta happened at ta - lag
        v = 0.6 + 0.5 * np.sign(np.sin(0.9 * t + k))  # steps: a lag of the whole prediction shows at each one
        cur = (3.0 * v + 2.0 * _envelope(t, k))[:, None] * np.array([1.0, 1.1]) + 0.05 * rng.standard_normal((t.size, 2))
        out.append(InteractionLog(t, v, np.zeros(t.size), cur[:, 0], cur[:, 1], ta, az))
    return out


def test_a_lagged_imu_clock_is_found_and_its_lag_fitted():
    logs = _logs(TRUE_LAG_S)
    model = VibrationToyModel().fit(_logs(0.0, seed=1))
    d = diagnose(model, logs, effects=["imu_lag", "time_lag", "current_gain"], settings=FitSettings(n_bootstrap=50))
    assert d.current.ranking[0].name == "imu_lag" and d.current.chosen[0] == "imu_lag"
    assert d.current.ranking[0].parameters["lag_s"] == pytest.approx(TRUE_LAG_S, abs=0.03)
    assert d.current.ranking[0].added_pct > 50.0
    # the corrected model carries the lag: it predicts the lagged logs closer than the model as given
    err = lambda m: np.mean([np.mean((m.predict(g) - np.column_stack([g.current_left_a, g.current_right_a])) ** 2)  # noqa: E731
                             for g in logs])
    assert err(d.corrected_model) < 0.5 * err(model)


def test_no_lag_no_imu_lag_and_models_without_the_imu_skip_it():
    logs = _logs(0.0)
    model = VibrationToyModel().fit(_logs(0.0, seed=1))
    d = diagnose(model, logs, effects=["imu_lag"], settings=FitSettings(n_bootstrap=50))
    assert "imu_lag" not in d.current.chosen
    assert reads_vibration(model) and not reads_vibration(LinearCurrentModel())
    lin = LinearCurrentModel().fit(logs)
    d2 = diagnose(lin, logs, effects=["imu_lag", "current_gain"], settings=FitSettings(n_bootstrap=20))
    assert "imu_lag" in d2.current.skipped and d2.current.score("imu_lag") is None


def test_imu_lag_composes_as_a_difference():
    logs = _logs(TRUE_LAG_S, n_logs=1)
    model = VibrationToyModel().fit(_logs(0.0, seed=1))
    e = effect("imu_lag").bind(logs)
    prep = e.prepare(model, logs[0])
    base = model.predict(logs[0])
    assert np.allclose(e.apply(np.array([0.0]), base, prep), base)  # lag 0 adds nothing
    shifted = InteractionLog(logs[0].time_s, logs[0].v_mps, logs[0].omega_radps, logs[0].current_left_a,
                             logs[0].current_right_a, logs[0].accel_time_s - 0.2, logs[0].accel_z_mps2)
    assert np.allclose(e.apply(np.array([0.2]), base, prep), model.predict(shifted))  # a grid lag is exact


def test_wrapped_models_read_the_imu_when_their_base_does_and_switched_off_features_do_not():
    logs = _logs(0.0, n_logs=2)
    toy = VibrationToyModel().fit(_logs(0.0, seed=1))
    corrected = CorrectedCurrentModel(toy, ["current_gain"]).fit(logs)
    assert reads_vibration(corrected) and effect("imu_lag").applies_to(corrected)
    lagged = CorrectedCurrentModel(toy, ["imu_lag"]).fit(logs)
    assert not effect("imu_lag").applies_to(lagged)  # it has one already
    assert not reads_vibration(CorrectedCurrentModel(LinearCurrentModel().fit(logs), ["current_gain"]).fit(logs))
    off = types.SimpleNamespace(band_hz=(1.0, 12.0), local_spectrum=False, run_features="none", use_yaw_slip=False)
    quiet = VibrationToyModel().fit(logs)
    quiet.config_ = off  # a fitted configuration with every IMU feature off
    assert not reads_vibration(quiet)
    quiet.config_ = types.SimpleNamespace(**{**vars(off), "run_features": "bands"})
    assert reads_vibration(quiet)


def _estimator_log(seed, duration_s=12.0):
    """10 Hz drive, 100 Hz IMU; the current follows the motion and the vibration envelope."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 0.1)
    p1, p2 = rng.uniform(0, 2 * np.pi, 2)
    v = 0.45 + 0.35 * np.sin(2 * np.pi * t / 7.0 + p1)
    w = 0.6 * np.sin(2 * np.pi * t / 5.0 + p2)
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    env = 1.0 + 0.5 * np.sin(2 * np.pi * ta / 3.0 + p1) ** 2
    az = 9.81 + 0.3 * env * rng.standard_normal(ta.size)
    shake = np.interp(t, ta, env)
    left = 0.5 + 4.0 * v + 3.0 * np.maximum(-w, 0) + np.maximum(w, 0) + shake
    right = 0.5 + 4.0 * v + 3.0 * np.maximum(w, 0) + np.maximum(-w, 0) + shake
    return InteractionLog(t, v, w, left, right, ta, az, meta=LogMeta(source=f"synthetic-{seed}", ground_label="g"))


def test_a_fitted_vibration_estimator_is_offered_imu_lag_and_a_physics_model_is_not():
    """The estimator is configured by a preset name (``config="default"``): what it reads is in its
    fitted ``config_``, not in ``config``. A physics model never reads the IMU."""
    pytest.importorskip("torch")
    from energy import VibrationCurrentEstimator

    logs = [_estimator_log(s) for s in range(3)]
    est = VibrationCurrentEstimator("default", seed=0, n_threads=1).fit(logs)  # about 1 s on a CPU
    assert est.config == "default" and reads_vibration(est)
    d = diagnose(est, logs, effects=["imu_lag", "current_gain"], settings=FitSettings(n_bootstrap=20))
    assert "imu_lag" not in d.current.skipped and d.current.score("imu_lag") is not None
    assert reads_vibration(CorrectedCurrentModel(est, ["current_gain"]).fit(logs))
    physics = PhysicsCurrentModel("husky").fit(logs)
    assert not reads_vibration(physics)
    d2 = diagnose(physics, logs, effects=["imu_lag", "current_gain"], settings=FitSettings(n_bootstrap=20))
    assert "imu_lag" in d2.current.skipped and d2.current.score("imu_lag") is None
