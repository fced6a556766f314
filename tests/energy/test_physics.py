"""Tests of energy.physics: each effect against its closed form, planner methods, errors."""

from __future__ import annotations

import numpy as np
import pytest

from energy import (
    EFFECTS,
    GroundParams,
    MotorParams,
    PhysicsEnergyModel,
    RobotParams,
    ground_preset,
    robot_preset,
)
from terrain import DataError, InvalidParameterError, UnknownNameError

G = 9.80665
MASS, R, B, N_GEAR, KT, RA = 20.0, 0.1, 0.4, 10.0, 0.05, 0.5


def ideal_robot(**kw: object) -> RobotParams:
    """Ke = Kt, no gear loss, no rotor inertia or damping, generous limits."""
    motor = dict(torque_constant_nm_per_a=KT, back_emf_v_s_per_rad=KT,
                 armature_resistance_ohm=RA, gear_ratio=N_GEAR, gear_efficiency=1.0,
                 max_torque_nm=100.0, max_speed_radps=1e4)
    motor.update(kw.pop("motor_kw", {}))  # type: ignore[arg-type]
    base = dict(name="ideal", mass_kg=MASS, wheel_radius_m=R, track_width_m=B, wheelbase_m=0.3,
                battery_voltage_v=24.0, drive_kind="skid_steer", motor=MotorParams(**motor),
                sensor_power_w=3.0, sensor_power_per_mps_w=2.0, control_standby_power_w=5.0,
                control_startup_power_w=9.0, control_stable_power_w=7.0, startup_duration_s=1.0,
                track_width_multiplier=1.5, max_speed_mps=2.0, max_omega_radps=3.0,
                turn_rate_radps=0.5)
    base.update(kw)
    return RobotParams(**base)


GROUND = GroundParams(name="test", static_friction_coef=0.8, coulomb_friction_coef=0.5,
                      stribeck_velocity_coef_s_per_m=5.0, viscous_friction_coef_s_per_m=0.05,
                      rolling_resistance_coef=0.03, lateral_friction_coef=0.6,
                      longitudinal_slip_coef=0.05, lateral_slip_coef=0.1)


def model(*effects: str, **robot_kw: object) -> PhysicsEnergyModel:
    return PhysicsEnergyModel(ideal_robot(**robot_kw), effects=effects)


# ------------------------------------------------------------------ closed forms, one effect
def test_slope_energy_is_m_g_sin_beta_times_distance() -> None:
    beta, v, dur = 0.1, 0.8, 5.0
    t = np.linspace(0.0, dur, 51)
    e = model("slope").energy_j(t, v, 0.0, GROUND, slope_rad=beta, accel_mps2=0.0)
    assert e == pytest.approx(MASS * G * np.sin(beta) * v * dur, rel=1e-12)
    # downhill: no regeneration, nothing back, nothing spent
    e_down = model("slope").energy_j(t, v, 0.0, GROUND, slope_rad=-beta, accel_mps2=0.0)
    assert e_down == 0.0
    # with 50 % regeneration half of the potential energy comes back
    e_regen = model("slope", regen_efficiency=0.5).energy_j(
        t, v, 0.0, GROUND, slope_rad=-beta, accel_mps2=0.0)
    assert e_regen == pytest.approx(-0.5 * MASS * G * np.sin(beta) * v * dur)


def test_energy_per_metre_slope_only() -> None:
    grade = np.array([-0.2, 0.0, 0.1, 0.3])
    e = model("slope").energy_per_metre_j(0.5, grade, GROUND)
    beta = np.arctan(grade)
    assert np.allclose(e, np.maximum(MASS * G * np.sin(beta), 0.0))


