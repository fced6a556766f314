"""Tests of energy.drivetrain: per-sample ground coefficients, the drive-train power, control-board and battery-side power."""

from __future__ import annotations

import numpy as np
import pytest
from params_samples import sample_robot

from energy import GroundParams
from energy.drivetrain import EFFECTS, GroundArrays, battery_side_w, control_power, drive_power
from terrain import InvalidParameterError

G = 9.80665
SAND = GroundParams(name="sand", static_friction_coef=0.8, coulomb_friction_coef=0.5, rolling_resistance_coef=0.1,
                    lateral_friction_coef=0.6)
ROCK = GroundParams(name="rock", static_friction_coef=0.9, coulomb_friction_coef=0.7, rolling_resistance_coef=0.02,
                    lateral_friction_coef=0.8)


def _zeros(n: int) -> np.ndarray:
    return np.zeros(n)


# ------------------------------------------------------------------ GroundArrays
def test_one_ground_for_every_sample_or_one_ground_per_sample():
    one = GroundArrays(SAND, None, 3)
    assert one.crr.tolist() == [0.1, 0.1, 0.1] and one.mu_k.tolist() == [0.5] * 3 and one.mu_s.tolist() == [0.8] * 3
    mixed = GroundArrays([SAND, ROCK], np.array([1, 0, 1]), 3)
    assert mixed.crr.tolist() == [0.02, 0.1, 0.02] and mixed.mu_k.tolist() == [0.7, 0.5, 0.7]
    assert GroundArrays([SAND, ROCK], 1, 2).crr.tolist() == [0.02, 0.02]  # one index for every sample


@pytest.mark.parametrize(("ground", "index", "match"), [
    (SAND, np.zeros(3, int), "ground_index must be None when ground is a single GroundParams"),
    ([], None, "ground must be a GroundParams or a non-empty sequence of GroundParams"),
    ("sand", None, "ground must be a GroundParams or a non-empty sequence"),
    ([SAND, "rock"], np.zeros(3, int), r"ground\[1\] must be a GroundParams, got 'str'"),
    ([SAND, ROCK], None, "ground_index is required when ground is a sequence of GroundParams"),
    ([SAND, ROCK], np.zeros(3), "ground_index must hold integers, got dtype float64"),
    ([SAND, ROCK], np.zeros(2, int), r"ground_index must have 3 entries, got shape \(2,\)"),
    ([SAND, ROCK], np.array([0, 2, -1]), r"ground_index must lie in \[0, 1\], got array\(\[ 2, -1\]\)"),
])
def test_ground_arrays_documented_errors(ground, index, match):
    with pytest.raises(InvalidParameterError, match=match):
        GroundArrays(ground, index, 3)


# -------------------------------------------------------------------- drive_power
def test_slope_alone_is_m_g_sin_beta_times_speed_and_nothing_back_downhill():
    robot = sample_robot(mass_kg=20.0)
    v = np.array([0.5, 1.0, 1.0])
    beta = np.array([0.1, 0.1, -0.1])
    res = drive_power(robot, ["slope"], v, _zeros(3), _zeros(3), _zeros(3), beta, GroundArrays(SAND, None, 3), None)
    lift = 20.0 * G * np.sin(beta) * v
    np.testing.assert_allclose(res.slope_power_w, lift, rtol=1e-12)
    np.testing.assert_allclose(res.drive_power_w, [lift[0], lift[1], 0.0], rtol=1e-12)  # no regeneration
    np.testing.assert_allclose(res.total_power_w, res.drive_power_w)  # no electronics switched on
    assert res.friction_power_w.tolist() == [0.0, 0.0, 0.0]
    assert res.motor_current_a.shape == (3, 2) and not res.saturated.any()


def test_coulomb_friction_is_rolling_resistance_on_each_ground():
    robot = sample_robot(mass_kg=20.0)
    v = np.full(2, 0.5)
    gr = GroundArrays([SAND, ROCK], np.array([0, 1]), 2)
    res = drive_power(robot, ["coulomb_friction"], v, _zeros(2), _zeros(2), _zeros(2), _zeros(2), gr, None)
    np.testing.assert_allclose(res.friction_power_w, np.array([0.1, 0.02]) * 20.0 * G * 0.5, rtol=1e-12)


def test_every_effect_has_a_name():
    assert len(EFFECTS) == len(set(EFFECTS)) == 15
    assert {"slope", "coulomb_friction", "armature_heat", "control"} <= set(EFFECTS)


# --------------------------------------------------------------- control and battery side
def test_control_power_standby_start_up_and_stable():
    robot = sample_robot(control_standby_power_w=5.0, control_startup_power_w=9.0, control_stable_power_w=7.0,
                         startup_duration_s=1.0)
    t = np.arange(8) * 0.5
    v = np.array([0.0, 0.3, 0.3, 0.3, 0.0, 0.0, 0.3, 0.3])
    assert control_power(robot, v, _zeros(8), t).tolist() == [5.0, 9.0, 9.0, 7.0, 5.0, 5.0, 9.0, 9.0]
    assert control_power(robot, v, _zeros(8), None).tolist() == [5.0, 7.0, 7.0, 7.0, 5.0, 5.0, 7.0, 7.0]
    turning = control_power(robot, _zeros(2), np.array([0.0, 0.5]), None)
    assert turning.tolist() == [5.0, 7.0] and turning.dtype == np.float64  # turning on the spot is moving


def test_battery_side_keeps_motoring_and_scales_regeneration():
    p = np.array([[10.0, -4.0], [0.0, -1.0]])
    assert battery_side_w(p, 0.5).tolist() == [[10.0, -2.0], [0.0, -0.5]]
    assert battery_side_w(p, 0.0).tolist() == [[10.0, 0.0], [0.0, 0.0]]
