"""The ties benchmark (benchmarks/diagnosis_ties.py): its map is the independent simulator's ramp, and one
pair closes on one seed — tie named, drive simulated where it was placed, the truth first after it."""

from __future__ import annotations

import math

import diagnosis_ties as dt
import numpy as np
import pytest

from energy.logs import log_slope_rad

sim = dt.sim


def test_the_map_is_the_simulators_ramp():
    tmap = dt.slope_map()
    assert tmap.bounds == (0.0, 0.0) + dt.MAP_EXTENT_M
    slope = np.asarray(tmap["slope"])
    x, _ = tmap.xy(np.zeros(tmap.shape[1], int), np.arange(tmap.shape[1]))
    inside = dt.SLOPE.on_ramp(x - 1.0, 0 * x) & dt.SLOPE.on_ramp(x + 1.0, 0 * x)
    np.testing.assert_allclose(slope[:, inside], math.radians(10.0), atol=1e-9)
    assert np.all(slope[:, (x < dt.SLOPE.start_m - 1.0)] == 0.0)
    # a run the simulator drives up the ramp: the map gives the pitch the simulator applied
    log = sim.simulate_run(0, duration_s=20.0, driving="cruise", slope=dt.SLOPE, start_pose=(72.0, 50.0, 0.0))
    on = dt.SLOPE.on_ramp(log.pose_xyh[:, 0] - 1.0, log.pose_xyh[:, 1]) & dt.SLOPE.on_ramp(
        log.pose_xyh[:, 0] + 1.0, log.pose_xyh[:, 1])
    assert on.sum() > 50
    np.testing.assert_allclose(log_slope_rad(tmap, log)[on], math.radians(10.0), atol=1e-6)
    # the diagnosed runs of a map pair start on its level part, heading along the contour
    for k in range(dt.RUNS):
        x0, y0, heading = dt._level_start(k)
        assert not dt.SLOPE.on_ramp(np.array([x0]), np.array([y0]))[0] and heading == pytest.approx(math.pi / 2)


def test_mass_vs_rolling_is_named_a_tie_and_settled_by_its_drive():
    row = dt.run_pair("mass_vs_rolling", 0, max_repeats=1)
    assert row["tie_named"]
    tie = next(t for t in row["ties"] if "mass" in t["effects"])
    assert "rolling_resistance" in tie["effects"]  # on level cruising, the payload looks like rolling resistance
    assert row["drive"]["duration_s"] <= dt.TARGETS["drive_max_s"] and row["drive_runs"] == 1
    assert row["truth_first_after"] and row["value_ok_after"]
    assert row["value_after"]["fitted"] == pytest.approx(0.6, rel=dt.VALUE_TOL)
    summary = dt.summarise([row])["mass_vs_rolling"]
    assert summary["truth_first_after_pct"] == 100.0 and "mass_vs_rolling" in dt.table({"mass_vs_rolling": summary})


def test_inertia_vs_lag_is_named_a_tie_on_waves_and_settled_by_its_drive():
    row = dt.run_pair("inertia_vs_lag", 0, max_repeats=1)
    assert row["tie_named"]
    tie = next(t for t in row["ties"] if "rotor_inertia" in t["effects"])
    assert "time_lag" in tie["effects"]  # the speed swelling and easing: a lag looks like a heavier drivetrain
    assert row["drive"]["duration_s"] <= dt.TARGETS["drive_max_s"] and row["drive_runs"] == 1
    assert row["truth_first_after"] and not row["tie_after"]
    assert row["value_after"]["fitted"] == pytest.approx(row["value_after"]["truth"], rel=dt.VALUE_TOL)
