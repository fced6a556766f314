"""TourResult (planner.tours.result): tour.json, GeoJSON, figures, the left-out sites, the ROS 2 bags."""

from __future__ import annotations

import json

import numpy as np
import pytest
from tour_samples import hills_cost  # noqa: F401  (fixture)

from energy import Battery
from planner.tours import TourRobot, TourSites, plan_tour
from planner.tours.tour import NOT_WORTH_IT


def test_the_result_writes_json_geojson_and_figures_and_names_the_left_out(tmp_path, hills_cost):
    sites = TourSites(("a", "b", "c", "zero"), [[10.0, 10.0], [30.0, 30.0], [12.0, 30.0], [20.0, 22.0]],
                      value=[3.0, 1.0, 2.0, 0.0], service_energy_j=[100.0, 0.0, 0.0, 0.0])
    res = plan_tour(hills_cost, sites, TourRobot(Battery(0.1, 24.0), (20.0, 20.0)))
    files = {p.name for p in res.write(tmp_path)}
    assert files == {"tour.json", "tour.geojson", "tour.png", "tour_soc.png"}
    doc = json.loads((tmp_path / "tour.json").read_text())
    assert doc["format"] == "terrawatt-tour" and doc["format_version"] == 4
    robot = doc["robots"][0]
    assert robot["sites"] == list(res.tours[0].sites) and res.left_out["zero"] == NOT_WORTH_IT
    assert len(robot["legs"]) == len(robot["sites"]) + 1
    soc = robot["soc"]
    assert soc["band_low"][-1] <= soc["mean"][-1] <= soc["band_high"][-1]
    assert soc["at_risk"][-1] >= 0.2 - 1e-12
    assert np.all(np.diff(soc["mean"]) < 0)
    spent = res.tours[0].energy.mean_j
    legs = sum(leg["energy_j"] for leg in robot["legs"])
    assert spent == pytest.approx(legs + (100.0 if "a" in robot["sites"] else 0.0))
    geo = json.loads((tmp_path / "tour.geojson").read_text())
    assert len(geo["features"]) == len(robot["legs"])
    assert "robot 0" in res.summary()


def test_each_robots_tour_is_written_as_a_ros2_bag(tmp_path, hills_cost):
    pytest.importorskip("rosbags", reason="the ROS 2 output needs the ros extra")
    from planner.ros_export import read_route_bag

    sites = TourSites(("a", "b"), [[10.0, 10.0], [30.0, 30.0]])
    res = plan_tour(hills_cost, sites, TourRobot(Battery(0.2, 24.0), (20.0, 20.0)))
    written = res.write(tmp_path, bag=True)
    assert tmp_path / "tour_0.mcap" in written
    bag = read_route_bag(tmp_path / "tour_0.mcap")
    assert np.allclose(bag.waypoints_m[0], (20.0, 20.0)) and np.allclose(bag.waypoints_m[-1], (20.0, 20.0))
