"""``terrawatt diagnose`` end to end on short synthetic CSV logs: files written, flags checked, output folder first."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from diagnosis_scenarios import scenario

from energy import load_current_model, write_csv_log
from terrawatt_base import plot_target
from terrawatt_cli import diagnose as diagnose_cli
from terrawatt_cli import main

PNG = b"\x89PNG\r\n\x1a\n"
FIGURES = ("residual_time.png", "gap_by_regime.png", "gap_map.png", "effect_ranking.png", "waterfall.png")


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """Three 8 s runs of a Husky pivoting and arcing (turning resistance on in the truth), as CSV logs,
    the map they drove on, and a saved physics model without turning resistance."""
    root = tmp_path_factory.mktemp("diagnose_data")
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    (root / "logs").mkdir()
    for k, log in enumerate(sc.make_logs(0)):
        write_csv_log(log, root / "logs" / f"run_{k}.csv")
    sc.terrain.save(root / "map.npz")
    sc.make_model(0).save(root / "model.zip")
    return root


def _run(capsys, *argv):
    rc = main(["diagnose", *map(str, argv)])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_physics_without_an_effect_writes_every_file(data, tmp_path, capsys):
    rc, out, err = _run(capsys, "--model", "physics", "--without", "turning_resistance", "--ground", "coated_wood",
                        "--data", data / "logs", "--map", data / "map.npz", "--out", tmp_path / "out", "--seed", 1, "--quiet")
    assert rc == 0, err
    files = {p.name for p in (tmp_path / "out").iterdir()}
    assert files == {"diagnosis.json", "diagnosis.md", "corrected_model.zip", *FIGURES}
    assert all((tmp_path / "out" / f).read_bytes()[:8] == PNG for f in FIGURES)
    doc = json.loads((tmp_path / "out" / "diagnosis.json").read_text())
    assert doc["split"] == "runs" and doc["waterfall"][0]["label"] == "as given"
    assert "presets as given" in out and "not fitted on the 3 runs it is diagnosed on" in out
    assert "without turning_resistance" in out
    assert doc["verdict"][0] in out  # the verdict is printed ...
    assert "charge err %" in out and "as given" in out  # ... and the waterfall as a table
    corrected = load_current_model(tmp_path / "out" / "corrected_model.zip")
    assert type(corrected).__name__ == "CorrectedCurrentModel"
    assert err == ""  # --quiet: no progress bars


def test_the_physics_model_is_calibrated_on_other_runs_only(data, tmp_path, capsys):
    # --calibration-data fits the coefficients on runs that are not diagnosed, and says which
    rc, out, err = _run(capsys, "--model", "physics", "--without", "turning_resistance", "--ground", "coated_wood",
                        "--data", data / "logs" / "run_0.csv", "--calibration-data", data / "logs" / "run_1.csv",
                        "--split", "blocks", "--effects", "turning_resistance", "--out", tmp_path / "out", "--quiet")
    assert rc == 0, err
    assert "fitted on the 1 run of" in out and "which are not diagnosed" in out and "run_1.csv" in out
    # the report says which runs calibrated the model
    assert "which are not diagnosed" in json.loads((tmp_path / "out" / "diagnosis.json").read_text())["model_note"]
    assert "Model under test: physics" in (tmp_path / "out" / "diagnosis.md").read_text()
    # the same runs on both sides, or one folder inside the other, are refused before any work
    for cal in (data / "logs" / "run_0.csv", data / "logs"):
        rc, out, err = _run(capsys, "--model", "physics", "--data", data / "logs" / "run_0.csv", "--calibration-data",
                            cal, "--out", tmp_path / "x")
        assert rc == 2 and "calibrate on runs that are not diagnosed" in err
    assert not (tmp_path / "x").exists()


def test_a_saved_model_on_one_csv_file_without_a_map_skips_the_map_figure(data, tmp_path, capsys):
    rc, out, err = _run(capsys, "--model", data / "model.zip", "--data", data / "logs" / "run_0.csv",
                        "--out", tmp_path, "--split", "blocks", "--effects", "turning_resistance", "idle_current")
    assert rc == 0, err
    assert "loaded from" in out and "skipped gap_map.png: no map figure: no terrain map given" in out
    assert not (tmp_path / "gap_map.png").exists()
    assert json.loads((tmp_path / "diagnosis.json").read_text())["split"] == "blocks"
    assert (tmp_path / "waterfall.png").read_bytes()[:8] == PNG


@pytest.mark.parametrize("extra, message", [
    (["--model", "physics", "--without", "warp_drive"], "--without"),
    (["--model", "physics", "--effects", "warp_drive"], "--effects"),
    (["--model", "physics", "--ground", "lava"], "--ground"),
    (["--model", "physics", "--robot", "rover"], "--robot"),
    (["--model", "estimator", "--without", "inertia"], "--without applies to --model physics only"),
    (["--model", "no_such_model.zip"], "--model must be 'physics', 'estimator' or a model file"),
    (["--model", "estimator"], "--model estimator needs --calibration-data"),
    (["--model", "physics", "--calibration-data", "no_such_folder"], "--calibration-data 'no_such_folder' does not"),
    (["--model", "physics", "--seed", "-1"], "--seed"),
    (["--model", "physics", "--workers", "0"], "--workers must be a positive number"),
    (["--model", "physics", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "exclude each other"),
    (["--model", "physics", "--landcover", "lc.tif", "--landcover-classes", "c.csv"],
     "--landcover, --landcover-classes describe(s) the map of --map MAP, which is not given"),
])
def test_bad_flags_exit_2_naming_the_flag(data, tmp_path, capsys, extra, message):
    rc, out, err = _run(capsys, *extra, "--data", data / "logs", "--out", tmp_path / "out")
    assert rc == 2
    assert err.startswith("terrawatt: error: ") and err.count("\n") == 1 and message in err
    assert not (tmp_path / "out").exists()


def test_a_bad_split_is_refused_by_the_parser_naming_the_flag(data, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["diagnose", "--model", "physics", "--data", str(data / "logs"), "--out", str(tmp_path), "--split", "rows"])
    assert exc.value.code == 2 and "--split" in capsys.readouterr().err


def test_an_output_path_that_is_a_file_exits_2_before_any_work(data, tmp_path, capsys, monkeypatch):
    def no_work(*args, **kwargs):
        raise AssertionError("read the logs although --out was refused")

    monkeypatch.setattr(diagnose_cli, "logs_from_args", no_work)
    (tmp_path / "taken").write_text("x")
    rc, _, err = _run(capsys, "--model", "physics", "--data", data / "logs", "--out", tmp_path / "taken")
    assert rc == 2 and "--out" in err and "is a file" in err
    (tmp_path / "out" / "diagnosis.md").mkdir(parents=True)
    rc, _, err = _run(capsys, "--model", "physics", "--data", data / "logs", "--out", tmp_path / "out")
    assert rc == 2 and "diagnosis.md" in err and "is a directory" in err


def test_data_that_holds_no_logs_exits_2(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    (tmp_path / "notes.txt").write_text("x")
    rc, _, err = _run(capsys, "--model", "physics", "--data", tmp_path / "empty", "--out", tmp_path / "out")
    assert rc == 2 and "holds no logs" in err
    rc, _, err = _run(capsys, "--model", "physics", "--data", tmp_path / "notes.txt", "--out", tmp_path / "out")
    assert rc == 2 and "unknown log file type '.txt'" in err
    rc, _, err = _run(capsys, "--model", "physics", "--data", tmp_path / "missing", "--out", tmp_path / "out")
    assert rc == 2 and "does not exist" in err


def test_a_failing_figure_warns_and_the_command_still_succeeds(data, tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(plot_target, "new_figure", broken)
    rc, out, err = _run(capsys, "--model", data / "model.zip", "--data", data / "logs", "--out", tmp_path,
                        "--effects", "turning_resistance")
    assert rc == 0
    assert "terrawatt: warning: could not draw" in err and "RuntimeError: no canvas" in err
    assert {p.name for p in Path(tmp_path).iterdir()} == {"diagnosis.json", "diagnosis.md", "corrected_model.zip"}


def test_a_tie_writes_its_separating_drive_as_commands_and_a_figure(tmp_path, capsys):
    """A payload seen on straights at one speed each: mass, rolling resistance and an offset tie; the command
    writes the drive that tells them apart (the commands a robot can drive, each model's currents) and its figure."""
    import numpy as np

    from energy import PhysicsCurrentModel, TruthSimulator, ground_preset, robot_preset

    husky = robot_preset("husky")
    laden = TruthSimulator(husky.replace(mass_kg=1.6 * husky.mass_kg), {"asphalt": ground_preset("asphalt")},
                           velocity_time_constant_s=0.0, seed=0)
    t = np.arange(0.0, 30.0, 0.05)
    (tmp_path / "logs").mkdir()
    runs = [laden.simulate_commands(t, np.full(t.size, 0.4 + 0.1 * k), 0 * t, ground="asphalt", seed=k) for k in range(4)]
    for k, log in enumerate(runs):
        write_csv_log(log, tmp_path / "logs" / f"run_{k}.csv")
    PhysicsCurrentModel("husky", "asphalt", fit_parameters=()).fit(runs[:1]).save(tmp_path / "model.zip")
    rc, out, err = _run(capsys, "--model", tmp_path / "model.zip", "--data", tmp_path / "logs", "--out", tmp_path / "out",
                        "--effects", "mass", "rolling_resistance", "current_offset", "--quiet")
    assert rc == 0, err
    doc = json.loads((tmp_path / "out" / "diagnosis.json").read_text())
    (tie,) = doc["indistinguishable"]
    assert tie["chosen"] == "mass" and set(tie["alternatives"]) == {"rolling_resistance", "current_offset"}
    (drive,) = doc["separating_drives"]
    stem = f"separating_drive_{tie['chosen']}"
    assert drive["csv"] == f"{stem}.csv" and drive["drive"]["duration_s"] <= 60.0
    table = np.loadtxt(tmp_path / "out" / f"{stem}.csv", delimiter=",", skiprows=1)
    assert table.shape[1] == 3 + 2 * 3 and np.all(np.diff(table[:, 0]) > 0)  # time, v, omega, then 3 models x 2 sides
    assert (tmp_path / "out" / f"{stem}.png").read_bytes()[:8] == PNG
    assert "cannot tell them apart" in out and "To tell mass from" in out
