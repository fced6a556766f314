"""The independent Husky log generator (benchmarks/independent_sim.py): seeded, each effect changes
what it should and nothing else, BorealTC-like measurement, CSV logs that read back."""

from __future__ import annotations

import doctest
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import energy
from energy.io import read_csv_log

SIM_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "independent_sim.py"


def _load():
    name = "independent_sim"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, SIM_PATH)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # dataclasses look their module up while the class is built
    spec.loader.exec_module(mod)
    return mod


sim = _load()
SEED = 3


def run(case: str = "none", seed: int = SEED, **kw):
    return sim.simulate_run(seed, sim.case_effects(case), **kw)


def currents(log) -> np.ndarray:
    return np.column_stack([log.current_left_a, log.current_right_a])


def straight(log) -> np.ndarray:
    # odometry noise is 0.005 rad/s: |omega| < 0.015 is a straight
    return (np.abs(log.omega_radps) < 0.015) & (np.abs(log.v_mps) > 0.15)


def pivot(log) -> np.ndarray:
    return (np.abs(log.v_mps) < 0.05) & (np.abs(log.omega_radps) > 0.25)


def at_rest(log) -> np.ndarray:
    return (np.abs(log.v_mps) < 0.01) & (np.abs(log.omega_radps) < 0.015)


@pytest.fixture(scope="module")
def base():
    return run()


def test_same_seed_same_log_other_seed_other_log(base):
    again = run()
    for name in ("time_s", "v_mps", "omega_radps", "current_left_a", "current_right_a", "accel_time_s",
                 "accel_z_mps2", "gyro_z_radps"):
        np.testing.assert_array_equal(getattr(base, name), getattr(again, name), err_msg=name)
    other = run(seed=SEED + 1)
    assert len(other) != len(base) or not np.array_equal(other.current_left_a, base.current_left_a)


def test_meta_rates_and_gravity(base):
    assert (base.meta.robot, base.meta.source, base.meta.ground_label) == ("husky", "independent-sim", "flooring")
    assert base.meta.velocity_source == "measured"
    assert base.meta.track_width_m == pytest.approx(sim.ICR_EXPANSION * sim.TRACK_WIDTH_M)
    assert 6.3 < base.drive_rate_hz < 6.7
    assert 99.0 < base.accel_rate_hz < 101.0
    assert 60.0 <= base.duration_s <= 90.0
    assert np.median(base.accel_z_mps2) == pytest.approx(9.81, abs=0.05)
    assert pivot(base).sum() > 20 and straight(base).sum() > 50 and at_rest(base).sum() > 10


def test_none_is_the_baseline(base):
    zero = sim.SimEffects(payload_kg=0.0, turning_mu_max=0.0, left_gain=1.0, drive_lag_s=0.0,
                          speed_friction_n_s2_per_m2=0.0)
    for log in (sim.simulate_run(SEED), sim.simulate_run(SEED, zero)):
        np.testing.assert_array_equal(currents(log), currents(base))
        np.testing.assert_array_equal(log.accel_z_mps2, base.accel_z_mps2)


@pytest.mark.parametrize("case", [c for c in sim.CASES if c != "none"])
def test_effects_leave_the_imu_and_the_stamps_alone(base, case):
    log = run(case)
    np.testing.assert_array_equal(log.time_s, base.time_s)
    np.testing.assert_array_equal(log.accel_time_s, base.accel_time_s)
    np.testing.assert_array_equal(log.accel_z_mps2, base.accel_z_mps2)
    np.testing.assert_array_equal(log.gyro_z_radps, base.gyro_z_radps)
    if case != "lag":  # only the drive-stream lag moves the speeds
        np.testing.assert_array_equal(log.v_mps, base.v_mps)
        np.testing.assert_array_equal(log.omega_radps, base.omega_radps)


def test_payload_raises_straight_line_current(base):
    log = run("payload")
    s = straight(base)
    extra = currents(log)[s].mean(axis=0) - currents(base)[s].mean(axis=0)
    # rolling resistance alone: Crr * 80 kg * g / 2 per side through the drivetrain
    rolling_a = (sim.ROLLING_RESISTANCE_COEF * 80.0 * sim.GRAVITY_MPS2 / 2 * sim.WHEEL_RADIUS_M
                 / (sim.GEAR_EFFICIENCY * sim.GEAR_RATIO * sim.TORQUE_CONSTANT_NM_PER_A))
    assert np.all(extra > 0.8 * rolling_a), (extra, rolling_a)