def test_armature_heat_is_i2_r_t() -> None:
    beta, v, dur = 0.15, 0.5, 4.0
    t = np.linspace(0.0, dur, 41)
    per_side_torque_m = MASS / 2 * G * np.sin(beta) * R / N_GEAR
    current = per_side_torque_m / KT
    res = model("slope", "armature_heat").power(v, 0.0, GROUND, slope_rad=beta)
    assert np.allclose(res.motor_current_a, current)
    assert res.armature_heat_power_w[0] == pytest.approx(2 * current**2 * RA)
    e_heat = model("slope", "armature_heat").energy_j(t, v, 0.0, GROUND, slope_rad=beta)
    e_cold = model("slope").energy_j(t, v, 0.0, GROUND, slope_rad=beta)
    assert e_heat - e_cold == pytest.approx(2 * current**2 * RA * dur)
    # terminal voltage is back-EMF plus the resistive drop
    omega_m = N_GEAR * v / R
    assert np.allclose(res.motor_voltage_v, KT * omega_m + RA * current)


def test_inertia_is_kinetic_energy() -> None:
    acc, dur = 0.4, 2.0
    t = np.linspace(0.0, dur, 201)
    v = acc * t
    e = model("inertia").energy_j(t, v, 0.0, GROUND, accel_mps2=np.full_like(t, acc))
    v_end = acc * dur
    assert e == pytest.approx(0.5 * MASS * v_end**2, rel=1e-9)
    # rotor inertia adds the rotors' kinetic energy 2 * Jm * omega_m**2 / 2
    jm = 2e-4
    e_rot = model("inertia", motor_kw={"rotor_inertia_kg_m2": jm}).energy_j(
        t, v, 0.0, GROUND, accel_mps2=np.full_like(t, acc))
    omega_m = N_GEAR * v_end / R
    assert e_rot - e == pytest.approx(jm * omega_m**2, rel=1e-9)
    # the acceleration is differentiated from the speed when not given
    assert model("inertia").energy_j(t, v, 0.0, GROUND) == pytest.approx(e, rel=1e-9)


def test_yaw_inertia_is_rotational_kinetic_energy_with_chi_one() -> None:
    alpha, dur = 0.5, 2.0
    t = np.linspace(0.0, dur, 201)
    m = model("inertia", track_width_multiplier=1.0, yaw_inertia_kg_m2=0.7)
    e = m.energy_j(t, 0.0, alpha * t, GROUND, accel_mps2=0.0, alpha_radps2=alpha)
    assert e == pytest.approx(0.5 * 0.7 * (alpha * dur) ** 2, rel=1e-9)


def test_control_power_is_p_times_t() -> None:
    t = np.arange(0.0, 10.0 + 1e-9, 0.5)
    v = np.where(t >= 2.0, 0.5, 0.0)  # stopped for 2 s, then moving
    m = model("control")
    res = m.power(v, 0.0, GROUND, time_s=t)
    expected = np.where(t < 2.0, 5.0, np.where(t < 3.0, 9.0, 7.0))
    assert np.array_equal(res.control_power_w, expected)
    assert res.energy_j(t, "control_power_w") == pytest.approx(np.trapezoid(expected, t))
    # without time the moving board is at its stable power
    assert np.array_equal(m.power(v, 0.0, GROUND).control_power_w, np.where(v > 0, 7.0, 5.0))
    # constant stable power for T seconds -> P * T
    t2 = np.linspace(0.0, 8.0, 9)
    steady = model("control", startup_duration_s=0.0).energy_j(t2, 0.3, 0.0, GROUND)
    assert steady == pytest.approx(7.0 * 8.0)


def test_startup_restarts_after_each_stop() -> None:
    t = np.arange(0.0, 6.0, 0.25)
    v = np.where((t >= 1.0) & (t < 2.5) | (t >= 4.0), 0.4, 0.0)
    res = model("control").power(v, 0.0, GROUND, time_s=t)
    startup = res.control_power_w == 9.0
    assert np.array_equal(t[startup], np.r_[np.arange(1.0, 2.0, 0.25), np.arange(4.0, 5.0, 0.25)])


def test_sensor_power_is_base_plus_per_speed() -> None:
    v = np.array([0.0, 0.5, -1.0])
    res = model("sensor").power(v, 0.0, GROUND)
    assert np.allclose(res.sensor_power_w, 3.0 + 2.0 * np.abs(v))
    assert np.allclose(res.total_power_w, res.sensor_power_w)


def test_coulomb_friction_is_rolling_resistance() -> None:
    e = model("coulomb_friction").energy_per_metre_j(0.7, [0.0], GROUND)
    assert e[0] == pytest.approx(GROUND.rolling_resistance_coef * MASS * G)


