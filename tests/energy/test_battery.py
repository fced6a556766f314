"""Tests of energy.battery: closed-form discharges, reserve crossing, stepping the state of charge, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import Battery, discharge_from_power, energy_budget
from terrain import DataError, InvalidParameterError


def test_constant_current_soc_closed_form():
    # No losses: a constant power P draws I = P / V and SoC = initial - I t / (3600 C) at every sample.
    b = Battery(capacity_ah=7.5, voltage_v=24.0, min_reserve_pct=10.0, initial_soc=0.9)
    t = np.linspace(0.0, 1234.5, 97)
    current = 3.3
    d = discharge_from_power(b, t, np.full_like(t, 24.0 * current))
    np.testing.assert_allclose(d.soc, 0.9 - current * t / (3600.0 * 7.5), rtol=0, atol=1e-13)
    np.testing.assert_allclose(d.charge_mah, current * t / 3.6, rtol=1e-13)
    np.testing.assert_allclose(d.energy_j, 24.0 * current * t, rtol=1e-13)
    assert d.reserve_crossed_index is None and not d.reserve_crossed


def test_constant_power_draws_p_over_v_without_resistance():
    b = Battery(capacity_ah=2.0, voltage_v=12.0)
    t = np.linspace(0.0, 600.0, 11)
    dp = discharge_from_power(b, t, np.full(11, 24.0))
    np.testing.assert_allclose(dp.current_a, 2.0)
    np.testing.assert_allclose(dp.soc, 1.0 - 2.0 * t / (3600.0 * 2.0), atol=1e-15)


def test_reserve_crossing_time_closed_form():
    # 1 Ah, start full, reserve 25 %, 2 A: crossing at (1 - 0.25) * 3600 / 2 = 1350 s.
    b = Battery(capacity_ah=1.0, voltage_v=12.0, min_reserve_pct=25.0)
    t = np.arange(0.0, 2001.0, 7.0)
    d = discharge_from_power(b, t, np.full(t.size, 24.0))  # 2 A
    assert d.reserve_crossed_time_s == pytest.approx(1350.0, abs=1e-9)
    k = d.reserve_crossed_index
    assert d.soc[k] < 0.25 <= d.soc[k - 1]
    assert t[k - 1] <= 1350.0 < t[k]
    budget = energy_budget(d, predicted_energy_j=0.0)
    assert not budget.feasible and budget.predicted_feasible
    assert budget.reserve_crossed_time_s == pytest.approx(1350.0, abs=1e-9)
    assert budget.reserve_margin_pct < 0 and budget.reserve_margin_wh < 0


def test_start_below_reserve_crosses_at_first_sample():
    b = Battery(capacity_ah=1.0, voltage_v=12.0, min_reserve_pct=50.0, initial_soc=0.4)
    d = discharge_from_power(b, [0.0, 1.0, 2.0], [0.0, 0.0, 0.0])
    assert d.reserve_crossed_index == 0 and d.reserve_crossed_time_s == 0.0


def test_soc_monotone_for_non_negative_current():
    rng = np.random.default_rng(3)
    b = Battery(capacity_ah=3.0, voltage_v=24.0, internal_resistance_ohm=0.05, peukert_exponent=1.2)
    t = np.cumsum(rng.uniform(0.01, 0.5, 400))
    power = np.abs(rng.normal(50.0, 40.0, t.size))
    power[::17] = 0.0
    d = discharge_from_power(b, t, power)
    assert np.all(np.diff(d.soc) <= 0)
    assert np.all(np.diff(d.charge_mah) >= 0) and np.all(np.diff(d.energy_j) >= 0)
    assert d.soc[0] == b.initial_soc


def test_internal_resistance_roundtrip_and_extra_charge():
    b = Battery(capacity_ah=5.0, voltage_v=24.0, internal_resistance_ohm=0.2)
    p = np.array([-50.0, 0.0, 10.0, 300.0, 700.0])
    i = b.current_a(p)
    np.testing.assert_allclose(b.terminal_power_w(i), p, rtol=1e-12, atol=1e-12)
    assert np.all(i[2:] > p[2:] / 24.0)  # losses: more current than P / V
    with pytest.raises(InvalidParameterError, match="maximum deliverable power"):
        b.current_a([b.max_power_w * 1.01])


def test_peukert_depletes_faster_above_reference_current():
    # Reference current 1 A (20 Ah over 20 h); at 4 A with k = 1.5, I_eff = 4 * 4**0.5 = 8 A.
    b = Battery(capacity_ah=20.0, voltage_v=12.0, peukert_exponent=1.5)
    d = discharge_from_power(b, [0.0, 3600.0], [48.0, 48.0])  # 4 A
    assert d.final_soc == pytest.approx(1.0 - 8.0 / 20.0, abs=1e-12)
    assert d.total_charge_mah == pytest.approx(4000.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"capacity_ah": 0.0}, "capacity_ah must be > 0"),
        ({"capacity_ah": -2.0}, "capacity_ah must be > 0"),
        ({"capacity_ah": math.nan}, "capacity_ah must be finite"),
        ({"voltage_v": 0.0}, "voltage_v must be > 0"),
        ({"min_reserve_pct": 100.0}, "min_reserve_pct must be < 100"),
        ({"min_reserve_pct": -1.0}, "min_reserve_pct must be >= 0"),
        ({"initial_soc": 0.0}, "initial_soc must be > 0"),
        ({"initial_soc": 1.5}, "initial_soc must be <= 1"),
        ({"internal_resistance_ohm": -0.1}, "internal_resistance_ohm must be >= 0"),
        ({"peukert_exponent": 0.9}, "peukert_exponent must be >= 1"),
        ({"capacity_ah": True}, "capacity_ah must be a real number"),
    ],
)
def test_battery_validation(kwargs, match):
    args = {"capacity_ah": 10.0, "voltage_v": 24.0} | kwargs
    with pytest.raises(InvalidParameterError, match=match):
        Battery(**args)


def test_series_validation():
    b = Battery(1.0, 12.0)
    with pytest.raises(DataError, match="strictly increasing"):
        discharge_from_power(b, [0.0, 1.0, 1.0], [1.0, 1.0, 1.0])
    with pytest.raises(DataError, match="at least 2 samples"):
        discharge_from_power(b, [0.0], [1.0])
    with pytest.raises(InvalidParameterError, match="must have the shape of time_s"):
        discharge_from_power(b, [0.0, 1.0], [1.0])
    with pytest.raises(DataError, match="power_w must be finite"):
        discharge_from_power(b, [0.0, 1.0], [1.0, math.nan])
    with pytest.raises(InvalidParameterError, match="battery must be a Battery"):
        discharge_from_power("battery", [0.0, 1.0], [1.0, 1.0])
    d = discharge_from_power(b, [0.0, 1.0, 2.0], [1.0, 1.0, 1.0])
    with pytest.raises(InvalidParameterError, match="predicted_energy_j must be >= 0"):
        energy_budget(d, -1.0)
    with pytest.raises(InvalidParameterError, match="must be given together"):
        energy_budget(d, 1.0, segment_index=[0, 0, 0])
    with pytest.raises(InvalidParameterError, match=r"segment_index must lie in \[0, 0\]"):
        energy_budget(d, 1.0, segment_index=[0, 1, 1], segment_predicted_j=[1.0])


# ------------------------------------------------------------------ stepping the state of charge
def test_soc_after_energy_matches_a_constant_power_discharge() -> None:
    # internal resistance and Peukert are applied exactly as by discharge_from_power
    b = Battery(capacity_ah=2.0, voltage_v=24.0, internal_resistance_ohm=0.3, peukert_exponent=1.05,
                min_reserve_pct=0.0, initial_soc=0.9)
    power, duration = 30.0, 1200.0
    d = discharge_from_power(b, [0.0, duration], [power, power])
    stepped = b.soc_after_energy(power * duration, power_w=power)
    assert stepped == pytest.approx(d.final_soc, rel=1e-12)
    # two half steps from an explicit soc equal one whole step
    half = b.soc_after_energy(power * duration / 2, power_w=power)
    assert b.soc_after_energy(power * duration / 2, power_w=power, soc=half) == pytest.approx(stepped, rel=1e-12)
    # more than a plain soc -= E / (C V): losses cost charge
    assert 0.5 < stepped < 0.9 - power * duration / (2.0 * 24.0 * 3600.0)


def test_soc_after_never_goes_below_zero_and_time_to_empty() -> None:
    b = Battery(capacity_ah=1e-4, voltage_v=24.0)
    assert b.soc_after_energy(1000.0, power_w=100.0) == 0.0
    assert b.soc_after(5.0) == 0.0 and b.soc_after(0.05) == pytest.approx(0.5)
    assert b.time_to_empty_s(100.0) == pytest.approx(0.0864)
    assert Battery(1.0, 10.0).time_to_empty_s(5.0, soc=0.25) == pytest.approx(1800.0)
    assert b.soc_after_energy(0.0, power_w=1.0, soc=0.0) == 0.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"energy_j": -1.0, "power_w": 10.0}, "energy_j must be >= 0"),
        ({"energy_j": "lots", "power_w": 10.0}, "energy_j must be a real number"),
        ({"energy_j": 1.0, "power_w": 0.0}, "power_w must be > 0"),
        ({"energy_j": 1.0, "power_w": 10.0, "soc": 1.5}, "soc must be <= 1"),
        ({"energy_j": 1.0, "power_w": 1e9}, "maximum deliverable power"),
    ],
)
def test_soc_after_energy_bad_input(kwargs: dict, match: str) -> None:
    b = Battery(capacity_ah=1.0, voltage_v=24.0, internal_resistance_ohm=0.1)
    energy = kwargs.pop("energy_j")
    with pytest.raises(InvalidParameterError, match=match):
        b.soc_after_energy(energy, **kwargs)


def test_battery_string_capacity_names_the_parameter() -> None:
    with pytest.raises(InvalidParameterError, match="Battery.capacity_ah must be a real number, got '20'"):
        Battery(capacity_ah="20", voltage_v=24.0)  # type: ignore[arg-type]

