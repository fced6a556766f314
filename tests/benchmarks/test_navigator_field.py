"""The Navigator field study (benchmarks/navigator_field.py) on one or two small drives: its own client drives
a truth map whose "grass" band is mud, the navigator must learn it from driven data, the JSON holds the study."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

BENCH_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "navigator_field.py"


def _load():
    name = "navigator_field"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, BENCH_PATH)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # dataclasses look their module up while the class is built
    spec.loader.exec_module(mod)
    return mod


nf = _load()

#: A 60 m map, a straight 24 m band the map calls grass that is mud (rolling resistance x2.5).
MUD = nf.Scenario(index=0, seed=123, size=60, background="gravel", layout="band", centres_m=(30.0,),
                  widths_m=(24.0,), tilt_rad=0.0, wobble_m=0.0, truth_kind="mud", crr_factor=2.5,
                  patch_variation=0.05, start_xy_m=(4.5, 30.5), goal_xy_m=(55.5, 30.5))


@pytest.fixture(scope="module")
def mud_drive():
    return nf.drive(MUD)


def test_the_truth_map_differs_from_the_navigators_map_only_on_the_band():
    w = nf.build_world(MUD)
    nav_g, truth_g = np.asarray(w["nav_map"].ground), np.asarray(w["truth_map"].ground)
    band = w["mask"]
    assert band[:, 20:40].all() and not band[:, :17].any() and not band[:, 43:].any()
    assert w["nav_map"].ground_names == {0: "gravel", 1: "grass"}
    assert np.all(nav_g[band] == 1) and np.all(truth_g[band] == 2) and np.all(truth_g[~band] == 0)
    assert w["truth_map"].ground_names[2] == "mud" and w["patch"].rolling_resistance_coef == pytest.approx(0.25)
    ids = np.asarray(w["registry"].model_id_map)
    assert len(set(ids[band].tolist())) == 1 and set(ids[band].tolist()).isdisjoint(ids[~band].tolist())


def test_the_mud_band_is_flagged_and_learned_from_driven_data(mud_drive):
    d = mud_drive
    assert d["status"] == "completed"
    assert d["flagged_patch"] and not d["flagged_background"]
    driven = [u for u in d["updates"] if u["kind"] == "driven" and u["accepted"]]
    assert driven and d["driven_update"] and d["driven_update_ground"] == "grass"
    up = driven[0]
    assert up["region_error_pct"] < -10.0  # the grass prior under-predicts mud
    assert up["validation_error_new"] < up["validation_error_old"]
    assert up["after_leg"] in d["patch_legs"]  # learned where the robot drove the band
    assert d["update_forecast"] is not None and d["update_forecast"]["checkpoint"] == d["first_update_leg"]


def test_every_checkpoint_is_scored_against_the_energy_then_used(mud_drive):
    d = mud_drive
    cps = d["checkpoints"]
    assert len(cps) >= d["legs"] - 2  # every checkpoint but the arrival (and a declined request's duplicate)
    used = [a for _, a in d["leg_pred_actual"]]
    for c in cps:
        assert c["actual_j"] == pytest.approx(sum(used[c["checkpoint"] + 1:]))
        assert c["low_j"] <= c["forecast_j"] <= c["high_j"]
        assert c["covered"] == (c["low_j"] <= c["actual_j"] <= c["high_j"])
        assert c["bucket"] in nf.BUCKETS and c["phase"] in ("before_update", "after_update")
    assert [c["checkpoint"] for c in cps] == sorted({c["checkpoint"] for c in cps})
    assert d["early_checkpoints"] == 0 and d["client_legs"] == d["legs"]


def test_chunks_cover_the_log_once():
    log = nf.build_world(MUD)["truth"].run_drive(nf.build_world(MUD)["truth_map"],
                                                 np.array([[4.5, 30.5], [12.5, 30.5]]), seed=1).log
    chunks = nf._chunks(log, 0.5)
    assert len(chunks) > 10
    np.testing.assert_array_equal(np.concatenate([c.time_s for c in chunks]), log.time_s)
    assert max(c.duration_s for c in chunks) < 0.76


def test_scenarios_are_seeded():
    assert nf.make_scenario(4, 7) == nf.make_scenario(4, 7)
    assert nf.make_scenario(4, 7) != nf.make_scenario(5, 7)
    kinds = {nf.make_scenario(0, i).truth_kind for i in range(12)}
    assert kinds == set(nf.TRUTH_KINDS)


def test_main_writes_the_study_and_the_same_seed_gives_the_same_numbers(tmp_path, capsys):
    out = tmp_path / "nf.json"
    assert nf.main(["--n", "1", "--quick", "--seed", "3", "--out", str(out)]) == 0
    assert "80 % interval coverage" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert {"config", "summary", "scenarios", "drives", "drives_without_gain", "wall_time_s"} <= set(doc)
    assert doc["config"]["n"] == 1 and doc["config"]["chunk_s"] == 0.5
    s = doc["summary"]
    assert {"with_gain", "without_gain", "leg_ratios", "identical_drives", "by_truth"} <= set(s)
    assert s["identical_drives"] is True  # the gain changes forecasts, never the drive
    for variant in ("with_gain", "without_gain"):
        v = s[variant]
        cov = v["coverage"]["pooled"]
        assert cov["n"] > 0 and 0.0 <= cov["coverage"] <= 1.0
        assert cov["coverage"] + cov["above"] + cov["below"] == pytest.approx(1.0)
        for b in nf.BUCKETS:
            c = v["coverage"]["by_bucket"][b]["coverage"]
            assert c is None or 0.0 <= c <= 1.0
        assert {"n", "median_abs_error_pct", "p90_abs_error_pct", "within_5pct"} <= set(v["update_forecast"])
    again = nf.run(1, 3, quick=True, compare=False)
    assert again["drives"][0]["checkpoints"] == doc["drives"][0]["checkpoints"]
