"""The ``terrawatt`` command line: each subcommand end to end on small inputs."""

from __future__ import annotations

import json
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

import terrain
from terrawatt_cli import main
from terrain import TerrawattWarning

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _is_png(path: Path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == PNG_MAGIC


def test_demo_plans_on_the_bundled_map_and_writes_json_and_plot(tmp_path, capsys):
    rc = main(["demo", "--planner", "lattice", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "shortest distance" in out and "energy saved vs shortest route" in out
    data = json.loads((tmp_path / "route.json").read_text())
    assert data["status"] == "exact"
    assert set(data["routes"]) == {"min_energy", "lattice", "shortest"}
    saved = data["energy_saved_pct"]
    energies = {k: v["energy_j"] for k, v in data["routes"].items()}
    # the saving printed is the saving between the two routes written
    assert saved == pytest.approx(100.0 * (1 - energies["min_energy"] / energies["shortest"]), rel=1e-9)
    assert saved > 5.0  # the example map is built so that the straight line climbs a hill and crosses sand
    assert data["optimality_ratio"] == pytest.approx(1.0, abs=0.02)
    assert _is_png(tmp_path / "route.png")


def test_plan_on_a_map_file_goes_around_the_wall(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5",
               "--planner", "lattice", "--out", str(tmp_path / "out")])
    assert rc == 0
    wp = np.array(json.loads((tmp_path / "out" / "route.json").read_text())["routes"]["min_energy"]["waypoints_m"])
    assert wp[:, 1].max() >= 30.0  # through the gap at y in [30, 34)
    assert _is_png(tmp_path / "out" / "route.png")
    capsys.readouterr()


def test_plan_stopped_short_by_its_work_bound_is_not_compared_and_fails(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    args = ["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "RRTstar",
            "--max-evaluations", "30", "--seed", "1", "--out", str(tmp_path / "out")]
    rc = main(args)
    out = capsys.readouterr().out
    data = json.loads((tmp_path / "out" / "route.json").read_text())
    assert rc == 1 and data["status"] == "approximate" and data["max_evaluations"] == 30
    assert "short of the goal" in out and "energy saved" not in out
    assert data["energy_saved_pct"] is None and data["optimality_ratio"] is None
    main(args)  # the same work bound and seed give the same route
    again = json.loads((tmp_path / "out" / "route.json").read_text())
    assert again["routes"]["min_energy"]["waypoints_m"] == data["routes"]["min_energy"]["waypoints_m"]
    capsys.readouterr()


@pytest.mark.parametrize(
    ("start", "message"),
    [(("20.5", "10"), "obstacle"), (("-5", "10"), "outside")],
)
def test_plan_reports_a_bad_start_as_an_error(tmp_path, capsys, wall_map, start, message):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", *start, "--goal", "35", "5", "--planner", "lattice",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert message in capsys.readouterr().err


def test_plan_reports_a_corrupt_map_file(tmp_path, capsys):
    bad = tmp_path / "broken.npz"
    bad.write_bytes(b"not a zip archive")
    rc = main(["plan", "--map", str(bad), "--start", "1", "1", "--goal", "2", "2", "--out", str(tmp_path)])
    assert rc == 2
    assert "corrupt" in capsys.readouterr().err


def test_unknown_planner_is_refused_with_the_valid_names(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--planner", "Dijkstra", "--out", str(tmp_path)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "Dijkstra" in err and "RRTstar" in err


def _patch_map(tmp_path: Path) -> Path:
    """Level asphalt with a sand band across the straight line."""
    ground = np.zeros((24, 60), dtype=int)
    ground[6:18, 20:40] = 1
    tmap = terrain.TerrainMap(np.zeros((24, 60)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})
    return tmap.save(tmp_path / "patch.npz")


def test_mission_writes_budget_json_and_plot(tmp_path, capsys):
    path = _patch_map(tmp_path)
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
    assert _is_png(tmp_path / "out" / "mission.png")
    # the budget written and printed is the library's EnergyBudget of the same mission, not a CLI formula
    expected = _library_mission(path).budget
    assert budget == expected.to_json_dict()
    assert f"final state of charge {expected.arrival_soc_pct:.1f} %" in out
    assert f"{expected.predicted_energy_wh:8.2f} Wh" in out and "fits" in out


def _library_mission(path: Path):
    """The mission `terrawatt mission --map path --start 3 12 --goal 57 12 --battery-ah 20` runs, via the API."""
    from energy import Battery, TruthSimulator, ground_preset, robot_preset
    from planner import AdaptiveSettings, run_adaptive_mission
    from planner.missions import fit_prior_model

    tmap = terrain.read_map(path)
    robot = robot_preset("husky")
    grounds = {name: ground_preset(name) for name in ("asphalt", "sand")}
    truth = TruthSimulator(robot, grounds, seed=0)
    prior = fit_prior_model(truth, "asphalt", seed=0)
    registry = terrain.CellModelRegistry.from_terrain(tmap, prior, prior_name="asphalt-prior")
    return run_adaptive_mission(tmap, registry, robot, Battery(20.0, robot.battery_voltage_v, min_reserve_pct=20.0),
                                truth, (3.0, 12.0), (57.0, 12.0), physics_ground=grounds["asphalt"],
                                settings=AdaptiveSettings(speed_mps=0.5, leg_length_m=10.0, seed=0))


def test_mission_without_adaptation_makes_no_update(tmp_path, capsys):
    path = _patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--no-adapt", "--out", str(tmp_path / "out")])
    assert rc == 0
    data = json.loads((tmp_path / "out" / "mission.json").read_text())
    assert data["updates"] == [] and data["excitation_energy_j"] == 0.0
    capsys.readouterr()


def test_mission_with_a_small_battery_stops_and_says_why(tmp_path, capsys):
    path = _patch_map(tmp_path)
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
     (["--battery-ah", "5", "--reserve-pct", "100"], "--reserve-pct must be in [0, 100), got 100"),
     (["--battery-ah", "5", "--leg-m", "-1"], "--leg-m must be a number > 0, got -1")],
)
def test_mission_bad_input_is_an_error(tmp_path, capsys, extra, message):
    path = _patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", *extra,
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out" / "mission.json").exists()


def test_train_then_predict_round_trip(tmp_path, capsys):
    model = tmp_path / "linear.pt"
    assert main(["train", "--data", str(FIXTURES), "--model", "linear", "--out", str(model)]) == 0
    assert model.is_file()
    assert main(["predict", "--model", str(model), "--data", str(FIXTURES), "--out", str(tmp_path / "pred"),
                 "--plots"]) == 0
    figures = sorted(p.name for p in (tmp_path / "pred" / "plots").iterdir())
    assert figures == ["current_asphalt_pro_00.png", "current_snow_pro_05.png"]
    assert all(_is_png(tmp_path / "pred" / "plots" / f) for f in figures)
    runs = json.loads((tmp_path / "pred" / "predictions.json").read_text())["runs"]
    assert {(r["ground"], r["side"]) for r in runs} == {(g, s) for g in ("asphalt", "snow") for s in ("left", "right")}
    for r in runs:
        assert r["charge_true_mah"] > 0 and np.isfinite(r["charge_predicted_mah"])
        assert r["whole_run_error_pct"] == pytest.approx(
            100.0 * abs(r["charge_predicted_mah"] - r["charge_true_mah"]) / r["charge_true_mah"], rel=1e-6
        )
    capsys.readouterr()


@pytest.fixture
def tiny_paper_preset(monkeypatch):
    """The ``paper`` preset shrunk to train in a second on the two short fixture runs."""
    from energy import estimator_preset
    from energy.models import ESTIMATOR_PRESETS

    small = estimator_preset("paper").replace(max_epochs=2, n_spectrum_bins=100, hidden_sizes=(8, 8, 8))
    monkeypatch.setitem(ESTIMATOR_PRESETS, "paper", small)


def test_train_passes_threads_and_shows_the_loss(tmp_path, capsys, monkeypatch, tiny_paper_preset):
    import torch

    from energy import load_current_model

    calls = []
    real = torch.set_num_threads
    monkeypatch.setattr(torch, "set_num_threads", lambda n: (calls.append(n), real(n))[1])
    before = torch.get_num_threads()
    model = tmp_path / "paper.pt"
    assert main(["train", "--data", str(FIXTURES), "--model", "paper", "--threads", "1", "--out", str(model)]) == 0
    loaded = load_current_model(model)
    assert (loaded.n_threads, loaded.progress) == (1, True)
    assert calls[0] == 1 and torch.get_num_threads() == before  # used while fitting, restored after
    assert "loss=" in capsys.readouterr().err  # the progress bar's postfix

    quiet = tmp_path / "quiet.pt"
    assert main(["train", "--data", str(FIXTURES), "--model", "paper", "--quiet", "--out", str(quiet)]) == 0
    loaded = load_current_model(quiet)
    assert (loaded.n_threads, loaded.progress) == (None, False)
    assert "loss=" not in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, message",
    [(["--model", "paper", "--threads", "0"], "--threads must be a positive number of threads, got 0"),
     (["--model", "linear", "--threads", "2"], "--threads applies to the estimator and paper models only")],
)
def test_train_bad_threads_is_an_error(tmp_path, capsys, extra, message):
    rc = main(["train", "--data", str(FIXTURES), *extra, "--out", str(tmp_path / "m.pt")])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "m.pt").exists()


