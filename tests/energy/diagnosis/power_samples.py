"""Shared samples of the power-stage tests: small electrical scenarios and hand-made power inputs."""

from __future__ import annotations

import dataclasses

import numpy as np
from diagnosis_scenarios import null_scenario, scenario

from energy.diagnosis.power_data import PowerInputs

__all__ = ["N_BOOT", "small_power_scenario", "sample_power_inputs"]

#: Bootstrap resamples of the power-stage diagnoses in the tests.
N_BOOT = 50


def small_power_scenario(name: str, **kw):
    """The scenario ``name`` (``"null"``: the null with power logs) with 3 runs of 12 s."""
    sc = scenario(name) if name != "null" else dataclasses.replace(null_scenario(), power_logs=True)
    return dataclasses.replace(sc, n_runs=3, run_duration_s=12.0, **kw)


def sample_power_inputs(**changes) -> PowerInputs:
    """Four samples: stopped, starting up, moving at 1 m/s, braking (back-EMF power negative on the left)."""
    base = dict(
        back_emf_w=np.array([[0.0, 0.0], [10.0, 10.0], [20.0, 30.0], [-8.0, 4.0]]),
        current_sq_a2=np.array([[0.0, 0.0], [4.0, 4.0], [1.0, 9.0], [4.0, 1.0]]),
        speed_mps=np.array([0.0, 0.5, 1.0, 1.0]),
        stopped=np.array([1.0, 0.0, 0.0, 0.0]),
        startup=np.array([0.0, 1.0, 0.0, 0.0]),
        ra0_ohm=0.5, sensor0=(3.0, 2.0), control0_w=np.array([5.0, 9.0, 7.0, 7.0]), startup_excess_w=2.0, regen=0.5,
    )
    base.update(changes)
    return PowerInputs(**base)
