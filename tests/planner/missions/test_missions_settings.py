"""Tests of planner.missions.settings: AdaptiveSettings defaults and its checks (named test_missions_settings.py:
tests/planner/test_settings.py holds planner.settings, and test modules need distinct names)."""

from __future__ import annotations

import pytest

from planner import AdaptiveSettings
from planner.missions.settings import UPDATE_SCOPES
from terrawatt_base.errors import InvalidParameterError


def test_defaults_are_valid_and_speeds_become_a_tuple():
    s = AdaptiveSettings()
    assert s.update_scope in UPDATE_SCOPES and s.planner == "lattice"
    assert isinstance(s.excitation_speeds_mps, tuple) and all(v > 0 for v in s.excitation_speeds_mps)
    assert AdaptiveSettings(excitation_speeds_mps=[0.3, 0.6]).excitation_speeds_mps == (0.3, 0.6)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"speed_mps": 0.0}, "speed_mps"),
        ({"leg_length_m": -1.0}, "leg_length_m"),
        ({"excitation_duration_s": 2.0}, "excitation_duration_s"),
        ({"policy": "always"}, "policy must be an UpdatePolicy"),
        ({"update_scope": "everywhere"}, "update_scope must be one of"),
        ({"validation_fraction": 0.6}, "validation_fraction"),
        ({"excitation_speeds_mps": ()}, "excitation_speeds_mps must be numbers > 0"),
        ({"excitation_speeds_mps": 0.5}, "excitation_speeds_mps must be numbers > 0"),
        ({"excitation_speeds_mps": (0.5, -1.0)}, "excitation_speeds_mps"),
        ({"max_updates": -1}, "max_updates"),
        ({"max_legs": 0}, "max_legs"),
        ({"in_run_update": "yes"}, "in_run_update"),
        ({"seed": None}, "seed must be an integer"),
    ],
)
def test_bad_values_are_refused_by_name(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        AdaptiveSettings(**kwargs)