def test_predict_with_a_corrupt_model_file_is_an_error(tmp_path, capsys):
    bad = tmp_path / "model.pt"
    bad.write_bytes(b"\x00garbage")
    rc = main(["predict", "--model", str(bad), "--data", str(FIXTURES), "--out", str(tmp_path)])
    assert rc == 2
    assert "model.pt" in capsys.readouterr().err


def test_evaluate_writes_json_and_markdown(tmp_path, capsys):
    data = tmp_path / "logs"
    shutil.copytree(FIXTURES, data)
    # a second asphalt run, so leave-one-run-out has something to train on per ground
    for kind in ("imu", "pro"):
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    with pytest.warns(TerrawattWarning, match="'snow' has 1 run"):
        rc = main(["evaluate", "--data", str(data), "--model", "constant", "linear", "--out", str(tmp_path / "out")])
    assert rc == 0
    result = json.loads((tmp_path / "out" / "evaluation.json").read_text())
    assert result["models"] == ["constant", "linear"]
    assert result["skipped"] == ["ground 'snow' has 1 run; per-ground leave-one-run-out needs 2"]
    rows = {(r["variant"], r["ground"], r["model"]): r for r in result["summary"]}
    # each asphalt run is held out against its identical copy: the constant model's charge is exact
    assert rows[("per_ground", "asphalt", "constant")]["whole_run_median_pct"] == pytest.approx(0.0, abs=1e-9)
    assert rows[("ground_agnostic", "snow", "constant")]["n_runs"] == 1
    assert rows[("ground_agnostic", "snow", "constant")]["whole_run_median_pct"] > 10.0  # trained on asphalt only
    md = (tmp_path / "out" / "evaluation.md").read_text()
    assert "| per_ground | asphalt | constant | 2 |" in md
    assert _is_png(tmp_path / "out" / "spectra.png")
    capsys.readouterr()