def test_turning_raises_pivot_current_not_straight_current(base):
    log = run("turning")
    p, s = pivot(base), straight(base)
    assert np.all(currents(log)[p].mean(axis=0) > currents(base)[p].mean(axis=0) + 3.0)
    same = np.all(currents(log)[s] == currents(base)[s], axis=1)
    assert same.mean() > 0.9  # a few straight-labelled samples are the ends of turns
    assert np.abs(currents(log)[s] - currents(base)[s]).mean() < 0.05


def test_turning_follows_wongs_radius_law():
    """Ideal runs: the outer side's extra current is the couple M_r / B of Wong's mu_lat(R)."""
    log, ref = run("turning", ideal=True), run(ideal=True)
    extra_a = (currents(log) - currents(ref)).max(axis=1)  # the outer side pushes, the inner one brakes
    amps_per_newton = sim.WHEEL_RADIUS_M / (sim.GEAR_EFFICIENCY * sim.GEAR_RATIO * sim.TORQUE_CONSTANT_NM_PER_A)
    mu_implied = extra_a / amps_per_newton * sim.TRACK_WIDTH_M / (sim.MASS_KG * sim.GRAVITY_MPS2 * sim.WHEELBASE_M / 2)
    radius = np.abs(log.v_mps) / np.maximum(np.abs(log.omega_radps), 1e-9)
    mu_wong = sim.CASES["turning"].turning_mu_max / (0.925 + 0.15 * radius / sim.TRACK_WIDTH_M)
    turning = np.abs(log.omega_radps) > 0.2
    tight, wide = turning & (radius < 0.1), turning & (radius > 1.0)
    assert tight.sum() > 5 and wide.sum() > 5
    for sel in (tight, wide):
        assert np.median(mu_implied[sel] / mu_wong[sel]) == pytest.approx(1.0, abs=0.05)
    assert np.median(mu_implied[tight]) > 1.2 * np.median(mu_implied[wide])


def test_left_gain_scales_only_the_left_side():
    log, ref = run("left_gain", ideal=True), run(ideal=True)
    np.testing.assert_array_equal(log.current_right_a, ref.current_right_a)
    motor_log = log.current_left_a - sim.REST_CURRENT_A
    motor_ref = ref.current_left_a - sim.REST_CURRENT_A
    moving = motor_ref > 0.1
    assert moving.sum() > 50
    np.testing.assert_allclose(motor_log[moving] / motor_ref[moving], 1.25, rtol=1e-9)
    noisy, noisy_ref = run("left_gain"), run()
    np.testing.assert_array_equal(noisy.current_right_a, noisy_ref.current_right_a)
    assert noisy.current_left_a.mean() > noisy_ref.current_left_a.mean()


def _best_shift(t, late, early, shifts) -> float:
    """The shift s minimising |late(t) - early(t - s)|."""
    errors = [np.mean(np.abs(late - np.interp(t - s, t, early))) for s in shifts]
    return float(shifts[int(np.argmin(errors))])


def test_lag_shifts_the_drive_clock_against_the_imu():
    log, ref = run("lag", ideal=True), run(ideal=True)
    np.testing.assert_array_equal(log.accel_z_mps2, ref.accel_z_mps2)
    shifts = np.round(np.arange(-0.6, 0.61, 0.01), 2)
    lag = sim.CASES["lag"].drive_lag_s
    assert _best_shift(log.time_s, log.v_mps, ref.v_mps, shifts) == pytest.approx(lag, abs=0.04)
    assert _best_shift(log.time_s, log.current_left_a, ref.current_left_a, shifts) == pytest.approx(lag, abs=0.04)
    # against the IMU's vibration, which grows with speed: the drive stream's speed now trails it
    vib = np.abs(log.accel_z_mps2 - 9.81)
    speed_on_imu = np.interp(log.accel_time_s, log.time_s - lag, np.abs(log.v_mps))
    speed_as_logged = np.interp(log.accel_time_s, log.time_s, np.abs(log.v_mps))
    assert np.corrcoef(vib, speed_on_imu)[0, 1] > np.corrcoef(vib, speed_as_logged)[0, 1]


