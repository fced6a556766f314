"""Tests of planner.reach_report: reach_on_battery, a Reachability with its header (summary, reach.json, files)."""

from __future__ import annotations

import json

import pytest

import terrain
from energy import Battery
from planner import Reachability
from planner.cost_spec import CostSpec
from planner.missions.mission_report import mission_battery
from planner.reach_report import reach_on_battery
from planner.reachability_result import REACH_FORMAT_VERSION
from terrain import FigureWarning, InvalidParameterError
from terrawatt_base.formats import read_result_json


@pytest.fixture
def report(flat_map) -> Reachability:
    return reach_on_battery(flat_map, (5.0, 5.0), battery=Battery(0.2, 24.0, min_reserve_pct=25.0),
                            round_trip=True, map_label="flat")


def test_the_budget_is_capacity_times_voltage_less_the_reserve(report, flat_map):
    assert isinstance(report, Reachability) and report.round_trip
    assert report.budget_j == pytest.approx(0.2 * 24.0 * 3600.0)
    assert report.reserve_j == pytest.approx(0.25 * report.budget_j)
    assert report.n_reachable_cells == flat_map.ground.size  # a flat 15 x 10 m map on 17 kJ: everywhere
    assert report.total_time_s >= report.priced.map_preparation_s >= 0.0 and report.model is None


def test_the_mission_battery_takes_the_robots_voltage(flat_map):
    from energy import robot_preset

    battery = mission_battery("jackal", 0.01)
    jackal = reach_on_battery(flat_map, (5.0, 5.0), battery=battery, pricing=CostSpec(robot="jackal"))
    assert jackal.battery.voltage_v == robot_preset("jackal").battery_voltage_v
    assert jackal.budget_j == pytest.approx(0.01 * jackal.battery.voltage_v * 3600.0)


def test_the_summary_lists_the_battery_the_area_and_the_times(report):
    lines = report.summary().splitlines()
    assert lines[0] == "map: flat  20 x 30 cells of 0.5 m"
    assert lines[1] == "robot: husky, speed 0.5 m/s, max slope 20 deg"
    assert lines[2] == "battery 0.2 Ah at 24 V = 4.8 Wh; reserve 25 % -> 3.6 Wh usable there and back"
    assert lines[3] == "depot (5.0, 5.0)" and lines[4] == ""
    names = [line[:24].strip() for line in lines[5:]]
    assert names == ["reachable area", "reachable cells", "farthest reachable", "max one-way energy",
                     "max round-trip energy", "map preparation", "lattice moves", "search", "total"]
    assert lines[6].split()[-1] == "600"


def test_nothing_reachable_is_said(flat_map):
    report = reach_on_battery(flat_map, (5.0, 5.0), battery=Battery(1e-9, 24.0))
    assert report.n_reachable_cells == 0
    assert report.summary().splitlines()[-1].startswith("no cell is reachable within the usable energy")


def test_reach_json_and_the_files(report, tmp_path):
    written = report.write(tmp_path)
    assert [p.name for p in written] == ["reach.npz", "reach.json", "reach.png"]  # no CRS: the .npz raster
    data = json.loads((tmp_path / "reach.json").read_text())
    assert read_result_json(tmp_path / "reach.json", "reachability", REACH_FORMAT_VERSION) == data
    assert data["raster"] == "reach.npz" and data["battery_voltage_v"] == 24.0 and data["reserve_pct"] == 25.0
    assert data["reachable_cells"] == 600 and data["map"] == "flat" and "model" not in data
    assert report.to_dict("x.npz")["raster"] == "x.npz"
    assert Reachability.load(tmp_path / "reach.npz").n_reachable_cells == 600


def test_a_figure_that_fails_warns(report, tmp_path, monkeypatch):
    monkeypatch.setattr(Reachability, "plot", lambda *a, **k: 1 / 0)
    with pytest.warns(FigureWarning, match="reach.png: ZeroDivisionError"):
        assert [p.name for p in report.write(tmp_path, raster="reach.npz")] == ["reach.npz", "reach.json"]


def test_a_model_is_named_in_reach_json(corridor_map, known_model):
    report = reach_on_battery(corridor_map, (2.5, 7.5), battery=Battery(1.0, 24.0),
                              pricing=CostSpec(model=known_model(), model_label="m.tw"))
    assert report.to_dict()["model"] == {"file": "m.tw", "class": "GroundKeyedModel", "model_ground": None,
                                         "grounds": ["loam", "gravel"]}


@pytest.mark.parametrize(("kwargs", "match"), [({"battery": 1.0}, "battery must be a Battery"),
                                               ({"pricing": "husky"}, "pricing must be a CostSpec")])
def test_bad_arguments_are_refused(flat_map, kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        reach_on_battery(flat_map, (5.0, 5.0), **{"battery": Battery(1.0, 24.0), **kwargs})


def test_a_map_with_a_crs_writes_a_geotiff(flat_map, tmp_path):
    pytest.importorskip("rasterio")
    geo = terrain.flat_map((20, 30), 0.5, ground="asphalt")
    geo.crs = "EPSG:32633"
    report = reach_on_battery(geo, (5.0, 5.0), battery=Battery(0.01, 24.0))
    assert report.write(tmp_path)[0].name == "reach.tif"
