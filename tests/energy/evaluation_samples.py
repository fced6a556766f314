"""Shared samples of the energy.evaluation tests: synthetic runs of known currents on two grounds."""

from __future__ import annotations

import numpy as np

from energy import InteractionLog, LogMeta
from energy.evaluation import AdaptSettings

__all__ = ["score_log", "score_logs", "adapt_log", "adapt_logs", "adapt_settings"]


def score_log(seed: int, ground: str, gain: float) -> InteractionLog:
    """30 s at 10 Hz; currents linear in |v| and |omega|, scaled by ``gain``; named ``<ground>/pro_<seed>``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 30.0, 0.1)
    v = 0.4 + 0.3 * np.sin(2 * np.pi * t / rng.uniform(5, 9) + rng.uniform(0, 6))
    w = 0.4 * np.sin(2 * np.pi * t / 4.0 + rng.uniform(0, 6))
    left = gain * (0.5 + 3.0 * np.abs(v) + 2.0 * np.abs(w))
    right = gain * (0.8 + 2.0 * np.abs(v) + 1.0 * np.abs(w))
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    return InteractionLog(t, v, w, left, right, ta, np.full(ta.size, 9.81),
                          meta=LogMeta(source=f"{ground}/pro_{seed:02d}.csv", ground_label=ground))


def score_logs() -> list[InteractionLog]:
    """Three runs on grass (gain 1) and three on sand (gain 2.5)."""
    return [score_log(i, "grass", 1.0) for i in range(3)] + [score_log(10 + i, "sand", 2.5) for i in range(3)]


def adapt_log(seed: int, ground: str, *, gain: float = 1.0, offset_a: float = 0.0, duration_s: float = 60.0) -> InteractionLog:
    """At 5 Hz; currents linear in |v| and |omega|, scaled by ``gain`` and shifted by ``offset_a``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 0.2)
    v = 0.4 + 0.2 * np.sin(2 * np.pi * t / rng.uniform(5, 9) + rng.uniform(0, 6))
    w = 0.5 * np.sign(np.sin(2 * np.pi * t / 7.0 + rng.uniform(0, 6)))
    left = gain * (0.5 + 3.0 * np.abs(v) + 2.0 * np.abs(w)) + offset_a
    right = gain * (0.8 + 2.0 * np.abs(v) + 1.0 * np.abs(w)) + offset_a
    ta = np.arange(0.0, t[-1] + 0.005, 0.05)
    return InteractionLog(t, v, w, left, right, ta, np.full(ta.size, 9.81),
                          meta=LogMeta(source=f"{ground}/pro_{seed:02d}.csv", ground_label=ground))


def adapt_logs() -> list[InteractionLog]:
    """Three runs on grass and three on sand, each drawing more current than the others by its own offset."""
    # each run draws more current than the others by its own offset: only adaptation can know it
    return ([adapt_log(i, "grass", offset_a=0.3 * i) for i in range(3)]
            + [adapt_log(10 + i, "sand", gain=2.0, offset_a=0.4 * i, duration_s=50.0) for i in range(3)])


def adapt_settings(**kw) -> AdaptSettings:
    """AdaptSettings adapting on the first 10 s and 20 s (plus ``kw``)."""
    return AdaptSettings(adapt_seconds=(10.0, 20.0), **kw)