def test_current_lag_shifts_only_the_currents():
    log, ref = run("current_lag", ideal=True), run(ideal=True)
    np.testing.assert_array_equal(log.v_mps, ref.v_mps)
    shifts = np.round(np.arange(-0.6, 0.61, 0.01), 2)
    lag = sim.CASES["current_lag"].current_lag_s
    assert _best_shift(log.time_s, log.current_right_a, ref.current_right_a, shifts) == pytest.approx(lag, abs=0.04)


def test_speed_friction_grows_with_speed(base):
    log = run("speed_friction")
    s = straight(base)
    fast, slow = s & (np.abs(base.v_mps) > 0.7), s & (np.abs(base.v_mps) < 0.4)
    assert fast.sum() > 10 and slow.sum() > 10
    extra = currents(log).mean(axis=1) - currents(base).mean(axis=1)
    assert extra[fast].mean() > 2.5 * extra[slow].mean() > 0


@pytest.mark.parametrize("case", list(sim.CASES))
def test_currents_never_negative_and_quantised(case):
    log = run(case)
    i = currents(log)
    assert np.all(i >= 0.0)
    np.testing.assert_allclose(i / sim.CURRENT_STEP_A, np.round(i / sim.CURRENT_STEP_A), atol=1e-9)


def test_rest_level_at_standstill(base):
    rest = at_rest(base)
    np.testing.assert_allclose(currents(base)[rest].mean(axis=0), sim.REST_CURRENT_A, atol=0.06)
    ideal = run(ideal=True)
    np.testing.assert_allclose(currents(ideal)[at_rest(ideal)], sim.REST_CURRENT_A, atol=1e-6)


def test_csv_reads_back(base, tmp_path):
    (path,) = sim.write_runs([base], tmp_path)
    back = read_csv_log(path)
    for name in ("time_s", "v_mps", "omega_radps", "current_left_a", "current_right_a", "accel_time_s",
                 "accel_z_mps2", "gyro_z_radps"):
        np.testing.assert_array_equal(getattr(back, name), getattr(base, name), err_msg=name)
    assert (back.meta.robot, back.meta.ground_label, back.meta.velocity_source) == ("husky", "flooring", "measured")
    assert back.meta.track_width_m == pytest.approx(base.meta.track_width_m)


def test_case_effects():
    assert sim.case_effects("payload").payload_kg == 80.0
    assert sim.case_effects("payload:40").payload_kg == 40.0
    with pytest.raises(KeyError, match="unknown case 'mud'"):
        sim.case_effects("mud")
    with pytest.raises(ValueError, match="takes no value"):
        sim.case_effects("none:1")
    with pytest.raises(ValueError, match="drive_lag_s"):
        sim.SimEffects(drive_lag_s=5.0)


def _cruise(seed=SEED, **kw):
    return sim.simulate_run(seed, duration_s=30.0, driving="cruise", **kw)


def test_uphill_draws_more_than_level_than_downhill():
    """On a 10° plane, a straight at one speed: uphill the motors lift the robot (gravity, m g sin 10° = 85 N,
    well above the 15 N of rolling); downhill gravity pushes harder than rolling holds back, so the back-driven
    motors log an exact 0 (the driver's zero, sensor offset included); the same seed, the same noise."""
    plane = sim.Slope(math.radians(10.0))
    level = _cruise()
    up = _cruise(slope=plane, start_pose=(0.0, 0.0, 0.0))
    down = _cruise(slope=plane, start_pose=(0.0, 0.0, math.pi))
    across = _cruise(slope=plane, start_pose=(0.0, 0.0, math.pi / 2))  # level along the contour
    cruising = np.abs(level.v_mps) > 0.5
    mean = {k: currents(log)[cruising].mean() for k, log in
            {"up": up, "level": level, "down": down, "across": across}.items()}
    assert mean["up"] > mean["level"] + 2.0 > mean["down"] + 2.0, mean
    assert np.all(currents(down)[cruising] == 0.0)
    assert np.all(currents(down)[at_rest(down)] > 0.3)  # standing still (on the slope), the sensor's offset
    assert mean["across"] == pytest.approx(mean["level"], abs=0.1)  # level along the contour (cos 10° of the weight)
    # the gravity term as the physics gives it, per side through the drivetrain
    lift_a = (0.5 * sim.MASS_KG * sim.GRAVITY_MPS2 * math.sin(math.radians(10.0)) * sim.WHEEL_RADIUS_M
              / (sim.GEAR_EFFICIENCY * sim.GEAR_RATIO * sim.TORQUE_CONSTANT_NM_PER_A))
    assert mean["up"] - mean["level"] == pytest.approx(lift_a, rel=0.1)
    np.testing.assert_array_equal(level.v_mps, up.v_mps)  # the slope changes the currents, not the motion
    assert level.pose_xyh is None and up.pose_xyh is not None  # poses only where the run is placed


