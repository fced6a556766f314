"""Tests of energy.power: PowerBreakdown (shapes, read-only arrays, energy of a component) and sample times."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from energy.power import PowerBreakdown, check_sample_times, trapezoid
from terrain import DataError, InvalidParameterError, UnknownNameError


def breakdown(n: int = 3, total_w: float = 10.0, **changes) -> PowerBreakdown:
    fields = {}
    for f in dataclasses.fields(PowerBreakdown):
        shape = (n, 2) if f.name.startswith("motor_") else (n,)
        fields[f.name] = np.zeros(shape, dtype=bool if f.name.endswith("exceeded") or f.name == "saturated" else float)
    fields["total_power_w"] = np.full(n, total_w)
    fields["slope_power_w"] = np.arange(n, dtype=float)
    fields.update(changes)
    return PowerBreakdown(**fields)


def test_check_sample_times_gives_float_times():
    t = check_sample_times([0, 1, 3], 3)
    assert t.dtype == np.float64 and t.tolist() == [0.0, 1.0, 3.0]
    assert check_sample_times([5.0], 1).tolist() == [5.0]


@pytest.mark.parametrize(("time_s", "match"), [
    ([0.0, 1.0], r"time_s must be 1-D with 3 samples, got shape \(2,\)"),
    ([[0.0, 1.0, 2.0]], r"got shape \(1, 3\)"),
    ([0.0, np.nan, 2.0], "time_s must be finite"),
    ([0.0, 2.0, 2.0], r"time_s must be strictly increasing; time_s\[1\]=2, time_s\[2\]=2$"),
])
def test_check_sample_times_documented_errors(time_s, match):
    with pytest.raises(DataError, match=match):
        check_sample_times(time_s, 3)


def test_trapezoid_is_numpys():
    assert trapezoid([0.0, 2.0, 2.0], [0.0, 1.0, 3.0]) == pytest.approx(5.0)


def test_energy_of_a_component_by_the_trapezoid_rule():
    pb = breakdown()
    assert pb.n_samples == 3
    assert pb.energy_j([0.0, 1.0, 3.0]) == pytest.approx(30.0)
    assert pb.energy_j([0.0, 1.0, 3.0], "slope_power_w") == pytest.approx(0.5 + 3.0)
    with pytest.raises(UnknownNameError, match=r"component 'motor_current_a' is unknown; expected one of \['armature"):
        pb.energy_j([0.0, 1.0, 3.0], "motor_current_a")
    with pytest.raises(DataError, match="strictly increasing"):
        pb.energy_j([0.0, 0.0, 1.0])


def test_arrays_are_read_only_and_shapes_are_checked():
    pb = breakdown()
    with pytest.raises(ValueError):
        pb.total_power_w[0] = 1.0
    with pytest.raises(InvalidParameterError, match=r"PowerBreakdown.total_power_w must be 1-D, got shape \(3, 1\)"):
        breakdown(total_power_w=np.zeros((3, 1)))
    with pytest.raises(InvalidParameterError, match=r"PowerBreakdown.motor_current_a must have shape \(3, 2\), got \(3,\)"):
        breakdown(motor_current_a=np.zeros(3))
    with pytest.raises(InvalidParameterError, match=r"PowerBreakdown.slope_power_w must have shape \(3,\), got \(2,\)"):
        breakdown(slope_power_w=np.zeros(2))
