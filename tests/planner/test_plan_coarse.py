"""Tests of planner.plan_report.plan_coarse: a coarse-to-fine PlanReport, of a map in memory or of a GeoTIFF."""

from __future__ import annotations

import json
import math

import pytest

import terrain
from planner import CoarseOptions
from planner.cost_spec import CostSpec
from planner.plan_report import ROUTE_JSON_FORMAT_VERSION, PlanReport, plan_coarse, route_table
from terrain import InvalidParameterError
from terrain.procedural import procedural_map
from terrawatt_base.formats import read_result_json

START, GOAL = (5.0, 5.0), (35.0, 5.0)


def test_a_coarse_plan_reports_one_row_and_its_stages(wall_map, tmp_path):
    report = plan_coarse(wall_map, START, GOAL, options=CoarseOptions(factor=4), map_label="wall")
    assert isinstance(report, PlanReport) and not report.windowed and report.fine_map is wall_map
    assert report.route.status == "exact" and report.coarse.grid == wall_map.grid and report.lattice is None
    rows = report.rows()
    assert [r["route"] for r in rows] == ["coarse-to-fine (x4)"] and math.isnan(rows[0]["ratio_to_lattice_optimum"])
    lines = report.summary().splitlines()
    assert lines[0] == "map: wall  40 x 40 cells of 1 m; grounds {0: 'asphalt'}"
    assert lines[1].startswith("robot: husky, speed 0.5 m/s, max slope 20 deg; map preparation ")
    assert lines[2].startswith("start (5.0, 5.0) -> goal (35.0, 5.0); coarse-to-fine, factor 4, corridor ")
    assert f"fallback: {report.coarse.fallback})" in lines[2]
    assert lines[3].startswith("coarse route ") and lines[4] == ""
    assert "\n".join(lines[5:]) == route_table(rows)
    data = report.to_dict()
    assert data["format_version"] == ROUTE_JSON_FORMAT_VERSION and data["planner"] == "coarse-to-fine"
    assert data["windowed"] is False and data["coarse_to_fine"]["factor"] == 4
    assert "energy_j" not in data["coarse_to_fine"]  # the route's own scalars live under routes
    assert data["routes"]["min_energy"]["waypoints_m"] == report.route.waypoints_m.tolist()
    written = report.write(tmp_path)
    assert [p.name for p in written] == ["route.json", "route.geojson", "route.png"]
    assert json.loads((tmp_path / "route.json").read_text())["coarse_waypoints_m"] == data["coarse_waypoints_m"]
    assert read_result_json(tmp_path / "route.json", "route", ROUTE_JSON_FORMAT_VERSION)["planner"] == "coarse-to-fine"


def test_a_coarse_plan_without_route(tmp_path):
    closed = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(0, 0))
    report = plan_coarse(closed, START, GOAL)
    assert report.route.status == "infeasible" and report.rows() == []
    assert report.summary().splitlines()[-1] == "no route: status 'infeasible'"
    assert report.to_dict()["routes"] == {}
    assert [p.name for p in report.write(tmp_path, whole_map=True)] == ["route.json", "route.png"]


def test_a_pricing_coarse_to_fine_cannot_use_is_refused(wall_map, known_model):
    with pytest.raises(InvalidParameterError, match="physics presets") as err:
        plan_coarse(wall_map, START, GOAL, pricing=CostSpec(model=known_model()))
    assert err.value.parameter == "pricing"
    with pytest.raises(InvalidParameterError, match="pricing must be a CostSpec"):
        plan_coarse(wall_map, START, GOAL, pricing={"max_slope_deg": 10.0})
    with pytest.raises(InvalidParameterError, match="options must be a CoarseOptions"):
        plan_coarse(wall_map, START, GOAL, options={"factor": 4})


def test_a_windowed_plan_equals_the_plan_in_memory(tmp_path):
    pytest.importorskip("rasterio")
    tmap = procedural_map((131, 97), 1.0, seed=4, origin_xy_m=(0.0, 0.0))
    tmap.crs = "EPSG:32633"
    dem = terrain.write_geotiff(tmap, tmp_path / "dem.tif")
    start, goal = (5.5, 6.5), (90.5, 120.5)
    windowed = plan_coarse(dem, start, goal, options=CoarseOptions(factor=4))
    whole = plan_coarse(terrain.read_map(dem), start, goal, options=CoarseOptions(factor=4), map_label="dem.tif")
    assert windowed.windowed and windowed.priced.map_label == "dem.tif" and windowed.priced.map_preparation_s == 0.0
    assert windowed.terrain is None and windowed.coarse.grid.shape == (131, 97)
    assert windowed.route.energy_j == whole.route.energy_j
    lines = windowed.summary().splitlines()
    assert lines[0] == "map: dem.tif  131 x 97 cells of 1 m, read by windows; ground unknown, priced as 'gravel'"
    assert "full-resolution cells read by the fine stage: " in lines[1]
    w, m = windowed.to_dict(), whole.to_dict()
    assert w["windowed"] is True and w["map_crs"] == "EPSG:32633" and "start_lonlat_deg" in w
    assert w["routes"] == {**m["routes"], "min_energy": {**m["routes"]["min_energy"],
                                                         "planning_time_s": w["routes"]["min_energy"]["planning_time_s"]}}
    assert [p.name for p in windowed.write(tmp_path / "w", whole_map=True)] == ["route.json", "route.geojson",
                                                                                 "route.png"]
