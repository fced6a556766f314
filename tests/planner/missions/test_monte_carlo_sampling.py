"""Tests of planner.missions.monte_carlo_sampling: a sample applies its draw; bad distributions are refused."""

from __future__ import annotations

import pytest

from energy import Battery, ground_preset, robot_preset
from planner import MissionDistributions
from planner.missions import MissionSample
from terrawatt_base.errors import InvalidParameterError


def test_sample_applies_its_draw_to_robot_grounds_and_battery():
    s = MissionSample({"sand": 2.0}, payload_kg=10.0, capacity_fade_pct=25.0, internal_resistance_ohm=0.1,
                      speed_mps=0.4)
    robot = robot_preset("husky")
    assert s.robot(robot).mass_kg == robot.mass_kg + 10.0
    g = s.grounds({"sand": ground_preset("sand"), "asphalt": ground_preset("asphalt")})
    assert g["sand"].rolling_resistance_coef == 2.0 * ground_preset("sand").rolling_resistance_coef
    assert g["sand"].coulomb_friction_coef == 2.0 * ground_preset("sand").coulomb_friction_coef
    assert g["asphalt"] == ground_preset("asphalt")
    b = s.battery(Battery(4.0, 24.0, internal_resistance_ohm=0.5))
    assert b.capacity_ah == 3.0 and b.internal_resistance_ohm == 0.1


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"payload_kg": (5.0, 1.0)}, r"payload_kg must have low <= high"),
        ({"payload_kg": (-1.0, 1.0)}, r"payload_kg\[0\] must be >= 0"),
        ({"capacity_fade_pct": (0.0, 100.0)}, r"capacity_fade_pct\[1\] must be <= 99"),
        ({"ground_coef_scale": (0.0, 1.0)}, r"ground_coef_scale\[0\] must be > 0"),
        ({"speed_scale": (1.0,)}, r"speed_scale must be a \(low, high\) pair"),
        ({"internal_resistance_ohm": (0.0, float("nan"))}, r"internal_resistance_ohm\[1\] must be finite"),
    ],
)
def test_bad_distributions_are_refused(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        MissionDistributions(**kwargs)
