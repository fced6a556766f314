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


def test_a_robot_is_plain_values_and_back():
    from energy import RobotParams, robot_preset

    husky = robot_preset("husky")
    plain = husky.to_plain()
    assert isinstance(plain["motor"], dict) and RobotParams.from_plain(plain) == husky
    del plain["rest_current_a"]  # a field with a default may be left out
    assert RobotParams.from_plain(plain).rest_current_a == 0.0
    del plain["mass_kg"]
    with pytest.raises(InvalidParameterError, match=r"missing field\(s\) \['mass_kg'\]"):
        RobotParams.from_plain(plain)
    with pytest.raises(InvalidParameterError, match=r"my robot: motor: unknown field\(s\) \['kv'\]"):
        RobotParams.from_plain({**husky.to_plain(), "motor": {**husky.motor.__dict__, "kv": 1.0}}, "my robot")
    with pytest.raises(InvalidParameterError, match="must be a mapping of fields, got 'list'"):
        RobotParams.from_plain([1, 2])
