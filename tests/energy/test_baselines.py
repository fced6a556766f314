"""Tests of energy.baselines: constant, linear and fitted-physics current models."""

import dataclasses

import numpy as np
import pytest

from energy import (
    EFFECTS,
    ConstantCurrentModel,
    InteractionLog,
    LinearCurrentModel,
    LogMeta,
    PhysicsCurrentModel,
    PhysicsEnergyModel,
    ground_preset,
    robot_preset,
)
from energy.logs import at_rest, rest_samples
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError


def _motion(seed: int, duration_s: float = 40.0, rate_hz: float = 10.0):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    p1, p2 = rng.uniform(0, 2 * np.pi, 2)
    v = 0.4 + 0.3 * np.sin(2 * np.pi * t / 9.0 + p1)
    w = 0.5 * np.sin(2 * np.pi * t / 6.0 + p2)
    return t, v, w


def _log(t, v, w, left, right, meta=None):
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    return InteractionLog(t, v, w, left, right, ta, np.full(ta.size, 9.81), meta=meta or LogMeta())


def test_constant_model_predicts_the_time_averaged_current():
    t = np.array([0.0, 1.0, 3.0])
    log = _log(t, np.zeros(3), np.zeros(3), np.array([1.0, 1.0, 4.0]), np.full(3, 2.0))
    model = ConstantCurrentModel().fit(log)
    # left: (1 + 2.5 * 2) / 3 = 2 A (charge over time, not the sample mean 2.0 by chance)
    assert model.current_a_.tolist() == pytest.approx([2.0, 2.0])
    assert model.predict(log).shape == (3, 2)
    assert np.all(model.predict(log)[:, 0] == pytest.approx(2.0))


def test_linear_model_recovers_known_coefficients():
    logs = []
    for seed in (0, 1):
        t, v, w = _motion(seed)
        dv = np.gradient(v, t)
        left = 0.7 + 3.0 * np.abs(v) + 2.0 * np.abs(w) + 1.5 * dv
        right = 0.5 + 4.0 * np.abs(v) + 1.0 * np.abs(w) - 0.5 * dv
        logs.append(_log(t, v, w, left, right))
    model = LinearCurrentModel().fit(logs)
    assert model.coef_[:, 0] == pytest.approx([0.7, 3.0, 2.0, 1.5], abs=1e-9)
    assert model.coef_[:, 1] == pytest.approx([0.5, 4.0, 1.0, -0.5], abs=1e-9)
    assert model.score(logs) == pytest.approx(1.0)


def test_linear_model_needs_samples():
    log = _log(np.array([0.0, 0.1]), np.zeros(2), np.zeros(2), np.ones(2), np.ones(2))
    with pytest.raises(DataError, match="at least 4"):
        LinearCurrentModel().fit(log)


DRIVE_EFFECTS = [e for e in EFFECTS if e not in ("sensor", "control")]


def _physics_truth(seed, crr, mu_lat, idle_a, robot, ground, meta=None):
    t, v, w = _motion(seed)
    model = PhysicsEnergyModel(robot, DRIVE_EFFECTS)
    g = ground.replace(rolling_resistance_coef=crr, lateral_friction_coef=mu_lat)
    res = model.power(v, w, g, accel_mps2=np.gradient(v, t), alpha_radps2=np.gradient(w, t), time_s=t)
    cur = res.motor_current_a * np.sign(res.motor_speed_radps)
    cur = np.maximum(idle_a + cur, 0.0)
    return _log(t, v, w, cur[:, 0], cur[:, 1], meta)


def test_physics_model_recovers_ground_coefficients_from_its_own_currents():
    robot, ground = robot_preset("husky"), ground_preset("asphalt")
    logs = [_physics_truth(s, 0.06, 0.4, 0.8, robot, ground) for s in (0, 1)]
    # with the idle current fitted too (not by default: see the next test); it is told from rolling
    # resistance here only because the motion never drives straight at constant speed for long
    fit = ("rolling_resistance_coef", "lateral_friction_coef", "idle_current_a", "rest_current_a")
    model = PhysicsCurrentModel("husky", "asphalt", fit_parameters=fit).fit(logs)
    assert model.fitted_["rolling_resistance_coef"] == pytest.approx(0.06, rel=0.05)
    assert model.fitted_["lateral_friction_coef"] == pytest.approx(0.4, rel=0.05)
    # no sample stands still: the husky's rest level (0.59 A) is kept and the idle current is the rest of 0.8 A
    assert model.rest_current_a_.tolist() == [0.59, 0.59]
    assert model.rest_current_a_ + model.idle_current_a_ == pytest.approx([0.8, 0.8], abs=0.05)
    assert model.ground_.rolling_resistance_coef == pytest.approx(0.06, rel=0.05)
    assert model.cost_ < 1e-3
    assert model.score(logs) > 0.99


