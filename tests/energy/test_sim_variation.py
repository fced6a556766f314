"""energy.sim.variation: slow random variation of a ground's resistance along the path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import ground_preset
from energy.sim import FACTOR_LOG_STEP, GroundVariation, variation_factor, varied_ground_table
from terrain import InvalidParameterError


def test_defaults_and_bad_values():
    var = GroundVariation(relative_std=0.1)
    assert (var.length_scale_m, var.vibration_coupling) == (2.0, 1.0)
    with pytest.raises(InvalidParameterError, match="GroundVariation.relative_std"):
        GroundVariation(relative_std=2.5)
    with pytest.raises(InvalidParameterError, match="length_scale_m must be > 0"):
        GroundVariation(relative_std=0.1, length_scale_m=0.0)
    with pytest.raises(InvalidParameterError, match="vibration_coupling must be >= 0"):
        GroundVariation(relative_std=0.1, vibration_coupling=-1.0)
    with pytest.raises(TypeError):
        GroundVariation(0.1)  # type: ignore[misc]


def test_grounds_without_variation_have_factor_one():
    index = np.array([0, 0, 1, 1])
    travel = np.linspace(0.0, 3.0, 4)
    f = variation_factor(index, travel, [None, GroundVariation(relative_std=0.0)], np.random.SeedSequence(1))
    assert np.array_equal(f, np.ones(4))


def test_the_factor_is_seeded_log_normal_with_mean_one():
    n = 200_000
    travel = np.linspace(0.0, 20_000.0, n)
    var = GroundVariation(relative_std=0.2, length_scale_m=1.0)
    f = variation_factor(np.zeros(n, int), travel, [var], np.random.SeedSequence(7))
    assert np.all(f > 0)
    assert np.log(f).std() == pytest.approx(0.2, rel=0.05)
    assert f.mean() == pytest.approx(1.0, abs=0.01)
    again = variation_factor(np.zeros(n, int), travel, [var], np.random.SeedSequence(7))
    assert np.array_equal(f, again)


def test_the_factor_is_smooth_over_the_length_scale():
    travel = np.linspace(0.0, 100.0, 10_001)  # 1 cm steps
    f = variation_factor(np.zeros(travel.size, int), travel, [GroundVariation(relative_std=0.2, length_scale_m=5.0)],
                         np.random.SeedSequence(3))
    assert np.max(np.abs(np.diff(np.log(f)))) < 0.01  # no jumps within 1 cm


def test_the_table_scales_resistance_by_the_quantised_factor():
    wood = ground_preset("coated_wood")
    index = np.array([0, 0, 0])
    factor = np.array([1.0, 1.1, 1.1001])
    table, which, quantised = varied_ground_table([wood], index, factor)
    assert len(table) == 2 and table[0] is wood  # level 0 keeps the ground itself
    assert which.tolist() == [0, 1, 1]
    level = round(math.log(1.1) / FACTOR_LOG_STEP)
    f = math.exp(level * FACTOR_LOG_STEP)
    assert quantised.tolist() == pytest.approx([1.0, f, f])
    assert abs(f - 1.1) < 1.1 * FACTOR_LOG_STEP
    assert table[1].rolling_resistance_coef == pytest.approx(wood.rolling_resistance_coef * f)
    assert table[1].viscous_friction_coef_s_per_m == pytest.approx(wood.viscous_friction_coef_s_per_m * f)
    assert table[1].lateral_friction_coef == pytest.approx(wood.effective_lateral_friction_coef * f)
    assert table[1].coulomb_friction_coef == wood.coulomb_friction_coef  # not a resistance term
