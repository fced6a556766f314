"""``terrawatt plan --model FILE [--risk Q]`` (and reach, batch, mission): a saved current model prices the map."""

from __future__ import annotations

import json

import numpy as np
import pytest

from terrawatt_cli import main

START, GOAL = ["2.5", "7.5"], ["27.5", "7.5"]
Z90 = 1.2815515655446004


@pytest.fixture
def files(tmp_path, corridor_map, known_model):
    return (corridor_map.save(tmp_path / "corridors.npz"), known_model().save(tmp_path / "husky.tw"))


def _plan(tmp_path, files, *extra):
    out = tmp_path / ("out" + "_".join(extra).replace("-", "").replace(".", ""))
    rc = main(["plan", "--map", str(files[0]), "--start", *START, "--goal", *GOAL, "--planner", "lattice",
               "--model", str(files[1]), "--out", str(out), *extra])
    return rc, out


def _crosses_loam(route_json) -> bool:
    wp = np.array(route_json["routes"]["min_energy"]["waypoints_m"])
    return bool(wp[:, 1].max() > 9.0)  # the loam corridor lies at y in [10, 13) m, the gravel one at [2, 5)


def test_plan_with_a_model_prints_and_writes_the_interval_and_risk_changes_the_corridor(tmp_path, capsys, files):
    rc, out = _plan(tmp_path, files)
    assert rc == 0
    text = capsys.readouterr().out
    assert "edge costs: model husky.tw (GroundKeyedModel) on grounds ['loam', 'gravel']" in text
    assert "P50" in text and "P90" in text
    mean = json.loads((out / "route.json").read_text())
    iv = mean["routes"]["min_energy"]["energy_interval"]
    assert _crosses_loam(mean)
    assert iv["p90_j"] == pytest.approx(iv["mean_j"] + Z90 * iv["sd_j"]) and iv["sd_j"] > 0
    assert iv["central_interval_j"][0] < iv["mean_j"] < iv["central_interval_j"][1]
    assert mean["model"]["risk_q"] is None and mean["model"]["gives_interval"] is True
    assert (out / "route.png").read_bytes()[:4] == b"\x89PNG"

    rc, out90 = _plan(tmp_path, files, "--risk", "0.9")
    assert rc == 0
    risky = json.loads((out90 / "route.json").read_text())
    assert not _crosses_loam(risky)  # the certain gravel corridor
    assert risky["routes"]["min_energy"]["energy_interval"]["sd_j"] == 0.0
    assert risky["routes"]["min_energy"]["energy_interval"]["p90_j"] < iv["p90_j"]
    rc, out50 = _plan(tmp_path, files, "--risk", "0.5")  # the median: the mean route again
    assert rc == 0 and _crosses_loam(json.loads((out50 / "route.json").read_text()))


def test_plan_without_a_model_writes_no_interval_or_model_block(tmp_path, capsys, wall_map):
    rc = main(["plan", "--map", str(wall_map.save(tmp_path / "wall.npz")), "--start", "5", "5", "--goal", "35", "5",
               "--planner", "lattice", "--out", str(tmp_path / "plain")])
    assert rc == 0
    result = json.loads((tmp_path / "plain" / "route.json").read_text())
    assert "model" not in result and "energy_interval" not in result["routes"]["min_energy"]
    assert "P90" not in capsys.readouterr().out


@pytest.mark.parametrize("extra, message", [
    (["--robot", "jackal"], "trained on robot(s) ['husky_a200'], not on the robot preset 'jackal' (['husky_a200'] do "
                            "not match): train a model on 'jackal' logs, or give the model's robot as --robot"),
    (["--model-ground", "sand"], "--model-ground 'sand' is not a ground the model drove"),
    (["--risk", "1.5"], "--risk must be"),
    (["--risk", "1e-9"], "--risk 1e-09 lies below the median"),  # mean - 6 sd floored at 0: a route "costing" 0 J
])
def test_plan_with_an_incompatible_model_or_bad_flags_is_exit_2(tmp_path, capsys, files, extra, message):
    rc, _ = _plan(tmp_path, files, *extra)
    assert rc == 2
    assert message in capsys.readouterr().err


def test_risk_needs_a_model_with_an_interval(tmp_path, capsys, corridor_map, known_model):
    flat = {"loam": [9.0, 2.0, 4.0, 0.0], "gravel": [10.5, 2.5, 4.5, 0.0]}
    files = (corridor_map.save(tmp_path / "c.npz"), known_model(grounds=flat).save(tmp_path / "point.tw"))
    rc, _ = _plan(tmp_path, files, "--risk", "0.9")
    assert rc == 2 and "needs a model with a predictive interval" in capsys.readouterr().err
    rc = main(["plan", "--map", str(files[0]), "--start", *START, "--goal", *GOAL, "--risk", "0.9",
               "--out", str(tmp_path / "x")])
    assert rc == 2 and "--risk needs --model FILE" in capsys.readouterr().err


def test_mission_monte_carlo_draws_from_the_model_and_checks_the_reserve_at_a_quantile(tmp_path, capsys, corridor_map,
                                                                                      known_model):
    from terrain import TerrainMap

    tmap = TerrainMap(corridor_map.elevation_m, 1.0, ground=corridor_map.ground, obstacle=corridor_map.obstacle,
                      ground_names={0: "sand", 1: "gravel"})  # preset names: the mission simulates its grounds
    grounds = {"sand": [9.0, 2.0, 4.0, 1.0], "gravel": [10.5, 2.5, 4.5, 0.0]}
    model = known_model(trained_on=("sand", "gravel"), grounds=grounds).save(tmp_path / "m.tw")
    common = ["mission", "--map", str(tmap.save(tmp_path / "m.npz")), "--start", *START, "--goal", *GOAL,
              "--model", str(model), "--monte-carlo", "50", "--mc-draw", "model"]
    rc = main([*common, "--battery-ah", "5", "--risk", "0.9", "--out", str(tmp_path / "big")])
    text = capsys.readouterr().out
    assert rc == 0 and "predictive distribution" in text and "reserve check at Q = 0.9" in text and "fits" in text
    data = json.loads((tmp_path / "big" / "monte_carlo.json").read_text())
    assert data["draw_from"] == "model" and data["forecast_interval"]["p90_j"] > data["forecast_interval"]["mean_j"]
    rc = main([*common, "--battery-ah", "0.01", "--risk", "0.9", "--out", str(tmp_path / "small")])
    assert rc == 1 and "does NOT fit" in capsys.readouterr().out
    rc = main(["mission", "--battery-ah", "5", "--mc-draw", "model", "--monte-carlo", "5", "--out", str(tmp_path / "x")])
    assert rc == 2 and "--mc-draw model" in capsys.readouterr().err