def test_stribeck_excess_decays_with_speed() -> None:
    v = np.array([0.05, 0.5, 2.0])
    res = model("stribeck").power(v, 0.0, GROUND)
    excess = GROUND.rolling_resistance_coef * (0.8 / 0.5 - 1.0)
    expected = excess * MASS * G * np.exp(-5.0 * v) * v
    assert np.allclose(res.friction_power_w, expected)
    assert np.allclose(res.drive_power_w, expected)
    assert np.all(np.diff(res.drive_power_w / v) < 0)


def test_static_friction_costs_stall_current_at_breakaway() -> None:
    res_on = model("static_friction", "coulomb_friction", "armature_heat").power(
        0.0, 0.0, GROUND, accel_mps2=0.1)
    res_off = model("coulomb_friction", "armature_heat").power(0.0, 0.0, GROUND, accel_mps2=0.1)
    f_side = GROUND.rolling_resistance_coef * (0.8 / 0.5) * MASS * G / 2
    current = f_side * R / N_GEAR / KT
    assert np.allclose(res_on.motor_current_a, current)
    assert res_on.total_power_w[0] == pytest.approx(2 * RA * current**2)
    assert res_on.total_power_w[0] > res_off.total_power_w[0] > 0
    # once rolling, static friction alone adds nothing
    moving = model("static_friction").power(0.5, 0.0, GROUND)
    assert moving.total_power_w[0] == 0.0


def test_viscous_friction_closed_form() -> None:
    bm, v = 1e-4, 0.6
    res = model("viscous_friction", motor_kw={"viscous_damping_nm_s_per_rad": bm}).power(
        v, 0.0, GROUND)
    omega_m = N_GEAR * v / R
    expected = 0.05 * MASS * G * v**2 + 2 * bm * omega_m**2
    assert res.total_power_w[0] == pytest.approx(expected)


def test_longitudinal_slip_loss_closed_form() -> None:
    v = 0.5
    on = model("coulomb_friction", "longitudinal_slip").power(v, 0.0, GROUND)
    off = model("coulomb_friction").power(v, 0.0, GROUND)
    ratio = 0.03 / 0.5
    slip = -0.05 * np.log1p(-ratio)
    f_total = 0.03 * MASS * G
    assert on.longitudinal_slip_power_w[0] == pytest.approx(f_total * v * slip / (1 - slip))
    assert on.total_power_w[0] == pytest.approx(off.total_power_w[0] / (1 - slip))


def test_lateral_slip_zero_straight_positive_in_curve() -> None:
    m = model("lateral_slip")
    straight = m.power(1.0, 0.0, GROUND)
    assert straight.total_power_w[0] == 0.0
    v, w = 1.0, 0.8
    curve = m.power(v, w, GROUND)
    f_y = MASS * v * w
    expected = f_y * 0.1 * f_y / (0.5 * MASS * G) * v
    assert curve.lateral_slip_power_w[0] == pytest.approx(expected)
    assert curve.total_power_w[0] > 0


def test_turning_resistance_pivot_closed_form() -> None:
    w = 0.5
    m = model("turning_resistance")
    res = m.power(0.0, w, GROUND)
    moment = 0.6 * MASS * G * 0.15 / 0.925
    assert res.turning_power_w[0] == pytest.approx(1.5 * moment * w)
    assert res.total_power_w[0] == pytest.approx(1.5 * moment * w)
    # differential drives do not scrub
    diff = model("turning_resistance", drive_kind="differential", track_width_multiplier=1.0)
    assert diff.power(0.0, w, GROUND).total_power_w[0] == 0.0
    # gentle curves cost less than pivots at the same yaw rate (Wong's mu_lat(R))
    assert m.power(1.0, w, GROUND).turning_power_w[0] < res.turning_power_w[0]


def test_gear_losses_divide_motoring_power() -> None:
    kw = {"motor_kw": {"gear_efficiency": 0.8}}
    on = model("slope", "gear_losses", **kw).power(0.5, 0.0, GROUND, slope_rad=0.1)
    off = model("slope", **kw).power(0.5, 0.0, GROUND, slope_rad=0.1)
    assert on.total_power_w[0] == pytest.approx(off.total_power_w[0] / 0.8)


