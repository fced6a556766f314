"""Tests of planner.missions.adaptive_results: AdaptiveResult's error figures, route changes, checks and JSON."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from planner.cost_spec import CostSpec
from planner.missions.adaptive_results import ADAPTIVE_STATUSES, AdaptiveResult, LegRecord, ReplanRecord, UpdateRecord
from planner.route import evaluate_route
from terrain import InvalidParameterError, flat_map
from terrawatt_base.errors import FigureWarning
from terrawatt_base.formats import read_result_json


def _leg(index: int, predicted: float, actual: float) -> LegRecord:
    return LegRecord(index, (0.0, 0.0), (1.0, 0.0), predicted, actual, 1.0, 10, predicted)


def _update(after_leg: int, accepted: bool) -> UpdateRecord:
    return UpdateRecord(after_leg, "sand", 4, 4, 30.0, accepted, 1 if accepted else None, 0.1, 0.3, 50.0, 20.0, 0.5)


def _replan(after_leg: int, reason: str, predicted: float, changed: bool) -> ReplanRecord:
    return ReplanRecord(after_leg, reason, predicted, predicted, changed, 0.0, 0.01, 1)


def _result(status: str = "completed", updates=(), replans=()) -> AdaptiveResult:
    cost = CostSpec().build(flat_map((10, 10), 1.0, ground="asphalt"))
    route = evaluate_route(cost, [[0.5, 0.5], [8.5, 0.5]])
    legs = (_leg(0, 90.0, 100.0), _leg(1, 80.0, 100.0), _leg(2, 105.0, 100.0), _leg(3, 95.0, 100.0))
    series = np.linspace(0.0, 1.0, 30)
    return AdaptiveResult(status, "reached the goal", (8.5, 0.5), 0.0, route, legs, tuple(updates), tuple(replans),
                          series, series, series, 1.0 - 0.1 * series, series, series, 400.0, 50.0, 0.5, 0.9)


def test_errors_before_and_after_the_accepted_update():
    res = _result(updates=[_update(0, False), _update(1, True)],
                  replans=[_replan(-1, "initial", 380.0, False), _replan(1, "update", 210.0, True)])
    assert res.accepted_updates == 1 and res.route_changes == 1
    assert res.error_before_update_pct == pytest.approx(-15.0)  # legs 0 and 1: 170 J predicted for 200 J
    assert res.error_after_update_pct == pytest.approx(0.0)  # legs 2 and 3: 200 J for 200 J
    assert res.remaining_error_after_update_pct == pytest.approx(5.0)  # 210 J predicted for the last 200 J


def test_without_an_accepted_update_the_after_figures_are_nan():
    res = _result(updates=[_update(0, False)])
    assert res.error_before_update_pct == pytest.approx(-7.5)  # all legs: 370 J for 400 J
    assert math.isnan(res.error_after_update_pct) and math.isnan(res.remaining_error_after_update_pct)


def test_the_status_is_checked_and_the_json_holds_the_records(tmp_path):
    assert "completed" in ADAPTIVE_STATUSES
    with pytest.raises(InvalidParameterError, match="status must be one of"):
        _result(status="done")
    res = _result(updates=[_update(1, True)], replans=[_replan(1, "update", 210.0, True)])
    data = json.loads(json.dumps(res.to_dict(series_every=10)))
    assert data["status"] == "completed" and len(data["legs"]) == 4 and data["updates"][0]["accepted"] is True
    with pytest.warns(FigureWarning, match="terrain must be the TerrainMap"):  # the figure needs the map: left out
        written = res.write(tmp_path)
    assert [p.name for p in written] == ["mission.json"]
    path = written[0]
    assert read_result_json(path, "adaptive-mission", 1) == json.loads(json.dumps(data).replace("NaN", "null"))
