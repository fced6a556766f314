"""The ``terrawatt replay`` command (terrawatt_cli.replay): a mission's own recording through the navigator, from files."""

from __future__ import annotations

import json

import pytest

from terrawatt_cli import main

from cli_samples import is_png, one_line_error, patch_map


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
