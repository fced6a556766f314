"""Tests of planner.missions.manoeuvres: the excitation manoeuvre's logs and the fitted prior model."""

from __future__ import annotations

import numpy as np
import pytest

from energy import NoiseModel, TruthSimulator, ground_preset, robot_preset
from planner.missions.manoeuvres import excitation_manoeuvre, excitation_profiles, fit_prior_model


def _truth() -> TruthSimulator:
    return TruthSimulator(robot_preset("husky"), {"asphalt": ground_preset("asphalt"), "sand": ground_preset("sand")},
                          noise=NoiseModel.off(), seed=0)


def _drive(seed: int):
    return excitation_manoeuvre(_truth(), "sand", _profiles(seed), sim_seed=seed)


def _profiles(seed: int):
    return excitation_profiles(straight_s=3.0, turn_s=3.0, speeds_mps=(0.3, 0.6), omega_radps=0.5, seed=seed)


def test_the_manoeuvre_gives_two_logs_repeatable_by_seed():
    logs = _drive(0)
    assert len(logs) == 2
    again = _drive(0)
    for a, b in zip(logs, again):
        assert np.array_equal(a.current_left_a, b.current_left_a)


def test_sand_draws_more_current_than_asphalt_for_the_same_manoeuvre():
    sand = np.mean([np.abs(log.current_left_a).mean() for log in _drive(0)])
    asphalt = np.mean([np.abs(log.current_left_a).mean() for log in
                       excitation_manoeuvre(_truth(), "asphalt", _profiles(0), sim_seed=0)])
    assert sand > asphalt


def test_the_prior_model_is_fitted_on_its_ground():
    model = fit_prior_model(_truth(), "asphalt", seed=1)
    assert model.is_fitted


def test_the_manoeuvre_drives_command_profiles_only():
    from terrain import InvalidParameterError

    with pytest.raises(InvalidParameterError, match="profiles must be CommandProfiles"):
        excitation_manoeuvre(_truth(), "sand", [{"v_mps": [0.5]}], sim_seed=0)
