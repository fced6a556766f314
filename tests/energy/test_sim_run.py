"""energy.sim.run: TruthRun, a synthetic log with the noise-free truth behind it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from energy import NoiseModel, TruthSimulator, robot_preset
from energy.sim import PAPER_GROUNDS, TruthRun
from terrain import InvalidParameterError


@pytest.fixture(scope="module")
def run() -> TruthRun:
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NoiseModel.off())
    n = 50
    return sim.run_commands(np.arange(n) * 0.01, np.full(n, 0.3), np.zeros(n), ground="coated_wood", seed=1)


def test_arrays_are_read_only_float_with_one_row_per_sample(run):
    n = len(run.log)
    assert run.breakdown.n_samples == n
    for name in ("actual_v_mps", "actual_omega_radps", "accel_mps2", "alpha_radps2", "slope_rad", "resistance_factor"):
        arr = getattr(run, name)
        assert arr.shape == (n,) and arr.dtype == np.float64 and not arr.flags.writeable, name
    assert run.clean_current_a.shape == (n, 2) and not run.clean_current_a.flags.writeable


def test_without_noise_the_log_holds_the_clean_currents(run):
    np.testing.assert_array_equal(run.log.current_left_a, run.clean_current_a[:, 0])
    np.testing.assert_array_equal(run.log.current_right_a, run.clean_current_a[:, 1])


def test_the_arrays_are_copies(run):
    slope = np.zeros(len(run.log))
    other = dataclasses.replace(run, slope_rad=slope)
    slope[0] = 1.0
    assert other.slope_rad[0] == 0.0


@pytest.mark.parametrize(
    ("name", "shape", "match"),
    [
        ("slope_rad", (3,), r"TruthRun.slope_rad must have shape \(50,\), got \(3,\)"),
        ("clean_current_a", (50,), r"TruthRun.clean_current_a must have shape \(50, 2\), got \(50,\)"),
    ],
)
def test_arrays_of_another_shape_are_refused(run, name, shape, match):
    with pytest.raises(InvalidParameterError, match=match):
        dataclasses.replace(run, **{name: np.zeros(shape)})


def test_a_breakdown_of_another_run_is_refused(run):
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NoiseModel.off())
    short = sim.run_commands(np.arange(10) * 0.01, np.full(10, 0.3), np.zeros(10), ground="coated_wood")
    with pytest.raises(InvalidParameterError, match="TruthRun.breakdown must have 50 samples like the log, got 10"):
        dataclasses.replace(run, breakdown=short.breakdown)
