"""Shared samples of the diagnose and result tests: the withheld turning-resistance case, small, with a noise candidate."""

from __future__ import annotations

import dataclasses

import numpy as np
from diagnosis_scenarios import scenario

from energy.diagnosis import Effect, EffectParameter, FitSettings, diagnose

__all__ = ["CANDIDATES", "NoiseEffect", "small_scenario", "turning_diagnosis"]

#: Catalogued candidates of the turning case.
CANDIDATES = ["turning_resistance", "gear_losses", "current_gain", "idle_current", "mass"]


def small_scenario(sc):
    """``sc`` with 3 runs of 8 s."""
    return dataclasses.replace(sc, n_runs=3, run_duration_s=8.0)


class NoiseEffect(Effect):
    """A pure-noise candidate: a gain on seeded random currents."""

    name = "pure_noise"
    kind = "measurement"
    parameters = (EffectParameter("gain", 0.0, -5.0, 5.0, "A"),)

    def prepare(self, model, log):
        return np.random.default_rng(len(log)).standard_normal((len(log), 2))

    def apply(self, values, predicted_a, prepared):
        return predicted_a + values[0] * prepared


def turning_diagnosis():
    """``(logs, model, diagnosis)`` of a physics model without turning resistance, seed 0, 50 bootstrap resamples."""
    sc = small_scenario(scenario("turning_resistance"))
    logs, model = sc.make_logs(0), sc.make_model(0)
    return logs, model, diagnose(model, logs, terrain=sc.terrain, effects=CANDIDATES + [NoiseEffect()],
                                 settings=FitSettings(n_bootstrap=50))