def test_torque_saturation_caps_power() -> None:
    t_max, w_max = 0.2, 150.0
    kw = {"motor_kw": {"max_torque_nm": t_max, "max_speed_radps": w_max}}
    slopes = np.array([0.05, 0.3, 0.6])
    capped = model("slope", "torque_saturation", "speed_saturation", **kw).power(
        1.0, 0.0, GROUND, slope_rad=slopes)
    free = model("slope", **kw).power(1.0, 0.0, GROUND, slope_rad=slopes)
    mech = np.abs(capped.motor_torque_nm * capped.motor_speed_radps)
    assert np.all(mech <= t_max * w_max * (1 + 1e-12))
    assert np.all(np.abs(capped.motor_torque_nm) <= t_max * (1 + 1e-12))
    assert np.array_equal(capped.saturated, [False, True, True])
    assert np.all(capped.drive_power_w <= free.drive_power_w)
    assert capped.drive_power_w[2] < free.drive_power_w[2]
    assert capped.drive_power_w[0] == free.drive_power_w[0]


def test_speed_saturation_clips_motor_speed() -> None:
    m = model("coulomb_friction", "speed_saturation", motor_kw={"max_speed_radps": 50.0})
    res = m.power([0.4, 0.6], 0.0, GROUND)  # 40 and 60 motor rad/s
    assert np.allclose(res.motor_speed_radps[:, 0], [40.0, 50.0])
    assert np.array_equal(res.saturated, [False, True])


# ----------------------------------------------------------- every effect, expected direction
def _rich_case() -> tuple[np.ndarray, ...]:
    t = np.linspace(0.0, 8.0, 161)
    v = np.clip(0.5 * t, 0.0, 1.2)
    w = np.where(t > 4.0, 0.6, 0.0)
    return t, v, w


@pytest.mark.parametrize("effect", [e for e in EFFECTS if not e.endswith("saturation")])
def test_each_effect_adds_energy(effect: str) -> None:
    t, v, w = _rich_case()
    robot = ideal_robot(motor_kw={"rotor_inertia_kg_m2": 1e-4, "gear_efficiency": 0.85,
                                  "viscous_damping_nm_s_per_rad": 1e-5})
    slope = np.full_like(t, 0.1)
    with_all = PhysicsEnergyModel(robot).energy_j(t, v, w, GROUND, slope_rad=slope)
    without = PhysicsEnergyModel(robot, effects=[e for e in EFFECTS if e != effect]).energy_j(
        t, v, w, GROUND, slope_rad=slope)
    assert with_all > without


@pytest.mark.parametrize("effect", ["torque_saturation", "speed_saturation"])
def test_saturation_lowers_energy_when_it_binds(effect: str) -> None:
    t, v, w = _rich_case()
    robot = ideal_robot(motor_kw={"max_torque_nm": 0.15, "max_speed_radps": 100.0})
    others = [e for e in EFFECTS if not e.endswith("saturation")]
    capped = PhysicsEnergyModel(robot, effects=[*others, effect]).energy_j(
        t, v, w, GROUND, slope_rad=0.1)
    free = PhysicsEnergyModel(robot, effects=others).energy_j(t, v, w, GROUND, slope_rad=0.1)
    assert capped < free


# ------------------------------------------------------------------- planner-facing methods
def test_energy_per_metre_nonnegative_shape_and_monotone() -> None:
    m = PhysicsEnergyModel(robot_preset("husky"))
    grade = np.linspace(-0.6, 0.45, 60).reshape(3, 20)
    e = m.energy_per_metre_j(0.5, grade, ground_preset("gravel"))
    assert e.shape == grade.shape and np.all(e >= 0)
    flat = e.reshape(-1)
    assert np.all(np.diff(flat[grade.reshape(-1) >= 0]) > 0)
    # electronics only on steep descents: (sensor + stable control) / speed
    r = robot_preset("husky")
    electronics = (r.sensor_power_w + r.sensor_power_per_mps_w * 0.5 + r.control_stable_power_w)
    assert flat[0] == pytest.approx(electronics / 0.5)
    assert m.energy_per_metre_j(0.5, 0.1, ground_preset("sand")).shape == ()


