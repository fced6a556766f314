"""Small valid robot and motor parameters for the tests of energy.params, energy.robot and energy.ground."""

from __future__ import annotations

from energy import MotorParams, RobotParams


def sample_motor(**kw: object) -> MotorParams:
    base = dict(torque_constant_nm_per_a=0.05, back_emf_v_s_per_rad=0.05,
                armature_resistance_ohm=0.5, max_torque_nm=1.0, max_speed_radps=500.0)
    base.update(kw)
    return MotorParams(**base)


def sample_robot(**kw: object) -> RobotParams:
    base = dict(name="r", mass_kg=10.0, wheel_radius_m=0.1, track_width_m=0.4,
                wheelbase_m=0.3, battery_voltage_v=24.0, drive_kind="skid_steer",
                motor=sample_motor(), max_speed_mps=1.0, max_omega_radps=2.0, turn_rate_radps=0.5)
    base.update(kw)
    return RobotParams(**base)
