"""Tests of planner.plan_report: plan_and_compare, PlanReport (summary, table, route.json, files), its helpers."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

import planner.plan_report as plan_report_module
import terrain
from planner.cost_spec import CostSpec
from planner.plan_report import (
    ROUTE_JSON_FORMAT,
    ROUTE_JSON_FORMAT_VERSION,
    PlanModel,
    PlanReport,
    compile_line,
    lonlat_fields,
    plan_and_compare,
    route_row,
    route_table,
)
from planner.planning import RouteSearch
from terrain import FigureWarning, InvalidParameterError
from terrawatt_base.formats import read_result_json

START, GOAL = (5.0, 5.0), (35.0, 5.0)


@pytest.fixture
def report(wall_map) -> PlanReport:
    return plan_and_compare(wall_map, START, GOAL, search=RouteSearch("lattice"), map_label="wall")


def test_a_lattice_plan_compares_with_itself_and_the_shortest_route(report, wall_map):
    assert report.route.status == "exact" and report.lattice is report.route
    assert report.shortest.status == "exact" and report.shortest.planner == "shortest"
    rows = report.rows()
    assert [r["route"] for r in rows] == ["min-energy (lattice)", "lattice + refinement", "shortest distance"]
    assert rows[0] == route_row("min-energy (lattice)", report.route, report.route.lattice_energy_j)
    assert rows[0]["ratio_to_lattice_optimum"] == pytest.approx(report.route.optimality_ratio)
    assert report.table() == route_table(rows)
    assert report.interval is None and report.model is None and report.risk_q is None
    assert report.cost.terrain is wall_map and report.terrain is wall_map
    assert report.start_xy_m == START and isinstance(report.start_xy_m[0], float)


def test_another_planner_gets_the_lattice_route_as_its_second_row(wall_map):
    report = plan_and_compare(wall_map, START, GOAL, search=RouteSearch("anyangle"), map_label="wall")
    assert report.route.planner.startswith("anyangle") and report.lattice.planner.startswith("lattice")
    assert report.lattice is not report.route
    assert report.rows()[1]["energy_j"] == pytest.approx(report.lattice.energy_j)


def test_the_summary_says_map_robot_budget_and_saving(report):
    text = report.summary()
    lines = text.splitlines()
    assert lines[0] == "map: wall  40 x 40 cells of 1 m; grounds {0: 'asphalt'}"
    assert lines[1].startswith("robot: husky, speed 0.5 m/s, max slope 20 deg; map preparation ")
    assert lines[2] == "start (5.0, 5.0) -> goal (35.0, 5.0); planner lattice, no budget (a graph search), seed 0"
    assert report.table() in text
    assert lines[-1].startswith("energy saved vs shortest route: ")
    assert f"energy / heading-lattice optimum (turns in both): {report.route.optimality_ratio:.3f}" in lines[-1]


def test_route_json_holds_the_query_the_table_and_every_route(report):
    data = report.to_dict()
    assert list(data)[:3] == ["format", "format_version", "map"]
    assert data["format"] == ROUTE_JSON_FORMAT and data["format_version"] == ROUTE_JSON_FORMAT_VERSION
    assert data["start_xy_m"] == [5.0, 5.0] and data["goal_xy_m"] == [35.0, 5.0] and data["map_crs"] is None
    assert data["planner"] == "lattice" and data["time_limit_s"] == 1.0 and data["max_evaluations"] is None
    assert data["status"] == "exact" and data["table"] == report.rows()
    assert sorted(data["routes"]) == ["lattice", "min_energy", "shortest"]
    assert data["routes"]["min_energy"]["waypoints_m"] == report.route.waypoints_m.tolist()
    assert "model" not in data and "start_lonlat_deg" not in data
    assert "energy_interval" not in data["routes"]["min_energy"]


def test_write_writes_json_geojson_and_figure(report, tmp_path):
    written = report.write(tmp_path / "out")
    assert [p.name for p in written] == ["route.json", "route.geojson", "route.png"]
    data = json.loads((tmp_path / "out" / "route.json").read_text())
    assert data["routes"]["min_energy"]["energy_j"] == report.route.energy_j
    # the one result codec reads it back: format terrawatt-route, its version
    assert read_result_json(tmp_path / "out" / "route.json", "route", ROUTE_JSON_FORMAT_VERSION) == data
    names = [f["properties"]["name"] for f in json.loads((tmp_path / "out" / "route.geojson").read_text())["features"]]
    assert sorted(names) == ["lattice", "min_energy", "shortest"]
    assert (tmp_path / "out" / "route.png").read_bytes()[:4] == b"\x89PNG"


def test_a_figure_that_fails_warns_and_leaves_the_results(report, tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(plan_report_module, "plot_routes", broken)
    with pytest.warns(FigureWarning, match=r"could not draw .*route.png: RuntimeError: no canvas"):
        written = report.write(tmp_path)
    assert [p.name for p in written] == ["route.json", "route.geojson"]
    with pytest.raises(RuntimeError, match="no canvas"):
        report.write(tmp_path / "again", on_figure_error="raise")


def test_no_route_is_reported_and_written_without_geojson(tmp_path):
    closed = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(0, 0))
    report = plan_and_compare(closed, START, GOAL, search=RouteSearch("lattice"), map_label="closed")
    assert report.route.status == "infeasible" and report.lattice is None and report.rows() == []
    assert report.summary().splitlines()[-1].startswith("no route: status 'infeasible' after ")
    data = report.to_dict()
    assert data["routes"] == {} and data["table"] == [] and data["energy_saved_pct"] is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        written = report.write(tmp_path)
    assert [p.name for p in written] == ["route.json", "route.png"]


def test_an_approximate_route_says_how_short_it_ends(wall_map):
    report = plan_and_compare(wall_map, START, GOAL, search=RouteSearch("RRTstar", None, max_cost_evaluations=30, seed=0))
    if report.route.status != "approximate":
        pytest.skip(f"RRT* reached the goal in 30 evaluations: {report.route.status}")
    last = report.summary().splitlines()[-1]
    assert last.startswith("the RRTstar route is approximate: it ends ") and "m short of the goal" in last
    assert report.to_dict()["time_limit_s"] is None and report.to_dict()["max_evaluations"] == 30
    assert "30 edge-cost evaluations" in report.summary()


def test_unknown_ground_is_said_in_the_summary():
    unknown = terrain.wall_map((20, 20), 1.0, ground=None)
    report = plan_and_compare(unknown, (2.0, 2.0), (18.0, 2.0), search=RouteSearch("lattice"),
                              pricing=CostSpec(unknown_ground="sand"))
    assert "ground class unknown in 400 of 400 cells: priced as 'sand'" in report.summary()


def test_a_model_prices_the_edges_and_gives_the_interval(corridor_map, known_model, tmp_path):
    model = known_model()
    report = plan_and_compare(corridor_map, (2.5, 7.5), (27.5, 7.5), search=RouteSearch("lattice"),
                              pricing=CostSpec(model=model, model_label="husky.tw", unknown_ground="gravel"))
    assert report.priced.spec.preset_unknown_ground is None  # a model prices every ground itself
    assert report.model == PlanModel(file="husky.tw", class_name="GroundKeyedModel", model_ground=None,
                                     grounds=("loam", "gravel"), gives_interval=True, risk_q=None)
    assert report.interval is not None and report.interval.sd_j > 0
    text = report.summary()
    assert "edge costs: model husky.tw (GroundKeyedModel) on grounds ['loam', 'gravel']" in text
    assert "P50" in text and "P90" in text and "(the table shows the planning objective)" not in text
    data = report.to_dict()
    assert data["model"]["objective"] == "energy mean" and data["model"]["class"] == "GroundKeyedModel"
    assert data["routes"]["min_energy"]["energy_interval"] == report.interval.to_dict()
    risky = plan_and_compare(corridor_map, (2.5, 7.5), (27.5, 7.5), search=RouteSearch("lattice"),
                             pricing=CostSpec(model=model, risk=0.9))
    assert risky.risk_q == 0.9 and "(the table shows the planning objective)" in risky.summary()
    assert risky.to_dict()["model"]["objective"] == "0.9 quantile: mean + z sd per edge"


def test_risk_needs_a_model_with_an_interval(corridor_map, known_model):
    flat = {"loam": [9.0, 2.0, 4.0, 0.0], "gravel": [10.5, 2.5, 4.5, 0.0]}
    with pytest.raises(InvalidParameterError, match="risk 0.9 needs a model with a predictive interval") as err:
        plan_and_compare(corridor_map, (2.5, 7.5), (27.5, 7.5), search=RouteSearch("lattice"),
                         pricing=CostSpec(model=known_model(grounds=flat), risk=0.9))
    assert err.value.parameter == "risk"


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"search": "lattice"}, InvalidParameterError, "search must be a RouteSearch"),
    ({"pricing": "husky"}, InvalidParameterError, "pricing must be a CostSpec"),
])
def test_bad_arguments_are_refused(wall_map, kwargs, error, match):
    with pytest.raises(error, match=match):
        plan_and_compare(wall_map, START, GOAL, **kwargs)


def test_helpers_rows_table_lonlat_compile_line(report):
    lost = report.route.replace(status="timeout", waypoints_m=np.empty((0, 2)), segment_energy_j=[], turn_energy_j=[])
    row = route_row("lost", lost, 100.0)
    assert math.isnan(row["energy_j"]) and math.isnan(row["ratio_to_lattice_optimum"])
    assert math.isnan(route_row("x", report.route, 0.0)["ratio_to_lattice_optimum"])
    table = route_table([route_row("x", report.route, report.route.energy_j)]).splitlines()
    assert len(table) == 3 and set(table[1]) == {"-"} and table[2].split()[-2] == "1.000"
    assert lonlat_fields(None, START, GOAL) == {} and lonlat_fields(report.terrain, START, GOAL) == {}
    assert compile_line(0.5) == [] and compile_line(2.0)[0].startswith("(compiled the edge-cost kernels in 2.0 s")


def test_lonlat_fields_of_a_map_with_a_crs(wall_map):
    pytest.importorskip("rasterio")
    wall_map.crs = "EPSG:32632"
    fields = lonlat_fields(wall_map, START, GOAL)
    assert sorted(fields) == ["goal_lonlat_deg", "start_lonlat_deg"]
    assert 4.0 < fields["start_lonlat_deg"][0] < 5.0 and 0.0 <= fields["start_lonlat_deg"][1] < 0.01
