"""energy.robot: validation of RobotParams and MotorParams."""

from __future__ import annotations

import pytest
from params_samples import sample_motor, sample_robot

from terrain import InvalidParameterError


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("mass_kg", -1.0, r"RobotParams\.mass_kg must be > 0, got -1\.0"),
        ("mass_kg", float("nan"), "mass_kg must be finite"),
        ("wheel_radius_m", 0.0, "wheel_radius_m must be > 0"),
        ("drive_kind", "tracked", "drive_kind must be one of"),
        ("track_width_multiplier", 0.5, "track_width_multiplier must be >= 1, got 0.5"),
        ("regen_efficiency", 1.5, "regen_efficiency must be <= 1, got 1.5"),
        ("driven_sides", 4, "driven_sides must be 2"),
        ("motor", "big", "motor must be a MotorParams"),
        ("name", "", "name must be a non-empty string"),
        ("mass_kg", "10", "mass_kg must be a real number, got '10' \\(str\\)"),
        ("wheel_radius_m", None, "wheel_radius_m must be a real number"),
        ("name", 7, "RobotParams.name must be a non-empty string"),
    ],
)
def test_robot_validation(field: str, value: object, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        sample_robot(**{field: value})


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("torque_constant_nm_per_a", 0.0, "torque_constant_nm_per_a must be > 0"),
        ("gear_efficiency", 1.2, "gear_efficiency must be <= 1, got 1.2"),
        ("gear_efficiency", 0.0, "gear_efficiency must be > 0"),
        ("rotor_inertia_kg_m2", -1e-3, "rotor_inertia_kg_m2 must be >= 0"),
        ("max_speed_radps", float("inf"), "max_speed_radps must be finite"),
    ],
)
def test_motor_validation(field: str, value: object, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        sample_motor(**{field: value})