def test_physics_model_uses_measured_wheel_speeds_for_side_speeds():
    # wheel-derived omega = (vR - vL) / 0.555 m: the side speeds are the wheel speeds (chi = 1)
    husky = robot_preset("husky")
    wheels = dataclasses.replace(husky, track_width_multiplier=0.555 / husky.track_width_m)
    ground = ground_preset("asphalt")
    measured = LogMeta(velocity_source="measured", track_width_m=0.555)
    logs = [_physics_truth(s, 0.06, 0.4, 0.8, wheels, ground, measured) for s in (0, 1)]
    assert PhysicsCurrentModel().fit(logs).cost_ < 1e-3
    commanded = [_physics_truth(s, 0.06, 0.4, 0.8, wheels, ground) for s in (0, 1)]
    assert PhysicsCurrentModel().fit(commanded).cost_ > 1e-2  # husky's own chi 1.875 is used


def test_physics_model_validates_its_parameters():
    log = _log(*_motion(0), np.ones(400), np.ones(400))
    with pytest.raises(UnknownNameError, match="fit parameter"):
        PhysicsCurrentModel(fit_parameters=("magic_coef",)).fit(log)
    with pytest.raises(InvalidParameterError, match="not a string"):
        PhysicsCurrentModel(fit_parameters="idle_current_a").fit(log)
    with pytest.raises(UnknownNameError):
        PhysicsCurrentModel(robot="rover9000").fit(log)
    with pytest.raises(InvalidParameterError, match="clip_negative"):
        PhysicsCurrentModel(clip_negative=1).fit(log)


def test_physics_model_persists_custom_robot_and_ground(tmp_path):
    robot = dataclasses.replace(robot_preset("husky"), mass_kg=60.0)
    ground = ground_preset("snow")
    logs = [_physics_truth(0, 0.1, 0.3, 0.5, robot, ground)]
    model = PhysicsCurrentModel(robot, ground, fit_parameters=("rolling_resistance_coef", "idle_current_a")).fit(logs)
    again = PhysicsCurrentModel.load(model.save(tmp_path / "p.pt"))
    assert again.robot == robot and again.ground == ground
    assert np.array_equal(again.predict(logs[0]), model.predict(logs[0]))


def _with_stops(seed, rest_a, moving_extra_a, robot, ground):
    """A log that stands still (speeds exactly 0) for its first and last 5 s: at rest the sensor
    logs ``rest_a`` per side, moving it logs rest + extra + the physics' motoring current."""
    t, v, w = _motion(seed)
    still = (t < 5.0) | (t >= t[-1] - 5.0)
    v, w = np.where(still, 0.0, v), np.where(still, 0.0, w)
    model = PhysicsEnergyModel(robot, DRIVE_EFFECTS)
    res = model.power(v, w, ground, accel_mps2=np.gradient(v, t), alpha_radps2=np.gradient(w, t), time_s=t)
    sign = np.sign(res.motor_speed_radps)  # in the direction of rotation; from rest, the current that starts it
    motoring = np.where(sign != 0, res.motor_current_a * sign, np.abs(res.motor_current_a))
    rest = at_rest(v, w, np.gradient(v, t), np.gradient(w, t))  # still, and not starting or stopping
    cur = np.maximum(np.asarray(rest_a) + motoring + np.where(rest, 0.0, moving_extra_a)[:, None], 0.0)
    return _log(t, v, w, cur[:, 0], cur[:, 1])


def test_rest_is_a_level_of_its_own_apart_from_the_idle_current_of_driving():
    # Standing still the sensor reads 0.35 / 0.5 A; driving adds 1.5 A of speed-independent current.
    # One idle constant (the old model) had to split the difference; the rest level takes the rest.
    robot, ground = robot_preset("husky"), ground_preset("asphalt")
    logs = [_with_stops(s, [0.35, 0.5], 1.5, robot, ground) for s in (0, 1)]
    model = PhysicsCurrentModel("husky", "asphalt", fit_parameters=("idle_current_a", "rest_current_a")).fit(logs)
    assert model.rest_current_a_ == pytest.approx([0.35, 0.5], abs=1e-9)
    assert model.fitted_["rest_left_a"] == pytest.approx(0.35) and model.fitted_["rest_right_a"] == pytest.approx(0.5)
    assert model.idle_current_a_ == pytest.approx(1.5, abs=0.02)
    for log in logs:
        rest = rest_samples(log)
        assert rest.sum() >= 80  # the stops, less the samples where the robot starts or stops
        np.testing.assert_allclose(model.predict(log)[rest], np.tile([0.35, 0.5], (rest.sum(), 1)), atol=1e-9)
    # not fitted: the robot's rest level (the Husky's sensor: 0.59 A), nothing learned from the logs
    given = PhysicsCurrentModel("husky", "asphalt", fit_parameters=()).fit(logs)
    assert given.rest_current_a_.tolist() == [0.59, 0.59] and given.idle_current_a_ == 0.0 and given.fitted_ == {}
    # logs that never stand still keep the robot's rest level even when it is fitted
    moving = PhysicsCurrentModel("husky", "asphalt", fit_parameters=("rest_current_a",)).fit(
        [_physics_truth(0, 0.06, 0.4, 0.8, robot, ground)])
    assert moving.rest_current_a_.tolist() == [0.59, 0.59]


