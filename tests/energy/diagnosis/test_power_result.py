"""Tests of energy.diagnosis.power_result: the battery-power gap summary and the power stage's report."""

import json
import math

import numpy as np
import pytest
from power_samples import N_BOOT, small_power_scenario

from energy import InteractionLog, LogMeta
from energy.diagnosis import diagnose
from energy.diagnosis.power_result import PowerGapSummary, power_gap_summary


@pytest.fixture(scope="module")
def found():
    """The control-board scenario, small, seed 1: its scenario and its diagnosis."""
    sc = small_power_scenario("control")
    return {"control": (sc, diagnose(sc.make_model(1), sc.make_logs(1), terrain=sc.terrain, seed=1, n_bootstrap=N_BOOT))}


def test_result_writes_the_power_stage(found, tmp_path):
    _, d = found["control"]
    doc = json.loads(d.write_json(tmp_path / "d.json").read_text())
    assert doc["power"]["chosen"] == ["control"] and doc["power"]["waterfall"][0]["label"] == "as given"
    assert doc["power"]["corrected_robot"]["control_standby_power_w"] > 0
    md = d.to_markdown()
    assert "## Battery power: electrical candidates" in md and "| + control |" in md


def _power_log(power_w: np.ndarray, v: np.ndarray) -> InteractionLog:
    t = np.arange(power_w.size, dtype=float)  # 1 s steps
    ta = np.arange(0.0, t[-1] + 0.05, 0.1)
    return InteractionLog(t, v, np.zeros(t.size), np.ones(t.size), np.ones(t.size), ta, np.full(ta.size, 9.81),
                          meta=LogMeta(source="p.csv"), battery_voltage_v=np.full(t.size, 24.0),
                          battery_current_a=power_w / 24.0)


def test_power_gap_summary_of_a_constant_shortfall():
    measured = np.full(37, 100.0)  # 36 s at 100 W = 1 Wh
    still = (np.arange(37) < 10).astype(float)  # standing still for the first 10 samples
    log = _power_log(measured, np.where(still > 0, 0.0, 0.5))
    s = power_gap_summary([log], [measured - 10.0], [still], section_s=8.0)
    assert isinstance(s, PowerGapSummary) and (s.n_runs, s.n_samples) == (1, 37)
    assert s.measured_wh == pytest.approx(1.0) and s.predicted_wh == pytest.approx(0.9) and s.gap_wh == pytest.approx(0.1)
    assert s.energy_error_pct == pytest.approx(10.0) and s.rmse_w == pytest.approx(10.0)
    assert s.section_error_pct == pytest.approx(10.0)
    assert s.stopped_time_pct == pytest.approx(100.0 * 9.5 / 36.0)  # trapezoid weights: half a second at the ends
    assert s.stopped_gap_pct == pytest.approx(s.stopped_time_pct)
    assert json.loads(json.dumps(s.to_dict()))["n_samples"] == 37


def test_a_perfect_prediction_has_no_gap_and_no_stopped_share():
    measured = np.linspace(50.0, 150.0, 20)
    log = _power_log(measured, np.full(20, 0.5))
    s = power_gap_summary([log], [measured], [np.zeros(20)])
    assert s.gap_wh == pytest.approx(0.0, abs=1e-12) and s.rmse_w == pytest.approx(0.0, abs=1e-9)
    assert s.stopped_gap_pct == 0.0  # no standstill
    empty = power_gap_summary([], [], [])
    assert empty.n_runs == 0 and math.isnan(empty.energy_error_pct) and math.isnan(empty.rmse_w)
