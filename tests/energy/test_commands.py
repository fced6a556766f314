"""Tests of energy.commands: the CommandProfile and its series checks."""

from __future__ import annotations

import numpy as np
import pytest

from energy import CommandProfile
from energy.profiles import waypoint_commands
from terrain import DataError, InvalidParameterError


# ------------------------------------------------------------------ CommandProfile
def test_profile_from_poses_recovers_the_commands() -> None:
    p = waypoint_commands([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], 0.4, dt_s=0.005)
    q = CommandProfile.from_poses(p.time_s, p.pose_xyh)
    assert np.abs(q.v_mps - p.v_mps).max() < 0.01
    assert np.abs(q.omega_radps - p.omega_radps).max() < 0.02


def test_profile_validation() -> None:
    with pytest.raises(DataError, match="uniformly spaced"):
        CommandProfile([0.0, 0.1, 0.3], [0.0] * 3, [0.0] * 3)
    with pytest.raises(DataError, match="strictly increasing"):
        CommandProfile([0.0, 0.1, 0.1], [0.0] * 3, [0.0] * 3)
    with pytest.raises(InvalidParameterError, match="length of time_s"):
        CommandProfile([0.0, 0.1, 0.2], [0.0] * 2, [0.0] * 3)
    with pytest.raises(DataError, match="finite"):
        CommandProfile([0.0, 0.1, 0.2], [0.0, np.nan, 0.0], [0.0] * 3)
    with pytest.raises(InvalidParameterError, match="pose_xyh"):
        CommandProfile([0.0, 0.1, 0.2], [0.0] * 3, [0.0] * 3, np.zeros((3, 2)))