def test_segment_energy_is_length_times_per_metre() -> None:
    m = PhysicsEnergyModel(robot_preset("jackal"))
    g = ground_preset("grass")
    lengths, grades = np.array([0.0, 1.5, 4.0]), np.array([0.0, 0.05, -0.05])
    assert np.allclose(m.segment_energy_j(lengths, 1.0, grades, g),
                       lengths * m.energy_per_metre_j(1.0, grades, g))


def test_turn_energy() -> None:
    m = PhysicsEnergyModel(robot_preset("husky"))
    g = ground_preset("asphalt")
    e = m.turn_energy_j([0.0, np.pi / 2, -np.pi / 2, np.pi], g)
    assert e[0] == 0.0 and np.all(e[1:] > 0)
    assert e[1] == pytest.approx(e[2]) and e[3] == pytest.approx(2 * e[1])
    # grass has a lower lateral coefficient than asphalt: cheaper to spin
    assert m.turn_energy_j(np.pi, ground_preset("grass"))[()] < e[3]
    assert m.turn_energy_j(np.pi, g, grade=[0.0, 0.2]).shape == (2,)


def test_max_feasible_grade() -> None:
    m = PhysicsEnergyModel(robot_preset("husky"))
    g = ground_preset("grass")
    gmax = m.max_feasible_grade(0.5, g)
    assert 0.1 < gmax < 0.5
    ok = m.power(0.5, 0.0, g, slope_rad=np.arctan([gmax, gmax + 0.01]))
    assert not (ok.saturated[0] or ok.traction_exceeded[0])
    assert ok.saturated[1] or ok.traction_exceeded[1]


# ----------------------------------------------------------------- sanity anchors (notes)
def test_husky_rolling_power_anchors() -> None:
    m = PhysicsEnergyModel(robot_preset("husky"))
    asphalt = m.power(0.5, 0.0, ground_preset("asphalt")).friction_power_w[0]
    grass = m.power(0.5, 0.0, ground_preset("grass")).friction_power_w[0]
    assert 3.7 / 2 < asphalt < 3.7 * 2
    assert 25.0 / 2 < grass < 25.0 * 2


def test_husky_pivot_turn_anchor() -> None:
    husky = robot_preset("husky")
    mu05 = ground_preset("asphalt").replace(lateral_friction_coef=0.5)
    wheel = PhysicsEnergyModel(husky).power(0.0, 0.5, mu05).turning_power_w[0]
    assert 47.0 / 2 < wheel < 47.0 * 2


def test_ground_sequence_with_index_matches_single_grounds() -> None:
    m = PhysicsEnergyModel(robot_preset("jackal"))
    grounds = [ground_preset("asphalt"), ground_preset("sand")]
    v = np.array([0.5, 0.5, 1.0])
    idx = np.array([0, 1, 1])
    mixed = m.power(v, 0.0, grounds, ground_index=idx).total_power_w
    for k in range(3):
        single = m.power(v[k], 0.0, grounds[idx[k]]).total_power_w[0]
        assert mixed[k] == pytest.approx(single)


def test_per_side_currents_in_a_turn() -> None:
    m = PhysicsEnergyModel(robot_preset("husky"))
    res = m.power(0.5, 0.4, ground_preset("asphalt"))
    left, right = res.motor_current_a[0]
    assert right > 0 and left < right  # outer (right) side pushes, inner side brakes
    assert res.motor_current_a.shape == (1, 2)


def test_vectorised_over_thousands_of_samples() -> None:
    rng = np.random.default_rng(0)
    n = 5000
    m = PhysicsEnergyModel(robot_preset("jackal"))
    res = m.power(rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), ground_preset("gravel"),
                  accel_mps2=rng.normal(0, 0.3, n), slope_rad=rng.uniform(-0.2, 0.2, n))
    assert res.total_power_w.shape == (n,) and np.all(np.isfinite(res.total_power_w))
    assert np.all(res.total_power_w >= 0)
    one = m.power(res.motor_speed_radps[:0, 0], 0.0, ground_preset("gravel"))
    assert one.n_samples == 0
    with pytest.raises(ValueError, match="read-only"):
        res.total_power_w[0] = 1.0


