"""energy.sim.noise: how drive currents, the pack and the accelerometer are measured."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from energy import Battery, NoiseModel
from energy.sim.noise import measure_battery, measure_currents
from terrain import InvalidParameterError

DRIVE_A = np.array([[1.0, 2.0], [-0.5, 0.3], [0.0, 4.0]])


def _rngs(seed: int = 0) -> dict[str, np.random.Generator]:
    return {k: np.random.default_rng([seed, i]) for i, k in enumerate(("side_gain", "current_noise", "outliers"))}


def test_defaults_are_the_husky_like_sensor():
    nm = NoiseModel()
    assert (nm.quantisation_step_a, nm.current_offset_a, nm.clip_negative) == (0.13, 0.59, True)
    with pytest.raises(dataclasses.FrozenInstanceError):
        nm.outlier_rate = 0.0  # type: ignore[misc]


def test_off_turns_every_component_off():
    nm = NoiseModel.off()
    for field in dataclasses.fields(NoiseModel):
        value = getattr(nm, field.name)
        assert value in (0.0, False), field.name


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"quantisation_step_a": -0.1}, "NoiseModel.quantisation_step_a must be >= 0"),
        ({"battery_voltage_noise_std_v": float("nan")}, "battery_voltage_noise_std_v must be finite"),
        ({"outlier_rate": -0.01}, "outlier_rate"),
        ({"side_gain_std": "0.1"}, "NoiseModel.side_gain_std must be a real number"),
    ],
)
def test_bad_values_are_refused(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        NoiseModel(**kwargs)


def test_no_noise_measures_the_motoring_currents_exactly():
    clean, meas = measure_currents(NoiseModel.off(), DRIVE_A, _rngs())
    assert np.array_equal(clean, DRIVE_A) and np.array_equal(meas, DRIVE_A)


def test_offset_clipping_and_quantisation_in_that_order():
    nm = dataclasses.replace(NoiseModel.off(), current_offset_a=0.2, clip_negative=True, quantisation_step_a=0.5)
    clean, meas = measure_currents(nm, DRIVE_A, _rngs())
    np.testing.assert_allclose(clean, [[1.2, 2.2], [0.0, 0.5], [0.2, 4.2]])
    np.testing.assert_allclose(meas, [[1.0, 2.0], [0.0, 0.5], [0.0, 4.0]])  # round(x / 0.5) * 0.5


def test_noise_is_drawn_only_from_its_own_generator():
    nm = dataclasses.replace(NoiseModel.off(), current_noise_std_a=0.1)
    rngs = _rngs(3)
    untouched = {k: rngs[k].bit_generator.state for k in ("side_gain", "outliers")}
    clean, meas = measure_currents(nm, DRIVE_A, rngs)
    assert np.array_equal(clean, DRIVE_A) and not np.array_equal(meas, DRIVE_A)
    assert {k: rngs[k].bit_generator.state for k in untouched} == untouched
    _, again = measure_currents(nm, DRIVE_A, _rngs(3))
    assert np.array_equal(meas, again)  # seeded: the same draws


def test_a_side_gain_scales_clean_and_measured_alike():
    nm = dataclasses.replace(NoiseModel.off(), side_gain_std=0.2)
    clean, meas = measure_currents(nm, DRIVE_A, _rngs(1))
    gain = clean[0] / DRIVE_A[0]
    np.testing.assert_allclose(clean, DRIVE_A * gain)
    assert np.array_equal(meas, clean) and not np.allclose(gain, 1.0)


def test_battery_without_noise_delivers_the_power_exactly():
    battery = Battery(capacity_ah=20.0, voltage_v=24.0, internal_resistance_ohm=0.1)
    power = np.array([0.0, 48.0, 240.0])
    v_clean, i_clean, v, i = measure_battery(NoiseModel.off(), battery, power, np.random.default_rng(0))
    np.testing.assert_allclose(v_clean * i_clean, power, atol=1e-9)
    np.testing.assert_allclose(v_clean, 24.0 - 0.1 * i_clean)
    assert np.array_equal(v, v_clean) and np.array_equal(i, i_clean)


def test_battery_noise_is_seeded_and_leaves_the_clean_values():
    battery = Battery(capacity_ah=20.0, voltage_v=24.0)
    power = np.full(2000, 120.0)
    nm = dataclasses.replace(NoiseModel.off(), battery_current_noise_std_a=0.05, battery_voltage_noise_std_v=0.01)
    v_clean, i_clean, v, i = measure_battery(nm, battery, power, np.random.default_rng(4))
    np.testing.assert_allclose(i_clean, 5.0)
    np.testing.assert_allclose(v_clean, 24.0)
    assert (i - i_clean).std() == pytest.approx(0.05, rel=0.1)
    assert (v - v_clean).std() == pytest.approx(0.01, rel=0.1)
    again = measure_battery(nm, battery, power, np.random.default_rng(4))
    assert np.array_equal(again[3], i) and np.array_equal(again[2], v)