def _two_ground_log(seed, robot, grounds, labels, crr, meta=None, slope_rad=0.0, pose=None):
    """Currents of the physics on a per-sample ground (``labels`` indexes ``grounds``), rolling resistance ``crr``."""
    t, v, w = _motion(seed)
    names = list(grounds)
    truth = [grounds[g].replace(rolling_resistance_coef=c) for g, c in zip(names, crr)]
    res = PhysicsEnergyModel(robot, DRIVE_EFFECTS).power(
        v, w, truth, accel_mps2=np.gradient(v, t), alpha_radps2=np.gradient(w, t), slope_rad=slope_rad, time_s=t,
        ground_index=labels)
    cur = np.maximum(0.59 + res.motor_current_a * np.sign(res.motor_speed_radps), 0.0)
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    return InteractionLog(t, v, w, cur[:, 0], cur[:, 1], ta, np.full(ta.size, 9.81), meta=meta or LogMeta(),
                          ground=np.array(names)[labels], pose_xyh=pose)


def test_a_ground_per_label_predicts_each_sample_on_its_own_ground():
    robot = robot_preset("husky")
    grounds = {"grass": ground_preset("grass"), "asphalt": ground_preset("asphalt")}
    t, _, _ = _motion(0)
    labels = (t > 15.0).astype(int)  # grass, then asphalt
    log = _two_ground_log(0, robot, grounds, labels, [grounds["grass"].rolling_resistance_coef,
                                                       grounds["asphalt"].rolling_resistance_coef])
    both = PhysicsCurrentModel("husky", {"grass": "grass", "asphalt": "asphalt"}, fit_parameters=()).fit(log)
    np.testing.assert_allclose(both.predict(log), log_currents_of(log), atol=1e-9)
    assert both.ground_ is None and set(both.grounds_) == {"grass", "asphalt"}
    # one ground for the whole log is wrong on the other ground's samples only
    grass_only = PhysicsCurrentModel("husky", "grass", fit_parameters=()).fit(log).predict(log)
    np.testing.assert_allclose(grass_only[labels == 0], both.predict(log)[labels == 0], atol=1e-9)
    assert np.abs(grass_only[labels == 1] - both.predict(log)[labels == 1]).max() > 0.1


def log_currents_of(log):
    return np.column_stack([log.current_left_a, log.current_right_a])


