"""Tests of planner.settings: PlannerSettings defaults and its range checks."""

from __future__ import annotations

import dataclasses

import pytest

from planner import PlannerSettings
from terrawatt_base.errors import InvalidParameterError


def test_defaults_are_valid_and_frozen():
    s = PlannerSettings()
    assert s.lattice_stride_cells == 1 and s.range_m is None and 0.0 <= s.goal_bias <= 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.goal_bias = 0.5


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rewire_factor": 0.0}, "rewire_factor"),
        ({"range_m": -1.0}, "range_m"),
        ({"goal_bias": 1.5}, "goal_bias"),
        ({"fmt_samples": 5}, "fmt_samples"),
        ({"bit_samples_per_batch": 0}, "bit_samples_per_batch"),
        ({"lattice_stride_cells": 0}, "lattice_stride_cells"),
        ({"anyangle_guide_stride_cells": 0}, "anyangle_guide_stride_cells"),
        ({"anyangle_corridor_cells": 0}, "anyangle_corridor_cells"),
        ({"refine_max_steps": 0}, "refine_max_steps"),
        ({"refine_rounds": 0}, "refine_rounds"),
        ({"coarse_factor": 1}, "coarse_factor"),
        ({"coarse_corridor_m": 0.0}, "coarse_corridor_m"),
    ],
)
def test_values_out_of_range_are_refused_by_name(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        PlannerSettings(**kwargs)
