"""The ``terrawatt mission`` command (terrawatt_cli.mission): the adaptive mission end to end on a small patch map."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_samples import is_png, one_line_error, patch_map

import planner.registry
import terrain
from terrawatt_cli import main

_NO_DASK = "Monte Carlo on a cluster needs the distributed extra (dask[distributed])"


def test_mission_writes_budget_json_and_plot(tmp_path, capsys):
    path = patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert rc == 0, out
    data = json.loads((tmp_path / "out" / "mission.json").read_text())
    assert data["status"] == "completed" and data["distance_to_goal_m"] == pytest.approx(0.0, abs=1e-6)
    budget = data["budget"]
    assert budget["battery"]["capacity_ah"] == 20 and budget["battery"]["min_reserve_pct"] == 20
    used = (data["driven_energy_j"] + data["excitation_energy_j"]) / 3600.0
    assert budget["actual_energy_wh"] == pytest.approx(used)
    assert budget["reserve_margin_pct"] == pytest.approx(budget["arrival_soc_pct"] - 20.0)
    assert data["accepted_updates"] >= 1  # the sand is unknown to the asphalt prior
    assert is_png(tmp_path / "out" / "mission.png")
    # the budget written and printed is the library's EnergyBudget of the same mission, not a CLI formula
    expected = _library_mission(path).budget
    assert budget == expected.to_json_dict()
    assert f"final state of charge {expected.arrival_soc_pct:.1f} %" in out
    assert f"{expected.predicted_energy_wh:8.2f} Wh" in out and "fits" in out


def _library_mission(path: Path):
    """The mission `terrawatt mission --map path --start 3 12 --goal 57 12 --battery-ah 20` runs, via the API."""
    from energy import Battery, TruthSimulator, ground_preset, robot_preset
    from planner import AdaptiveSettings, run_adaptive_mission
    from planner.missions import Navigator, NavigatorModels, fit_prior_model

    tmap = terrain.read_map(path)
    robot = robot_preset("husky")
    grounds = {name: ground_preset(name) for name in ("asphalt", "sand")}
    truth = TruthSimulator(robot, grounds, seed=0)
    prior = fit_prior_model(truth, "asphalt", seed=0)
    registry = planner.registry.CellModelRegistry.from_terrain(tmap, prior, prior_name="asphalt-prior")
    return run_adaptive_mission(Navigator(tmap, registry, robot,
                                          Battery(20.0, robot.battery_voltage_v, min_reserve_pct=20.0), (57.0, 12.0),
                                          settings=AdaptiveSettings(speed_mps=0.5, leg_length_m=10.0, seed=0),
                                          models=NavigatorModels(physics_ground=grounds["asphalt"])), truth,
                                (3.0, 12.0))


def test_mission_without_adaptation_makes_no_update(tmp_path, capsys):
    path = patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--no-adapt", "--out", str(tmp_path / "out")])
    assert rc == 0
    data = json.loads((tmp_path / "out" / "mission.json").read_text())
    assert data["updates"] == [] and data["excitation_energy_j"] == 0.0
    capsys.readouterr()


def test_mission_with_a_small_battery_stops_and_says_why(tmp_path, capsys):
    path = patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "0.01",
               "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert rc == 1
    data = json.loads((tmp_path / "out" / "mission.json").read_text())
    assert data["status"] == "budget_exceeded"
    assert "reserve" in data["reason"] and "does NOT fit" in out
    assert data["budget"]["predicted_feasible"] is False


@pytest.mark.parametrize(
    ("extra", "message"),
    [(["--battery-ah", "0"], "--battery-ah must be a number > 0, got 0"),
     (["--battery-ah", "5", "--prior-ground", "lava"], "--prior-ground 'lava' has no preset"),
     (["--battery-ah", "5", "--reserve-pct", "100"], "--reserve-pct must be a percentage in [0, 100), got 100"),
     (["--battery-ah", "5", "--leg-m", "-1"], "--leg-m must be a number > 0, got -1")],
)
def test_mission_bad_input_is_an_error(tmp_path, capsys, extra, message):
    path = patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", *extra,
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out" / "mission.json").exists()


def test_mission_with_start_equal_to_goal_says_so(tmp_path, capsys):
    path = patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "3", "12", "--battery-ah", "20",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "start equals goal" in one_line_error(capsys)
    assert not (tmp_path / "out" / "mission.json").exists()


def test_mission_output_taken_by_a_folder_is_refused_before_the_mission(tmp_path, capsys, monkeypatch):
    import terrawatt_cli.mission as mission_cli

    path = patch_map(tmp_path)
    (tmp_path / "out" / "mission.png").mkdir(parents=True)
    monkeypatch.setattr(mission_cli, "simulate_adaptive_mission", lambda *a, **k: pytest.fail("ran before checking --out"))
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "mission.png" in one_line_error(capsys)


def test_cli_monte_carlo_writes_its_files(tmp_path, capsys):
    rc = main(["mission", "--battery-ah", "5", "--monte-carlo", "4", "--seed", "3", "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert rc == 0
    assert "4 missions (seed 3)" in out and "below the 20 % reserve in 0 of 4 missions" in out
    for name in ("monte_carlo.json", "monte_carlo.csv", "monte_carlo.png"):
        assert (tmp_path / "o" / name).is_file()
    assert json.loads((tmp_path / "o" / "monte_carlo.json").read_text())["n"] == 4


def test_cli_monte_carlo_above_the_risk_threshold_exits_1(tmp_path, capsys):
    rc = main(["mission", "--battery-ah", "0.3", "--monte-carlo", "3", "--out", str(tmp_path / "o")])
    assert rc == 1 and "below the 20 % reserve in 3 of 3 missions" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--monte-carlo", "0"], "--monte-carlo must be a number of missions >= 1, got 0"),
        (["--workers", "2"], "--workers and --scheduler apply to --monte-carlo N only"),
        (["--monte-carlo", "3", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "exclude each other"),
        (["--monte-carlo", "3", "--max-risk-pct", "120"], "--max-risk-pct must be in [0, 100]"),
    ],
)
def test_cli_monte_carlo_bad_flags_exit_2(tmp_path, capsys, extra, message):
    rc = main(["mission", "--battery-ah", "5", *extra, "--out", str(tmp_path / "o")])
    assert rc == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_cli_monte_carlo_on_a_scheduler_gives_the_in_process_study(tmp_path, capsys):
    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    base = ["mission", "--battery-ah", "0.5", "--monte-carlo", "4", "--seed", "5"]
    assert main([*base, "--out", str(tmp_path / "here")]) == 1  # a 0.5 Ah pack is too small for some missions
    # worker processes, as a real scheduler has (a second client on an in-process cluster from the same
    # process shares its event loop thread; that pattern hung once in a full-suite run)
    with distributed.LocalCluster(processes=True, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster:
        assert main([*base, "--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "there")]) == 1
    assert f"on 2 worker(s) ({cluster.scheduler_address})" in capsys.readouterr().out
    here, there = (json.loads((tmp_path / d / "monte_carlo.json").read_text()) for d in ("here", "there"))
    assert here["energy_wh"] == there["energy_wh"] and here["samples"] == there["samples"]


def test_cli_monte_carlo_with_failed_missions_writes_their_rows_and_exits_1(tmp_path, capsys):
    # a 2 V pack delivers at most 1/R W: the missions that draw a resistance above a few mohm fail
    rc = main(["mission", "--battery-ah", "50", "--battery-v", "2", "--monte-carlo", "4", "--seed", "3",
               "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert rc == 1 and "missions failed" in out and "maximum deliverable power" in out
    data = json.loads((tmp_path / "o" / "monte_carlo.json").read_text())
    assert data["n_failed"] >= 1 and len(data["samples"]["error"]) == 4


def test_mission_logs_are_what_diagnose_reads_and_it_names_the_truths_lag(tmp_path, capsys):
    # The CLI path from a simulated mission to its diagnosis: the legs' logs (what the sensors
    # recorded) written by --logs, diagnosed against the planning physics as given on the map the
    # mission drove. The truth differs from that physics by its 0.1 s velocity lag (and its
    # sensor's rest offset, which is logged, never paid): the lag is named, alone.
    from energy.io import read_logs

    out = tmp_path / "out"
    rc = main(["mission", "--start", "10", "10", "--goal", "40", "70", "--battery-ah", "20", "--logs", "--out", str(out)])
    printed = capsys.readouterr().out
    assert rc == 0, printed
    legs = sorted((out / "logs").glob("leg_*.csv"))
    runs = sorted((out / "logs").glob("manoeuvre_*.csv"))  # the excitation manoeuvres, two runs each
    data = json.loads((out / "mission.json").read_text())
    assert len(runs) == 2 * sum(u["kind"] == "excitation" for u in data["updates"])
    assert len(legs) == len(data["legs"]) >= 2 and f"{len(legs)} leg logs and {len(runs)} manoeuvre runs in" in printed
    logs = [read_logs(path)[0] for path in legs]
    assert sum(len(log) for log in logs) == sum(leg["n_samples"] for leg in data["legs"])
    assert all(log.pose_xyh is not None and log.ground is not None for log in logs)
    rc = main(["diagnose", "--data", str(out / "logs"), "--model", "physics", "--map", "example", "--quiet",
               "--out", str(tmp_path / "diag")])
    assert rc == 0, capsys.readouterr()
    diagnosis = json.loads((tmp_path / "diag" / "diagnosis.json").read_text())
    assert diagnosis["chosen"] == ["time_lag"]
    assert 0.0 < diagnosis["ranking"][0]["parameters"]["lag_s"] < 0.15


def test_mission_logs_replace_an_earlier_missions_legs_and_refuse_other_files(tmp_path, capsys, monkeypatch):
    import terrawatt_cli.mission as mission_cli

    out = tmp_path / "out"
    (out / "logs").mkdir(parents=True)
    stale = out / "logs" / "leg_999.csv"
    stale.write_text("an earlier mission's leg")
    argv = ["mission", "--start", "10", "10", "--goal", "30", "10", "--battery-ah", "20", "--logs", "--out", str(out)]
    assert main(argv) == 0
    assert not stale.exists() and (out / "logs" / "leg_000.csv").is_file()
    (out / "logs" / "notes.txt").write_text("mine")
    monkeypatch.setattr(mission_cli, "simulate_adaptive_mission", lambda *a, **k: pytest.fail("ran before checking"))
    capsys.readouterr()
    assert main(argv) == 2
    assert "holds other files (['notes.txt'])" in one_line_error(capsys)
    assert (out / "logs" / "notes.txt").read_text() == "mine"
    assert main(["mission", "--battery-ah", "20", "--monte-carlo", "3", "--logs", "--out", str(out)]) == 2
    assert "--logs and --drive-bag write the legs of one adaptive mission" in one_line_error(capsys)
    (out / "logs" / "notes.txt").unlink()
    mine = out / "logs" / "leg_0042.csv"  # a user's file of a name the mission never writes: refused, never deleted
    mine.write_text("mine")
    assert main(argv) == 2 and "leg_0042.csv" in one_line_error(capsys) and mine.read_text() == "mine"