def test_start_pose_is_honoured_and_a_ramp_only_pitches_its_band():
    ramp = sim.Slope(math.radians(10.0), uphill_heading_rad=math.pi / 2, start_m=5.0, length_m=5.0)
    log = _cruise(start_pose=(3.0, -4.0, math.pi / 2))
    pose = log.pose_xyh
    np.testing.assert_allclose(pose[0], [3.0, -4.0, math.pi / 2], atol=1e-9)
    assert np.ptp(pose[:, 0]) < 1e-6 and pose[-1, 1] - pose[0, 1] == pytest.approx(
        np.sum(0.5 * (log.v_mps[1:] + log.v_mps[:-1]) * np.diff(log.time_s)), rel=0.02)  # driven along +y
    on = _cruise(slope=ramp, start_pose=(3.0, -4.0, math.pi / 2))
    np.testing.assert_array_equal(on.pose_xyh, pose)
    climbing = ramp.on_ramp(pose[:, 0], pose[:, 1]) & (np.abs(log.v_mps) > 0.5)
    level = ~ramp.on_ramp(pose[:, 0], pose[:, 1]) & (np.abs(log.v_mps) > 0.5)
    assert climbing.sum() > 5 and level.sum() > 20
    assert currents(on)[climbing].mean() > currents(log)[climbing].mean() + 2.0
    assert np.abs(currents(on)[level] - currents(log)[level]).mean() < 0.05
    assert ramp.elevation_m(np.zeros(3), np.array([0.0, 7.0, 40.0])).tolist() == pytest.approx(
        [0.0, 2.0 * math.tan(math.radians(10.0)), 5.0 * math.tan(math.radians(10.0))])
    with pytest.raises(ValueError, match="start_pose"):
        _cruise(start_pose=(0.0, math.nan, 0.0))
    with pytest.raises(ValueError, match="angle_rad"):
        sim.Slope(math.radians(45.0))
    with pytest.raises(TypeError, match="slope must be a Slope"):
        _cruise(slope=0.1)


def test_docstring_examples():
    result = doctest.testmod(sim)
    assert result.attempted > 0 and result.failed == 0


def test_the_rotor_inertia_truth_is_the_simulators_rotating_parts_as_the_library_charges_them():
    # a stop-and-go the simulator drives with its rotating parts x2 and x1: the extra current while accelerating
    # (motoring, not braking) is the library's rotor term at the difference of the two truths
    t = np.arange(0.0, 12.0, 0.1)
    v = np.where((t % 6.0 > 0.5) & (t % 6.0 < 3.5), 0.6, 0.0)
    prof = energy.CommandProfile(t, v, np.zeros_like(t))
    heavy = sim.simulate_run(1, sim.SimEffects(rotor_inertia_scale=2.0), commands=prof, ideal=True)
    light = sim.simulate_run(1, sim.SimEffects(), commands=prof, ideal=True)
    extra = heavy.current_left_a - light.current_left_a
    acc = np.gradient(heavy.v_mps, heavy.time_s)
    motor = energy.robot_preset("husky").motor
    jm = sim.rotor_inertia_kg_m2(2.0) - sim.rotor_inertia_kg_m2(1.0)
    library = jm * motor.gear_ratio * acc / (energy.robot_preset("husky").wheel_radius_m
                                             * motor.torque_constant_nm_per_a)
    steady = acc > 0.9  # at the controller's 1 m/s^2 limit
    assert steady.sum() >= 4
    np.testing.assert_allclose(extra[steady], library[steady], rtol=0.05)
    assert sim.rotor_inertia_kg_m2(3.0) == pytest.approx(3.0 * sim.rotor_inertia_kg_m2(1.0))
    assert sim.husky_robot().motor.rotor_inertia_kg_m2 == pytest.approx(sim.rotor_inertia_kg_m2())
    assert sim.husky_robot().replace(motor=energy.robot_preset("husky").motor) == energy.robot_preset("husky")