# --------------------------------------------------------------------------------- errors
def test_bad_inputs_raise_library_errors() -> None:
    m = PhysicsEnergyModel(robot_preset("jackal"))
    g = ground_preset("asphalt")
    with pytest.raises(InvalidParameterError, match=r"speed_mps has 1 NaN/inf entries"):
        m.power([0.1, np.nan], 0.0, g)
    with pytest.raises(InvalidParameterError, match="slope_rad must lie in"):
        m.power(0.1, 0.0, g, slope_rad=2.0)
    with pytest.raises(InvalidParameterError, match="broadcast to one 1-D shape"):
        m.power([0.1, 0.2], [0.0, 0.0, 0.0], g)
    with pytest.raises(InvalidParameterError, match="scalars or 1-D"):
        m.power(np.zeros((2, 2)), 0.0, g)
    with pytest.raises(InvalidParameterError, match="ground_index is required"):
        m.power(0.1, 0.0, [g])
    with pytest.raises(InvalidParameterError, match=r"ground_index must lie in \[0, 0\]"):
        m.power([0.1, 0.2], 0.0, [g], ground_index=[0, 3])
    with pytest.raises(InvalidParameterError, match="ground must be a GroundParams"):
        m.energy_per_metre_j(0.5, 0.0, "asphalt")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="speed_mps must be > 0"):
        m.energy_per_metre_j(0.0, 0.0, g)
    with pytest.raises(InvalidParameterError, match="grade has 1 NaN/inf entries"):
        m.energy_per_metre_j(0.5, [0.0, np.nan], g)
    with pytest.raises(InvalidParameterError, match="length_m must be >= 0"):
        m.segment_energy_j(-1.0, 0.5, 0.0, g)
    with pytest.raises(DataError, match="strictly increasing"):
        m.energy_j([0.0, 1.0, 1.0], [0.1, 0.1, 0.1], 0.0, g)
    with pytest.raises(InvalidParameterError, match="samples like time_s"):
        m.energy_j([0.0, 1.0, 2.0], [0.1, 0.1], 0.0, g)
    with pytest.raises(DataError, match="at least 2 samples"):
        m.energy_j([0.0], [0.1], 0.0, g)
    res = m.power([0.1, 0.2], 0.0, g)
    with pytest.raises(UnknownNameError, match="component 'warp_power_w' is unknown"):
        res.energy_j([0.0, 1.0], "warp_power_w")


@pytest.mark.parametrize(
    "call",
    [
        lambda m, g: m.power("fast", 0.0, g),
        lambda m, g: m.power(["0.1", "0.2"], 0.0, g),  # numeric strings are refused, not parsed
        lambda m, g: m.energy_j([0.0, 1.0], "fast", 0.0, g),
        lambda m, g: m.energy_per_metre_j("fast", 0.0, g),
        lambda m, g: m.max_feasible_grade("fast", g),
        lambda m, g: m.segment_energy_j(1.0, "fast", 0.0, g),
        lambda m, g: m.energy_per_metre_j(None, 0.0, g),
    ],
)
def test_speed_that_is_not_a_number_names_the_parameter(call) -> None:
    m = PhysicsEnergyModel(robot_preset("jackal"))
    with pytest.raises(InvalidParameterError, match=r"speed_mps must be a real number"):
        call(m, ground_preset("asphalt"))


def test_other_string_inputs_name_their_parameter() -> None:
    m = PhysicsEnergyModel(robot_preset("jackal"))
    g = ground_preset("asphalt")
    with pytest.raises(InvalidParameterError, match="omega_radps must be a real number"):
        m.power(0.5, "left", g)
    with pytest.raises(InvalidParameterError, match="slope_rad must be a real number"):
        m.power(0.5, 0.0, g, slope_rad="steep")
    with pytest.raises(InvalidParameterError, match="grade must be a real number"):
        m.energy_per_metre_j(0.5, "10%", g)
    with pytest.raises(InvalidParameterError, match="resolution must be a real number"):
        m.max_feasible_grade(0.5, g, resolution="fine")
    # numpy scalars and 0-d arrays are numbers
    assert m.energy_per_metre_j(np.float32(0.5), 0.0, g) == pytest.approx(m.energy_per_metre_j(0.5, 0.0, g))
    assert m.energy_per_metre_j(np.array(0.5), 0.0, g) == pytest.approx(m.energy_per_metre_j(0.5, 0.0, g))


