"""Tests of planner.missions.mission_report: simulate_adaptive_mission, an AdaptiveResult with its header."""

from __future__ import annotations

import json

import pytest

import planner.missions.mission_report as mission_report_module
import terrain
from energy import Battery
from planner.missions import AdaptiveResult, AdaptiveSettings
from planner.missions.adaptive_results import check_logs_folder
from planner.missions.mission_report import check_preset_grounds, mission_battery, simulate_adaptive_mission
from terrain import FigureWarning, InvalidParameterError, TerrainMap, UnknownNameError

START, GOAL = (3.0, 12.0), (37.0, 12.0)


@pytest.fixture(scope="module")
def report() -> AdaptiveResult:
    wall = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(10, 14))
    return simulate_adaptive_mission(wall, START, GOAL, battery=Battery(20.0, 24.0), map_label="wall")


def test_the_mission_reaches_the_goal_on_its_battery(report):
    assert isinstance(report, AdaptiveResult) and report.completed and report.status == "completed"
    assert report.battery.capacity_ah == 20.0 and report.battery.voltage_v == 24.0  # the husky's
    assert report.battery.min_reserve_pct == 20.0 and report.adapt and report.prior_ground == "asphalt"
    assert report.registry is not None and report.computing_time_s > 0


def test_the_summary_says_battery_plan_drive_and_final_charge(report):
    lines = report.summary().splitlines()
    assert lines[0] == "map: wall; robot husky; battery 20 Ah at 24 V (480 Wh, 384 Wh above the 20 % reserve)"
    assert lines[1] == "start (3.0, 12.0) -> goal (37.0, 12.0); prior trained on asphalt; adaptive updates on"
    assert lines[2] == "status: completed — reached the goal"
    assert lines[3].startswith("first plan (prior models): ") and "(fits the usable 384 Wh)" in lines[3]
    assert lines[4].startswith("driven (actual): ") and f"in {len(report.legs)} legs" in lines[4]
    assert lines[-1].startswith("final state of charge ") and "loop computing" in lines[-1]


def test_mission_json_and_figure(report, tmp_path):
    written = report.write(tmp_path)
    assert [p.name for p in written] == ["mission.json", "mission.png"]
    data = json.loads((tmp_path / "mission.json").read_text())
    assert data["status"] == "completed" and data["computing_time_s"] == report.computing_time_s
    assert data == json.loads(json.dumps(report.to_dict(), allow_nan=True).replace("NaN", "null"))


def test_the_legs_logs_are_what_the_mission_drove_and_read_back(report, tmp_path):
    from energy.io import read_logs

    legs = report.leg_logs
    assert len(legs) == len(report.legs) and [len(log) for log in legs] == [
        leg.n_samples for leg in report.legs]
    written = report.write(tmp_path, logs=True)
    csvs = [p for p in written if p.suffix == ".csv"]
    assert [p.name for p in csvs] == [f"leg_{k:03d}.csv" for k in range(len(legs))]
    back = read_logs(tmp_path / "logs")  # in name order
    assert [len(log) for log in back] == [len(log) for log in legs]
    first = back[0]
    assert first.meta.source.endswith("leg_000.csv")
    assert first.current_left_a.tolist() == legs[0].current_left_a.tolist()
    assert first.pose_xyh.tolist() == legs[0].pose_xyh.tolist() and first.ground.tolist() == legs[0].ground.tolist()
    assert "leg_logs" not in report.to_dict()


def test_the_logs_folder_is_checked_before_writing(report, tmp_path):
    assert check_logs_folder(tmp_path) == tmp_path / "logs"
    (tmp_path / "logs").write_text("a file")
    with pytest.raises(InvalidParameterError, match="is a file; expected a folder"):
        report.write(tmp_path, logs=True)
    assert not (tmp_path / "mission.json").exists()


def test_a_figure_that_fails_warns(report, tmp_path, monkeypatch):
    monkeypatch.setattr(AdaptiveResult, "plot", lambda *a, **k: 1 / 0)
    with pytest.warns(FigureWarning, match="mission.png: ZeroDivisionError"):
        assert [p.name for p in report.write(tmp_path)] == ["mission.json"]


def test_without_adaptation_no_update_is_made():
    flat = terrain.flat_map((10, 30), 1.0, ground="grass")
    report = simulate_adaptive_mission(flat, (2.0, 5.0), (27.0, 5.0), battery=Battery(20.0, 24.0),
                                       settings=AdaptiveSettings(max_updates=0, leg_length_m=5.0))
    assert report.updates == () and "adaptive updates off" in report.summary()


def test_grounds_without_presets_are_refused(corridor_map):
    with pytest.raises(UnknownNameError, match=r"the map's grounds \['Loam'\] have no preset"):
        check_preset_grounds(corridor_map)
    with pytest.raises(UnknownNameError, match="have no preset"):
        simulate_adaptive_mission(corridor_map, (2.5, 7.5), (27.5, 7.5), battery=Battery(5.0, 24.0))
    flat = TerrainMap(corridor_map.elevation_m, 1.0, obstacle=corridor_map.obstacle)
    with pytest.raises(UnknownNameError, match="prior_ground 'lava'"):
        simulate_adaptive_mission(flat, (2.5, 7.5), (27.5, 7.5), battery=Battery(5.0, 24.0), prior_ground="lava")
    with pytest.raises(InvalidParameterError, match="settings must be an AdaptiveSettings"):
        simulate_adaptive_mission(flat, (2.5, 7.5), (27.5, 7.5), battery=Battery(5.0, 24.0),
                                  settings={"leg_length_m": 5.0})


def test_the_battery_voltage_defaults_to_the_robot():
    from energy import robot_preset

    assert mission_battery("jackal", 2.0).voltage_v == robot_preset("jackal").battery_voltage_v
    assert mission_battery("husky", 2.0, 12.0, 10.0).min_reserve_pct == 10.0


def test_the_module_names_its_api():
    assert set(mission_report_module.__all__) == {"simulate_adaptive_mission", "mission_battery",
                                                  "check_preset_grounds"}


def test_an_update_after_the_last_leg_ends_the_mission_at_the_goal():
    # On the example map, 20 m east of (10, 10) are two legs; the second one (on grass, unknown
    # to the asphalt prior) is followed by an accepted update. The loop used to replan from the
    # goal itself, and the mission failed with "start equals goal".
    report = simulate_adaptive_mission(terrain.example_map(), (10.0, 10.0), (30.0, 10.0), battery=Battery(20.0, 24.0))
    result = report
    assert result.status == "completed" and result.distance_to_goal_m == pytest.approx(0.0, abs=1e-6)
    last = len(result.legs) - 1
    assert any(u.after_leg == last and u.accepted for u in result.updates)
