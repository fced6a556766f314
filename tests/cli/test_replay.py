"""The ``terrawatt replay`` command (terrawatt_cli.replay): a mission's own recording through the navigator, from files."""

from __future__ import annotations

import json

import pytest
from cli_samples import is_png, one_line_error, patch_map

from terrawatt_cli import main


def _mission(tmp_path, capsys, *extra):
    path = patch_map(tmp_path)
    out = tmp_path / "mission"
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--logs", "--out", str(out), *extra])
    assert rc == 0, capsys.readouterr()
    capsys.readouterr()
    return path, out, json.loads((out / "mission.json").read_text())


def test_a_missions_legs_and_manoeuvres_replayed_give_its_updates_and_final_route(tmp_path, capsys):
    path, out, mission = _mission(tmp_path, capsys)
    assert mission["accepted_updates"] >= 1
    rc = main(["replay", "--data", str(out / "logs"), "--map", str(path), "--registry", str(out / "start_registry"),
               "--goal", "57", "12", "--battery-ah", "20", "--out", str(tmp_path / "replay")])
    printed = capsys.readouterr().out
    assert rc == 0, printed
    data = json.loads((tmp_path / "replay" / "replay.json").read_text())
    assert data["format"] == "terrawatt-replay" and data["status"] == "completed" and data["mode"] == "legs"
    adaptive = data["adaptive"]
    key = ("kind", "ground", "accepted", "model_id", "region_cells")
    assert [[u[k] for k in key] for u in adaptive["updates"]] == [[u[k] for k in key] for u in mission["updates"]]
    assert [p["route_changed"] for p in adaptive["replans"]] == [p["route_changed"] for p in mission["replans"]]
    assert adaptive["replans"][-1]["predicted_energy_j"] == pytest.approx(mission["replans"][-1]["predicted_energy_j"],
                                                                          rel=0.01)
    assert adaptive["driven_energy_j"] == pytest.approx(mission["driven_energy_j"], rel=1e-6)
    assert is_png(tmp_path / "replay" / "replay.png") and (tmp_path / "replay" / "replay.mcap").is_file()
    assert "manoeuvre" in printed and "replayed in" in printed


def test_the_missions_drive_as_a_ros2_bag_is_replayed_in_chunks(tmp_path, capsys):
    path, out, mission = _mission(tmp_path, capsys, "--drive-bag", str(tmp_path / "drive.mcap"))
    rc = main(["replay", "--data", str(tmp_path / "drive.mcap"), "--cmd-vel-topic", "/odom", "--map", str(path),
               "--registry", str(out / "start_registry"), "--goal", "57", "12", "--battery-ah", "20", "--no-mcap",
               "--state", str(tmp_path / "state"), "--out", str(tmp_path / "replay")])
    printed = capsys.readouterr().out
    assert rc == 0, printed
    data = json.loads((tmp_path / "replay" / "replay.json").read_text())
    assert data["mode"] == "drive" and data["status"] == "completed" and data["chunks"] > 20
    assert (tmp_path / "state" / "navigator.json").is_file()
    # the bag holds no manoeuvre: each request was declined and the driving taught the models
    assert all(u["kind"] in ("driven", "reuse") for u in data["adaptive"]["updates"])
    assert data["adaptive"]["driven_energy_j"] == pytest.approx(mission["driven_energy_j"], rel=0.02)


def test_replay_refuses_what_it_cannot_start_from(tmp_path, capsys):
    path, out, _ = _mission(tmp_path, capsys)
    rc = main(["replay", "--data", str(out / "logs"), "--map", str(path), "--goal", "57", "12", "--battery-ah", "20",
               "--out", str(tmp_path / "r")])
    assert rc == 2 and "--registry or --model" in one_line_error(capsys)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--drive-bag", str(tmp_path / "x.txt"),
               "--out", str(tmp_path / "m2")])
    assert rc == 2 and ".mcap" in one_line_error(capsys)


def test_a_drive_with_gps_is_placed_on_the_map_through_its_crs(tmp_path, capsys):
    import numpy as np

    import terrain
    from energy.io import BagTopics, read_logs, read_navsat

    ground = np.zeros((24, 60), dtype=int)
    ground[6:18, 20:40] = 1
    utm = terrain.TerrainMap(np.zeros((24, 60)), 1.0, origin_xy_m=(500_000.0, 5_000_000.0), crs="EPSG:32632",
                             ground=ground, ground_names={0: "asphalt", 1: "sand"})
    path = utm.save(tmp_path / "utm.npz")
    out = tmp_path / "mission"
    rc = main(["mission", "--map", str(path), "--start", "500003", "5000012", "--goal", "500057", "5000012",
               "--battery-ah", "20", "--logs", "--drive-bag", str(tmp_path / "drive.bag"), "--out", str(out)])
    assert rc == 0, capsys.readouterr()
    capsys.readouterr()
    drive = read_logs(tmp_path / "drive.bag", bag=BagTopics(cmd_vel_topic="/odom"))[0]
    track = read_navsat(tmp_path / "drive.bag", start_time_ns=drive.meta.start_time_ns)
    x, y = utm.lonlat_to_xy(track.lon_deg, track.lat_deg)  # the fixes are the odometry's positions, through the CRS
    np.testing.assert_allclose(np.interp(drive.time_s, track.time_s, x), drive.pose_xyh[:, 0], atol=1e-3)
    rc = main(["replay", "--data", str(tmp_path / "drive.bag"), "--cmd-vel-topic", "/odom", "--gps-topic", "/gps/fix",
               "--map", str(path), "--registry", str(out / "start_registry"), "--goal", "500057", "5000012",
               "--battery-ah", "20", "--no-mcap", "--out", str(tmp_path / "replay")])
    printed = capsys.readouterr().out
    assert rc == 0, printed
    data = json.loads((tmp_path / "replay" / "replay.json").read_text())
    assert data["status"] == "completed" and data["mode"] == "drive"
    rc = main(["replay", "--data", str(tmp_path / "drive.bag"), "--cmd-vel-topic", "/odom", "--gps-topic", "/gps/fix",
               "--registry", str(out / "start_registry"), "--goal", "150", "150", "--battery-ah", "20",
               "--out", str(tmp_path / "r2")])  # the example map has no CRS
    assert rc == 2 and "CRS" in one_line_error(capsys)
