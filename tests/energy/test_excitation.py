"""Tests of energy.excitation: the paper's excitation pattern."""

from __future__ import annotations

import numpy as np
import pytest

from energy import excitation_commands
from terrain import InvalidParameterError, UnknownNameError


# ------------------------------------------------------------------ excitation pattern
def test_excitation_uses_the_papers_levels_and_visits_every_combination() -> None:
    p = excitation_commands(160.0, 0.01, seed=4)
    assert len(p) == 16000 and p.dt_s == pytest.approx(0.01)
    speeds = np.round(p.v_mps, 9)
    omegas = np.round(p.omega_radps, 9)
    assert set(np.unique(speeds)) <= {0.0, 0.1, 0.2, 0.3, 0.4}
    assert set(np.unique(omegas)) <= {0.0, 0.35, 0.7, 1.05}
    pairs = set(zip(speeds.tolist(), omegas.tolist()))
    assert len(pairs) == 20  # 5 speeds x 4 yaw rates
    # at rest for the first and last second
    assert np.all(p.v_mps[:100] == 0) and np.all(p.omega_radps[-100:] == 0)
    moving = (p.v_mps != 0) | (p.omega_radps != 0)
    assert 0.8 < moving.mean() < 0.99  # one combination in 20 is (0, 0)


def test_excitation_holds_last_between_min_and_max() -> None:
    p = excitation_commands(60.0, 0.01, hold_s=(2.0, 3.0), rest_s=0.0, seed=1)
    change = np.flatnonzero((np.diff(p.v_mps) != 0) | (np.diff(p.omega_radps) != 0)) + 1
    holds = np.diff(change) * p.dt_s
    # consecutive holds may repeat a combination across a cycle boundary (then they merge)
    assert holds.min() >= 2.0 - 1e-9
    assert np.median(holds) <= 3.0 + 1e-9


def test_excitation_is_seeded() -> None:
    a = excitation_commands(30.0, seed=3)
    b = excitation_commands(30.0, seed=3)
    c = excitation_commands(30.0, seed=4)
    assert np.array_equal(a.v_mps, b.v_mps) and np.array_equal(a.omega_radps, b.omega_radps)
    assert not np.array_equal(a.v_mps, c.v_mps)


def test_excitation_both_signs() -> None:
    p = excitation_commands(120.0, seed=2, omega_sign="both")
    assert p.omega_radps.min() < 0 < p.omega_radps.max()
    assert excitation_commands(120.0, seed=2).omega_radps.min() == 0.0


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"duration_s": -1.0}, InvalidParameterError, "duration_s"),
        ({"duration_s": 2.0, "rest_s": 1.0}, InvalidParameterError, "rest"),
        ({"dt_s": 0.0}, InvalidParameterError, "dt_s"),
        ({"hold_s": (3.0, 1.0)}, InvalidParameterError, "hold_s"),
        ({"speed_levels_mps": (0.1, float("nan"))}, InvalidParameterError, "speed_levels_mps"),
        ({"omega_sign": "negative"}, UnknownNameError, "omega_sign"),
        ({"seed": 1.5}, InvalidParameterError, "seed"),
    ],
)
def test_excitation_bad_input(kwargs: dict, exc: type, match: str) -> None:
    with pytest.raises(exc, match=match):
        excitation_commands(**kwargs)


def test_excitation_seed_follows_the_seed_rule() -> None:
    # one seed rule everywhere: None or an int in [0, 2**32)
    assert len(excitation_commands(10.0, seed=None)) == 1000
    assert len(excitation_commands(10.0, seed=2**32 - 1)) == 1000
    for bad in (-1, 2**32, True, "1"):
        with pytest.raises(InvalidParameterError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
            excitation_commands(10.0, seed=bad)


def test_excitation_string_duration_names_the_parameter() -> None:
    with pytest.raises(InvalidParameterError, match="duration_s must be a real number, got 'long'"):
        excitation_commands("long")
