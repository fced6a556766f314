"""Tests of planner.missions.results: MissionResult JSON (its series thinned) and figure files."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from simulate_samples import clean_sim, flat, flat_mission  # noqa: F401  (fixtures)

from planner.missions import MISSION_FORMAT_VERSION
from terrain import InvalidParameterError
from terrawatt_base.formats import read_result_json


def test_json_and_plot(flat_mission, flat, tmp_path):
    tmap, _ = flat
    _, res = flat_mission
    written = res.write(tmp_path, series_every=25, terrain=tmap)
    path, png = written
    assert [p.name for p in written] == ["mission.json", "mission.png"]
    data = json.loads(path.read_text())
    assert data["format_version"] == MISSION_FORMAT_VERSION and data["status"] == "completed"
    assert data["budget"]["actual_energy_j"] == pytest.approx(res.budget.actual_energy_j)
    assert data["reserve_crossing"] is None
    assert res.summary().splitlines()[0] == f"mission completed (truth): {res.route.length_m:.1f} m in {res.duration_s:.1f} s"
    assert f"actual {res.budget.actual_energy_wh:.2f} Wh" in res.summary() and "below the reserve" not in res.summary()
    n = len(range(0, res.n_samples, 25)) + (0 if (res.n_samples - 1) % 25 == 0 else 1)
    assert len(data["series"]["soc"]) == n and data["series"]["time_s"][-1] == res.time_s[-1]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mission.json", "mission.png"]  # no temp files left
    with pytest.raises(InvalidParameterError, match="series_every must be >= 1"):
        res.write(tmp_path / "never", series_every=0)
    assert not (tmp_path / "never").exists()
    assert read_result_json(path, "mission", MISSION_FORMAT_VERSION) == data  # through the one result codec


def test_a_non_finite_sample_is_written_as_null(flat_mission, tmp_path):
    _, res = flat_mission
    power = res.power_w.copy()
    power[1] = math.nan  # e.g. a replayed log without battery power
    bad = dataclasses.replace(res, power_w=power)
    data = json.loads(bad.write(tmp_path)[0].read_text())  # a NaN raised ValueError before the codec
    assert data["series"]["power_w"][1] is None
    assert data["series"]["power_w"][2] == res.power_w[2] and np.isfinite(res.power_w[1])
