"""Tests of planner.missions.monte_carlo_result: the table, JSON and figure files; a result checks its columns and errors."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from mc_samples import FIXED, run_mc, setup  # noqa: F401  (fixture)

from energy import Battery
from planner import MonteCarloResult
from planner.missions import MONTE_CARLO_FORMAT_VERSION
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import read_result_json


def test_the_result_writes_its_table_json_and_figure(setup, tmp_path):
    mc = run_mc(setup, n=5, seed=7, battery=Battery(0.12, 24.0))
    written = mc.write(tmp_path)
    assert [p.name for p in written] == ["monte_carlo.json", "monte_carlo.csv", "monte_carlo.png"]
    png = tmp_path / "monte_carlo.png"
    with open(tmp_path / "monte_carlo.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 5 and float(rows[2]["energy_j"]) == mc.energy_j[2]
    assert rows[0]["below_reserve"] in ("true", "false") and "ground_scale_asphalt" in rows[0]
    data = json.loads((tmp_path / "monte_carlo.json").read_text())
    assert data["format_version"] == MONTE_CARLO_FORMAT_VERSION and data["n"] == 5 and data["seed"] == 7
    assert read_result_json(tmp_path / "monte_carlo.json", "monte-carlo", MONTE_CARLO_FORMAT_VERSION) == data  # the one codec
    assert data["energy_wh"]["p90"] == pytest.approx(mc.energy_percentiles_wh["p90"])
    assert data["p_below_reserve"] == mc.p_below_reserve and len(data["samples"]["energy_j"]) == 5
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "file").write_text("x")
    with pytest.raises(InvalidParameterError, match="which is a file"):
        mc.plot(tmp_path / "file" / "mc.png")
    assert "5 missions (seed 7)" in mc.summary() and "P90" in mc.summary()


def test_a_result_checks_its_columns():
    ok = {c: np.ones(2) for c in ("payload_kg", "capacity_ah", "internal_resistance_ohm", "speed_mps", "energy_j",
                                  "charge_mah", "duration_s", "arrival_soc", "min_soc")}
    common = dict(seed=0, entropy=0, distributions=FIXED, battery=Battery(1, 24), predicted_energy_j=1.0,
                  ground_names=("a",), ground_scale=np.ones((2, 1)), below_reserve=np.zeros(2, bool),
                  depleted=np.zeros(2, bool))
    assert MonteCarloResult(**common, **ok).n == 2
    with pytest.raises(InvalidParameterError, match=r"speed_mps must have shape \(2,\)"):
        MonteCarloResult(**common, **{**ok, "speed_mps": np.ones(3)})
    with pytest.raises(InvalidParameterError, match="below_reserve must be a bool array"):
        MonteCarloResult(**{**common, "below_reserve": np.zeros(2)}, **ok)


def test_a_result_needs_error_text_exactly_for_missing_outcomes():
    ok = {c: np.ones(2) for c in ("payload_kg", "capacity_ah", "internal_resistance_ohm", "speed_mps", "energy_j",
                                  "charge_mah", "duration_s", "arrival_soc", "min_soc")}
    common = dict(seed=0, entropy=0, distributions=FIXED, battery=Battery(1, 24), predicted_energy_j=1.0,
                  ground_names=("a",), ground_scale=np.ones((2, 1)), below_reserve=np.zeros(2, bool),
                  depleted=np.zeros(2, bool))
    with pytest.raises(InvalidParameterError, match="error text exactly when its energy_j is not finite"):
        MonteCarloResult(**common, **ok, errors=("", "DataError: x"))
    with pytest.raises(InvalidParameterError, match="errors must be 2 strings"):
        MonteCarloResult(**common, **ok, errors=("",))
