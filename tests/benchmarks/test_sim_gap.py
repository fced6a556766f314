"""benchmarks/sim_gap.py: its steps add up to the gap, and on flat ground the edges price the stop-turn-go parts."""

from __future__ import annotations

import numpy as np
import pytest
import sim_gap  # benchmarks/ is on sys.path: tests/conftest.py

from terrain import flat_map


@pytest.fixture(scope="module")
def flat_turn():
    return sim_gap.gap(flat_map((8, 16), 1.0, ground="asphalt"), np.array([[1.5, 1.5], [12.5, 1.5], [12.5, 6.5]]))


def test_the_steps_walk_from_the_booked_energy_at_the_mean_payload_down_to_the_edges(flat_turn):
    r = flat_turn
    assert list(r["steps_j"]) == [*sim_gap.SIM_STEPS, *sim_gap.PROFILE_STEPS]
    walk = sum(r["steps_j"][k] for k in (*sim_gap.SIM_STEPS, "rest"))  # down to the profile, then to the edges
    assert r["simulated_payload_10kg_j"] - walk == pytest.approx(r["edges_j"], abs=1e-6)
    assert r["steps_j"]["payload"] > 0
    assert r["edges_j"] - r["steady_edges_j"] == pytest.approx(r["steps_j"]["priced"], abs=1e-9)


def test_on_flat_ground_the_edges_price_the_stops_and_turn_ramps_of_the_profile(flat_turn):
    steps = flat_turn["steps_j"]
    assert abs(steps["rest"]) < 0.005 * flat_turn["edges_j"]
    assert 2 * 40.0 < steps["starts_and_stops"] < 2 * 70.0  # two segments, each started and stopped once
    assert 30.0 < steps["turn_ramps"] < 70.0  # one pivot
    assert steps["priced"] == pytest.approx(steps["starts_and_stops"] + steps["turn_ramps"], abs=2.0)
    assert flat_turn["simulated_nominal_j"] == pytest.approx(flat_turn["profile_j"], rel=0.01)
    assert flat_turn["simulated_nominal_j"] == pytest.approx(flat_turn["edges_j"], rel=0.01)
