"""Shared samples of the forecast-interval tests: synthetic runs of known offset and gain, a small estimator with an interval."""

from __future__ import annotations

import dataclasses

import numpy as np

from energy import EstimatorConfig, InteractionLog, LogMeta, VibrationCurrentEstimator
from energy.models.config import estimator_preset

__all__ = ["interval_log", "small_interval_config", "fit_two_ground_estimator", "with_carry"]


def interval_log(seed: int, ground: str = "g", *, offset_a: float = 0.0, gain: float = 1.0, vibration: float = 0.3,
                 duration_s: float = 40.0) -> InteractionLog:
    """Known currents ``gain * (0.5 + 4 v + turning terms) + offset_a`` with 0.1 A noise and white vibration."""
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


def small_interval_config(**changes) -> EstimatorConfig:
    """The "default" preset made small: three members, a few epochs, no physics prior."""
    base = dict(window_s=0.5, hidden_sizes=(16, 16), n_members=3, max_epochs=25, patience=8, learning_rate=3e-3,
                batch_size=64, train_stride_s=0.3, dropout=0.0, physics_prior=None)
    base.update(changes)
    return estimator_preset("default").replace(**base)


def fit_two_ground_estimator() -> tuple[VibrationCurrentEstimator, list[InteractionLog]]:
    """A small estimator (with its cross-validated interval) fitted on four runs of ground "a" and four of "b"."""
    logs = [interval_log(s, "a", vibration=0.2) for s in range(4)] + [
        interval_log(10 + s, "b", vibration=1.0, gain=1.4) for s in range(4)]
    est = VibrationCurrentEstimator(small_interval_config(physics_prior="husky"), seed=0, n_threads=1).fit(logs)
    return est, logs


def with_carry(est, carry):
    """A copy of the fitted ``est`` whose interval carries a run's offset along it by ``carry``."""
    other = est.clone()
    other.__dict__.update({k: v for k, v in est.__dict__.items() if k.endswith("_")})
    other.interval_ = dataclasses.replace(est.interval_, run_carry=carry)
    return other