@pytest.fixture
def dask_environ_restored():
    """Undo what dask's nanny writes into this process's environment before it spawns a
    worker (``OMP_NUM_THREADS=1`` & co.), so later tests see the environment they started with."""
    dask = pytest.importorskip("dask", reason="--workers needs the distributed extra (dask[distributed])")
    pytest.importorskip("distributed", reason="--workers needs the distributed extra (dask[distributed])")
    keys = [*dask.config.get("distributed.nanny.pre-spawn-environ"), "PYTHONHASHSEED"]
    before = {k: os.environ.get(k) for k in keys}
    yield
    for k, v in before.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def test_evaluate_on_two_local_workers_gives_the_serial_scores(tmp_path, capsys, dask_environ_restored):
    data = tmp_path / "logs"
    shutil.copytree(FIXTURES, data)
    for kind in ("imu", "pro"):
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    runs = {}
    for workers in ("1", "2"):
        with pytest.warns(TerrawattWarning, match="'snow' has 1 run"):
            rc = main(["evaluate", "--data", str(data), "--model", "constant", "linear", "--workers", workers,
                       "--out", str(tmp_path / workers)])
        assert rc == 0
        assert f"on {workers} {'worker (serial)' if workers == '1' else 'dask workers'}" in capsys.readouterr().out
        runs[workers] = json.loads((tmp_path / workers / "evaluation.json").read_text())["runs"]
    assert len(runs["2"]) == len(runs["1"]) == 20
    for serial, parallel in zip(runs["1"], runs["2"]):
        for key, value in serial.items():
            # same rows in the same order; worker processes run one BLAS thread, so allow last-bit differences
            if key != "fit_duration_s":
                assert parallel[key] == (value if isinstance(value, str) else pytest.approx(value, rel=1e-12, abs=1e-12))


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"],
         "--workers 2 and --scheduler 'tcp://127.0.0.1:8786' exclude each other"),
        (["--workers", "0"], "--workers must be a positive number of processes, got 0"),
    ],
)
def test_evaluate_refuses_bad_worker_options(tmp_path, capsys, extra, message):
    rc = main(["evaluate", "--data", str(FIXTURES), "--model", "constant", "--out", str(tmp_path / "out"), *extra])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_evaluate_on_workers_without_distributed_names_the_extra(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` now raises ImportError
    rc = main(["evaluate", "--data", str(FIXTURES), "--model", "constant", "--workers", "2",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "--workers 2 needs dask.distributed; install it with: pip install 'terrawatt[distributed]'" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "out").exists()


def test_plan_on_a_geotiff_dem_uses_the_unknown_ground_preset(tmp_path, capsys):
    pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    from terrain import ramp_map, write_geotiff

    dem = write_geotiff(ramp_map((30, 40), 1.0, grade=0.05), tmp_path / "dem.tif")
    out = tmp_path / "out"
    rc = main(["plan", "--map", str(dem), "--start", "3", "3", "--goal", "36", "26", "--planner", "lattice",
               "--out", str(out)])
    assert rc == 0
    data = json.loads((out / "route.json").read_text())
    assert data["map"] == "dem.tif" and data["status"] == "exact"
    # a DEM carries no ground classes: every cell is unknown and priced as gravel, and says so
    out_text = capsys.readouterr().out
    assert "grounds {}" in out_text and "unknown in 1200 of 1200 cells: priced as 'gravel'" in out_text
    rc = main(["plan", "--map", str(dem), "--start", "3", "3", "--goal", "36", "26", "--planner", "lattice",
               "--unknown-ground", "none", "--out", str(out)])
    assert rc == 2
    assert "unknown" in capsys.readouterr().err


def test_plan_on_a_geotiff_with_nodata_needs_fill_nodata(tmp_path, capsys):
    rasterio = pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    from affine import Affine

    from terrain import DataRepairWarning

    z = np.tile(0.05 * np.arange(40.0), (30, 1)).astype(np.float32)
    z[10:13, 18:21] = -9999.0  # a hole in the survey
    dem = tmp_path / "holes.tif"
    with rasterio.open(dem, "w", driver="GTiff", height=30, width=40, count=1, dtype="float32",
                       transform=Affine(1.0, 0.0, 0.0, 0.0, -1.0, 30.0), nodata=-9999.0) as dst:
        dst.write(z, 1)
    args = ["plan", "--map", str(dem), "--start", "3", "3", "--goal", "36", "26", "--planner", "lattice",
            "--out", str(tmp_path / "out")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "--fill-nodata nearest" in err and "fill_nodata=" not in err
    with pytest.warns(DataRepairWarning, match="filled 9 nodata cells"):
        assert main([*args, "--fill-nodata", "nearest"]) == 0
    assert json.loads((tmp_path / "out" / "route.json").read_text())["status"] == "exact"
    capsys.readouterr()


# ---------------------------------------------------------------- CLI rules: exit codes, outputs, flags


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("terrawatt: error: ") and "Traceback" not in err and err.count("\n") == 1, err
    return err


def test_plan_with_start_equal_to_goal_says_so(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "5", "5", "--planner", "lattice",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    err = _one_line_error(capsys)
    assert "start equals goal" in err and "nan" not in err
    assert not (tmp_path / "out" / "route.json").exists()


def test_mission_with_start_equal_to_goal_says_so(tmp_path, capsys):
    path = _patch_map(tmp_path)
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "3", "12", "--battery-ah", "20",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "start equals goal" in _one_line_error(capsys)
    assert not (tmp_path / "out" / "mission.json").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--max-slope-deg", "95"], "--max-slope-deg must be between 0 and 90 degrees (exclusive), got 95"),
        (["--unknown-ground", "lava"], "--unknown-ground must be a ground preset"),
        (["--speed", "0"], "--speed must be a number > 0, got 0"),
        (["--time-limit", "-1"], "--time-limit must be a number > 0, got -1"),
    ],
)
def test_plan_flags_are_checked_and_named_as_flags(tmp_path, capsys, wall_map, extra, message):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               *extra, "--out", str(tmp_path / "out")])
    assert rc == 2
    err = _one_line_error(capsys)
    assert message in err
    assert "max_slope_rad" not in err and "unknown_ground=" not in err and "speed_mps" not in err


def test_unknown_ground_none_on_a_map_with_unknown_cells_names_the_flag(tmp_path, capsys):
    ground = np.zeros((20, 20), dtype=int)
    ground[5:8, 5:8] = -1
    tmap = terrain.TerrainMap(np.zeros((20, 20)), 1.0, ground=ground, ground_names={0: "asphalt"})
    path = tmap.save(tmp_path / "holes.npz")
    rc = main(["plan", "--map", str(path), "--start", "1", "1", "--goal", "18", "18", "--planner", "lattice",
               "--unknown-ground", "none", "--out", str(tmp_path / "out")])
    assert rc == 2
    err = _one_line_error(capsys)
    assert "unknown in 9 of 400 cells" in err and "--unknown-ground none" in err and "unknown_ground=" not in err


def test_a_missing_map_file_is_one_line_and_exit_2(tmp_path, capsys):
    rc = main(["plan", "--map", str(tmp_path / "nowhere.npz"), "--start", "1", "1", "--goal", "2", "2",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "nowhere.npz" in _one_line_error(capsys)


def test_plan_output_folder_that_is_a_file_is_refused_before_planning(tmp_path, capsys, wall_map, monkeypatch):
    import terrawatt_cli.plan as plan_cli

    path = wall_map.save(tmp_path / "wall.npz")
    out = tmp_path / "out"
    out.write_text("a file where the folder goes")
    monkeypatch.setattr(plan_cli, "plan_and_compare", lambda *a, **k: pytest.fail("planned before checking --out"))
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               "--out", str(out)])
    assert rc == 2
    assert "--out" in _one_line_error(capsys)
    (tmp_path / "out2" / "route.json").mkdir(parents=True)  # the JSON's place taken by a folder
    rc = main(["demo", "--planner", "lattice", "--out", str(tmp_path / "out2")])
    assert rc == 2
    assert "route.json" in _one_line_error(capsys)


def test_train_onto_a_directory_is_refused_before_training(tmp_path, capsys, monkeypatch):
    import terrawatt_cli.train as train_cli

    monkeypatch.setattr(train_cli, "logs_from_args", lambda *a, **k: pytest.fail("read the logs before checking --out"))
    rc = main(["train", "--data", str(FIXTURES), "--model", "linear", "--out", str(tmp_path)])
    assert rc == 2
    assert "--out" in _one_line_error(capsys)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc = main(["train", "--data", str(FIXTURES), "--model", "linear", "--out", str(blocker / "model.pt")])
    assert rc == 2
    assert "--out" in _one_line_error(capsys)


def test_mission_output_taken_by_a_folder_is_refused_before_the_mission(tmp_path, capsys, monkeypatch):
    import terrawatt_cli.mission as mission_cli

    path = _patch_map(tmp_path)
    (tmp_path / "out" / "mission.png").mkdir(parents=True)
    monkeypatch.setattr(mission_cli, "simulate_adaptive_mission", lambda *a, **k: pytest.fail("ran before checking --out"))
    rc = main(["mission", "--map", str(path), "--start", "3", "12", "--goal", "57", "12", "--battery-ah", "20",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "mission.png" in _one_line_error(capsys)


def test_evaluate_whose_figure_fails_still_succeeds_with_its_results(tmp_path, capsys, monkeypatch):
    import terrawatt_cli.evaluate as evaluate_cli
    from terrain import InvalidParameterError

    def no_spectra(*args, **kwargs):
        raise InvalidParameterError("band (0.5, 50.0) Hz exceeds the Nyquist frequency 25 Hz of a 50 Hz IMU")

    monkeypatch.setattr(evaluate_cli, "plot_vibration_spectra", no_spectra)
    data = tmp_path / "logs"
    shutil.copytree(FIXTURES, data)
    for kind in ("imu", "pro"):
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    with pytest.warns(TerrawattWarning, match="'snow' has 1 run"):
        rc = main(["evaluate", "--data", str(data), "--model", "constant", "--out", str(tmp_path / "out")])
    assert rc == 0
    assert json.loads((tmp_path / "out" / "evaluation.json").read_text())["models"] == ["constant"]
    err = capsys.readouterr().err
    assert "warning: could not draw" in err and "spectra.png" in err and "Nyquist" in err
    assert not (tmp_path / "out" / "spectra.png").exists()