def test_a_ground_per_label_fits_each_ground_its_own_coefficient(tmp_path):
    robot = robot_preset("husky")
    grounds = {"grass": ground_preset("grass"), "asphalt": ground_preset("asphalt")}
    logs = []
    for seed in (0, 1):
        t, _, _ = _motion(seed)
        labels = ((t // 10.0) % 2).astype(int)  # alternating 10 s stretches
        logs.append(_two_ground_log(seed, robot, grounds, labels, [0.09, 0.03]))
    model = PhysicsCurrentModel("husky", grounds, fit_parameters=("rolling_resistance_coef",)).fit(logs)
    assert model.fitted_["grass.rolling_resistance_coef"] == pytest.approx(0.09, rel=0.03)
    assert model.fitted_["asphalt.rolling_resistance_coef"] == pytest.approx(0.03, rel=0.03)
    assert model.grounds_["grass"].rolling_resistance_coef == pytest.approx(0.09, rel=0.03)
    again = PhysicsCurrentModel.load(model.save(tmp_path / "per_ground.zip"))
    assert set(again.ground) == {"grass", "asphalt"}
    assert np.array_equal(again.predict(logs[0]), model.predict(logs[0]))


def test_a_ground_per_label_refuses_logs_it_cannot_place():
    grounds = {"grass": "grass", "asphalt": "asphalt"}
    t, v, w = _motion(0)
    bare = _log(t, v, w, np.ones(t.size), np.ones(t.size))
    with pytest.raises(DataError, match="needs ground labels"):
        PhysicsCurrentModel("husky", grounds, fit_parameters=()).fit(bare)
    snow = _log(t, v, w, np.ones(t.size), np.ones(t.size), LogMeta(ground_label="snow"))
    with pytest.raises(DataError, match=r"drives on \['snow'\]"):
        PhysicsCurrentModel("husky", grounds, fit_parameters=()).fit(snow)
    with pytest.raises(InvalidParameterError, match="at least one ground label"):
        PhysicsCurrentModel("husky", {}).fit(snow)
    with pytest.raises(InvalidParameterError, match=r"ground\['grass'\] must be"):
        PhysicsCurrentModel("husky", {"grass": 3.0}).fit(snow)


def test_a_model_on_a_map_drives_the_slope_under_its_poses(tmp_path):
    from terrain.procedural import ramp_map

    robot, ground = robot_preset("husky"), ground_preset("asphalt")
    tmap = ramp_map((80, 80), 1.0, grade=0.15, axis="x")
    t, v, w = _motion(0)
    heading = np.cumsum(w) * (t[1] - t[0])
    x = 10.0 + np.cumsum(v * np.cos(heading)) * (t[1] - t[0]) * 0.5
    y = 40.0 + np.cumsum(v * np.sin(heading)) * (t[1] - t[0]) * 0.5
    pose = np.column_stack([x, y, heading])
    slope = np.arctan(0.15 * np.cos(heading))
    log = _two_ground_log(0, robot, {"asphalt": ground}, np.zeros(t.size, dtype=int),
                          [ground.rolling_resistance_coef], slope_rad=slope, pose=pose)
    on_map = PhysicsCurrentModel("husky", "asphalt", fit_parameters=(), terrain=tmap).fit(log)
    np.testing.assert_allclose(on_map.predict(log), log_currents_of(log), atol=1e-9)
    level = PhysicsCurrentModel("husky", "asphalt", fit_parameters=()).fit(log)
    assert np.abs(level.predict(log) - log_currents_of(log)).max() > 1.0
    # the map is not stored in the file, which records that the model needs one: no silent level ground
    loaded = PhysicsCurrentModel.load(on_map.save(tmp_path / "on_map.zip"))
    assert loaded.terrain is None and loaded.on_map_ and not level.on_map_
    with pytest.raises(DataError, match=r"give the map again with with_terrain\(tmap\)"):
        loaded.predict(log)
    np.testing.assert_array_equal(loaded.with_terrain(tmap).predict(log), on_map.predict(log))
    np.testing.assert_array_equal(PhysicsCurrentModel.load(level.save(tmp_path / "level.zip")).predict(log),
                                  level.predict(log))
    with pytest.raises(DataError, match="needs its poses"):
        on_map.predict(dataclasses.replace(log, pose_xyh=None))
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        PhysicsCurrentModel(terrain="map.npz").fit(log)


def test_a_model_on_a_map_holds_the_robot_standing_on_its_slope():
    """Standing still on a ramp the motors hold the robot: rest level plus m g sin(pitch) r / 2 a side through the
    gear; on the ramp's level part (and on a model without a map) the rest level alone, exactly."""
    from terrain.procedural import ramp_map

    tmap = ramp_map((80, 80), 1.0, grade=0.15, axis="x")
    t = np.arange(0.0, 4.0, 0.1)
    still = np.zeros(t.size)
    flat = np.full(t.size, 0.0)
    pose = np.column_stack([np.full(t.size, 40.0), np.full(t.size, 40.0), flat])
    log = _log(t, still, still, np.ones(t.size), np.ones(t.size), LogMeta(robot="husky"))
    log = dataclasses.replace(log, pose_xyh=pose)
    on_map = PhysicsCurrentModel("husky", "asphalt", fit_parameters=(), terrain=tmap).fit(log)
    level = PhysicsCurrentModel("husky", "asphalt", fit_parameters=()).fit(log)
    robot = robot_preset("husky")
    motor = robot.motor
    pitch = np.arctan(0.15)
    holding = (robot.mass_kg * 9.81 * np.sin(pitch) / 2.0 * robot.wheel_radius_m
               / (motor.gear_ratio * motor.gear_efficiency * motor.torque_constant_nm_per_a))
    np.testing.assert_allclose(on_map.predict(log), robot.rest_current_a + holding, rtol=0.02)
    np.testing.assert_array_equal(level.predict(log), np.full((t.size, 2), robot.rest_current_a))
    facing_across = dataclasses.replace(log, pose_xyh=pose + [0.0, 0.0, np.pi / 2])  # across the slope: no pitch
    np.testing.assert_allclose(on_map.predict(facing_across), robot.rest_current_a, atol=1e-9)