def test_effect_names_are_validated() -> None:
    robot = robot_preset("jackal")
    with pytest.raises(UnknownNameError, match=r"effect 'warp_drive' is unknown"):
        PhysicsEnergyModel(robot, effects=["slope", "warp_drive"])
    with pytest.raises(InvalidParameterError, match="not a string"):
        PhysicsEnergyModel(robot, effects="slope")
    with pytest.raises(InvalidParameterError, match="robot must be a RobotParams"):
        PhysicsEnergyModel("jackal")  # type: ignore[arg-type]
    m = PhysicsEnergyModel(robot, effects=["sensor", "slope"])
    assert m.effects == ("slope", "sensor") and m.has("slope") and not m.has("inertia")
    assert PhysicsEnergyModel(robot).effects == EFFECTS
    with pytest.raises(UnknownNameError, match="effect 'gravity'"):
        m.has("gravity")


# ------------------------------------------------------------------------ property checks
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    robot=st.sampled_from(["paper_seed", "jackal", "husky"]),
    ground=st.sampled_from(["asphalt", "sand", "snow", "grass", "ice"]),
    speed_fraction=st.floats(0.05, 1.0),
    grades=st.lists(st.floats(-1.5, 1.5), min_size=1, max_size=20),
)
def test_planner_energies_are_nonnegative(robot: str, ground: str, speed_fraction: float,
                                          grades: list[float]) -> None:
    m = PhysicsEnergyModel(robot_preset(robot))
    g = ground_preset(ground)
    speed = speed_fraction * m.robot.max_speed_mps
    e = m.energy_per_metre_j(speed, grades, g)
    capped = m.energy_per_metre_j(speed, grades, g, infeasible="capped")
    res = m.power(speed, 0.0, g, slope_rad=np.arctan(grades))
    infeasible = res.saturated | res.traction_exceeded
    assert e.shape == (len(grades),) and not np.any(np.isnan(e)) and np.all(e >= 0)
    np.testing.assert_array_equal(np.isinf(e), infeasible)  # impassable exactly where flagged
    assert np.all(np.isfinite(capped)) and np.all(capped >= 0)
    np.testing.assert_array_equal(capped[~infeasible], e[~infeasible])
    turn = m.turn_energy_j(np.array(grades) * 3.0, g)
    assert np.all(turn >= 0) and np.all((turn == 0) == (np.array(grades) == 0))


def test_holding_current_is_gravity_through_the_gear_and_nothing_without_a_slope():
    from energy import PhysicsEnergyModel, ground_preset, robot_preset
    from terrawatt_base.errors import InvalidParameterError

    robot, ground = robot_preset("husky"), ground_preset("asphalt")
    slope = np.radians([0.0, 5.0, -5.0, 10.0])
    hold = PhysicsEnergyModel(robot).holding_current_a(ground, slope)
    motor = robot.motor
    expected = (robot.mass_kg * 9.81 * np.abs(np.sin(slope)) / 2.0 * robot.wheel_radius_m
                / (motor.gear_ratio * motor.gear_efficiency * motor.torque_constant_nm_per_a))
    np.testing.assert_allclose(hold, np.column_stack([expected, expected]), rtol=0.02)
    assert hold[0].tolist() == [0.0, 0.0]
    no_gravity = PhysicsEnergyModel(robot, effects=[e for e in PhysicsEnergyModel(robot).effects if e != "slope"])
    assert np.all(no_gravity.holding_current_a(ground, slope) == 0.0)
    with pytest.raises(InvalidParameterError, match="1-D"):
        PhysicsEnergyModel(robot).holding_current_a(ground, np.zeros((2, 2)))
