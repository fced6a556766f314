"""simulate_missions_mc: reproducible whatever the workers, the reserve risk, the draws, its files and ``terrawatt mission --monte-carlo``."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from energy import Battery, PhysicsEnergyModel, TruthSimulator, ground_preset, robot_preset
from planner import (
    EnergyCost,
    MissionDistributions,
    MonteCarloResult,
    plan_route,
    simulate_mission,
    simulate_missions_mc,
)
from planner.missions import MONTE_CARLO_FORMAT_VERSION
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from terrawatt_cli import main
from planner.missions import MissionSample

NOMINAL = Battery(2.0, 24.0)
_NO_DASK = "Monte Carlo on a cluster needs the distributed extra (dask[distributed])"
FIXED = MissionDistributions(ground_coef_scale=(1.0, 1.0), payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0),
                             internal_resistance_ohm=(0.0, 0.0), speed_scale=(1.0, 1.0))


@pytest.fixture(scope="module")
def setup():
    """A 30 m route on a flat asphalt map (a few hundred samples per mission)."""
    import terrain

    tmap = terrain.flat_map((20, 40), 1.0, ground="asphalt")
    cost = EnergyCost.from_presets(tmap)
    route = plan_route(tmap, (3.5, 5.5), (33.5, 14.5), cost=cost, planner="lattice")
    assert route.found
    return tmap, route


def _mc(setup, n=6, battery=NOMINAL, **kw):
    tmap, route = setup
    return simulate_missions_mc(tmap, route, battery, n, **kw)


def test_same_seed_same_missions_and_another_seed_other_missions(setup):
    a, b, c = _mc(setup, seed=4), _mc(setup, seed=4), _mc(setup, seed=5)
    assert np.array_equal(a.energy_j, b.energy_j) and np.array_equal(a.payload_kg, b.payload_kg)
    assert not np.array_equal(a.energy_j, c.energy_j)
    assert a.n == 6 and a.seed == 4 == a.entropy and a.where == "in process"


def test_seed_none_keeps_the_seed_that_repeats_it(setup):
    a = _mc(setup, n=3, seed=None)
    assert a.seed is None and 0 <= a.entropy < 2**32
    assert np.array_equal(_mc(setup, n=3, seed=a.entropy).energy_j, a.energy_j)


def test_a_sample_depends_only_on_its_own_seed(setup):
    """Children of one SeedSequence come in spawn order: a longer study extends a shorter one."""
    six, four = _mc(setup, n=6, seed=9), _mc(setup, n=4, seed=9)
    assert np.array_equal(six.energy_j[:4], four.energy_j)


def test_percentiles_equal_with_one_and_two_workers(setup):
    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    here = _mc(setup, n=10, seed=11)
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        one_per_task = _mc(setup, n=10, seed=11, client=client, chunk_size=1, progress=True)
        chunks = _mc(setup, n=10, seed=11, client=client, chunk_size=4)
    for other in (one_per_task, chunks):
        assert other.energy_percentiles_wh == here.energy_percentiles_wh
        assert np.array_equal(other.energy_j, here.energy_j)
        assert np.array_equal(other.below_reserve, here.below_reserve)
        assert np.array_equal(other.ground_scale, here.ground_scale)
        assert other.n_workers == 2 and other.where == "given client"


def test_fixed_distributions_drive_the_nominal_mission(setup):
    tmap, route = setup
    mc = _mc(setup, n=3, seed=2, distributions=FIXED)
    assert np.all(mc.payload_kg == 0.0) and np.all(mc.capacity_ah == 2.0) and np.all(mc.ground_scale == 1.0)
    # each sample is simulate_mission with the nominal robot, grounds and battery and the sample's truth seed
    rng = np.random.default_rng(np.random.SeedSequence(2).spawn(3)[0])
    FIXED.draw(rng, ["asphalt"], nominal_speed_mps=0.5)
    truth_seed = int(rng.integers(0, 2**32))
    robot = robot_preset("husky")
    truth = TruthSimulator(robot, {"asphalt": ground_preset("asphalt")}, current_rate_hz=20.0, seed=truth_seed)
    one = simulate_mission(tmap, route, robot, Battery(2.0, 24.0), truth, speed_mps=mc.speed_mps[0], seed=truth_seed)
    assert mc.energy_j[0] == one.budget.actual_energy_j
    assert mc.arrival_soc[0] == one.budget.arrival_soc


def test_heavier_payload_costs_more_energy(setup):
    light = _mc(setup, n=3, seed=1, distributions=MissionDistributions(payload_kg=(0.0, 0.0)))
    heavy = _mc(setup, n=3, seed=1, distributions=MissionDistributions(payload_kg=(60.0, 60.0)))
    assert np.all(heavy.energy_j > light.energy_j)


def test_draws_stay_in_their_ranges(setup):
    d = MissionDistributions(ground_coef_scale=(0.5, 0.6), payload_kg=(5.0, 7.0), capacity_fade_pct=(10.0, 30.0),
                             internal_resistance_ohm=(0.2, 0.3), speed_scale=(0.8, 0.9))
    mc = _mc(setup, n=8, seed=3, distributions=d)
    assert np.all((mc.ground_scale >= 0.5) & (mc.ground_scale <= 0.6))
    assert np.all((mc.payload_kg >= 5.0) & (mc.payload_kg <= 7.0))
    assert np.all((mc.capacity_ah >= 2.0 * 0.7) & (mc.capacity_ah <= 2.0 * 0.9))
    assert np.all((mc.internal_resistance_ohm >= 0.2) & (mc.internal_resistance_ohm <= 0.3))
    assert np.all((mc.speed_mps >= 0.4) & (mc.speed_mps <= 0.45))


def test_sample_applies_its_draw_to_robot_grounds_and_battery():
    s = MissionSample({"sand": 2.0}, payload_kg=10.0, capacity_fade_pct=25.0, internal_resistance_ohm=0.1,
                      speed_mps=0.4)
    robot = robot_preset("husky")
    assert s.robot(robot).mass_kg == robot.mass_kg + 10.0
    g = s.grounds({"sand": ground_preset("sand"), "asphalt": ground_preset("asphalt")})
    assert g["sand"].rolling_resistance_coef == 2.0 * ground_preset("sand").rolling_resistance_coef
    assert g["sand"].coulomb_friction_coef == 2.0 * ground_preset("sand").coulomb_friction_coef
    assert g["asphalt"] == ground_preset("asphalt")
    b = s.battery(Battery(4.0, 24.0, internal_resistance_ohm=0.5))
    assert b.capacity_ah == 3.0 and b.internal_resistance_ohm == 0.1


def test_the_reserve_risk_follows_the_battery(setup):
    small = _mc(setup, n=6, seed=1, battery=Battery(0.05, 24.0))
    large = _mc(setup, n=6, seed=1, battery=Battery(50.0, 24.0))
    assert small.p_below_reserve == 1.0 and large.p_below_reserve == 0.0
    assert np.all(small.min_soc < 0.2) and np.all(large.min_soc >= 0.2)
    assert np.array_equal(small.below_reserve, small.min_soc < small.battery.reserve_soc)
    lo, hi = large.p_below_reserve_ci95
    assert lo == 0.0 and 0.0 < hi < 0.5  # Wilson: 0 of 6 still leaves room
    assert np.all(np.diff([large.energy_percentile_j(q) for q in (50, 90, 99)]) >= 0)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"n": 0}, InvalidParameterError, "n must be >= 1, got 0"),
        ({"n": -3}, InvalidParameterError, "n must be >= 1"),
        ({"n": 2.5}, InvalidParameterError, "n must be an integer"),
        ({"seed": 2**32}, InvalidParameterError, "seed must be None or an integer"),
        ({"chunk_size": 0}, InvalidParameterError, "chunk_size must be >= 1"),
        ({"current_rate_hz": 0.0}, InvalidParameterError, "current_rate_hz must be > 0"),
        ({"speed_mps": -0.5}, InvalidParameterError, "speed_mps must be > 0"),
        ({"battery": "2 Ah"}, InvalidParameterError, "battery must be a Battery"),
        ({"robot": 3}, InvalidParameterError, "robot must be a RobotParams or a preset name"),
        ({"robot": "rover9"}, UnknownNameError, "rover9"),
        ({"grounds": {"sand": ground_preset("sand")}}, UnknownNameError, r"grounds lacks the map's ground\(s\) \['asphalt'\]"),
        ({"distributions": {"payload_kg": (0, 1)}}, InvalidParameterError, "distributions must be a MissionDistributions"),
        ({"client": "tcp://127.0.0.1:8786"}, InvalidParameterError, r"client must be None .* distributed\.Client"),
        ({"workers": 0}, InvalidParameterError, "workers must be >= 1"),
    ],
)
def test_bad_arguments_are_refused(setup, kwargs, error, match):
    args = {"n": 2, "battery": Battery(2.0, 24.0), **kwargs}
    with pytest.raises(error, match=match):
        _mc(setup, **args)


def test_a_route_that_was_not_found_is_refused(setup):
    tmap, route = setup
    with pytest.raises(InvalidParameterError, match="route must be a found Route, got \"status 'infeasible'\""):
        simulate_missions_mc(tmap, route.replace(status="infeasible", waypoints_m=np.empty((0, 2)),
                                                 segment_energy_j=np.empty(0), turn_energy_j=np.empty(0),
                                                 energy_j=np.nan, length_m=np.nan, duration_s=np.nan), Battery(2, 24), 2)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"payload_kg": (5.0, 1.0)}, r"payload_kg must have low <= high"),
        ({"payload_kg": (-1.0, 1.0)}, r"payload_kg\[0\] must be >= 0"),
        ({"capacity_fade_pct": (0.0, 100.0)}, r"capacity_fade_pct\[1\] must be <= 99"),
        ({"ground_coef_scale": (0.0, 1.0)}, r"ground_coef_scale\[0\] must be > 0"),
        ({"speed_scale": (1.0,)}, r"speed_scale must be a \(low, high\) pair"),
        ({"internal_resistance_ohm": (0.0, float("nan"))}, r"internal_resistance_ohm\[1\] must be finite"),
    ],
)
def test_bad_distributions_are_refused(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        MissionDistributions(**kwargs)


def test_the_result_writes_its_table_json_and_figure(setup, tmp_path):
    mc = _mc(setup, n=5, seed=7, battery=Battery(0.12, 24.0))
    mc.to_csv(tmp_path / "mc.csv")
    mc.write_json(tmp_path / "mc.json")
    png = mc.plot(tmp_path / "mc.png")
    with open(tmp_path / "mc.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 5 and float(rows[2]["energy_j"]) == mc.energy_j[2]
    assert rows[0]["below_reserve"] in ("true", "false") and "ground_scale_asphalt" in rows[0]
    data = json.loads((tmp_path / "mc.json").read_text())
    assert data["format_version"] == MONTE_CARLO_FORMAT_VERSION and data["n"] == 5 and data["seed"] == 7
    assert data["energy_wh"]["p90"] == pytest.approx(mc.energy_percentiles_wh["p90"])
    assert data["p_below_reserve"] == mc.p_below_reserve and len(data["samples"]["energy_j"]) == 5
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "file").write_text("x")
    with pytest.raises(InvalidParameterError, match="which is a file"):
        mc.plot(tmp_path / "file" / "mc.png")
    assert "5 missions (seed 7)" in mc.summary() and "P90" in mc.summary()


def test_the_figure_draws_into_the_callers_axes_and_writes_nothing(setup, tmp_path):
    from matplotlib.figure import Figure

    mc = _mc(setup, n=5, seed=7, battery=Battery(0.12, 24.0))
    fig = Figure()
    hist, exceed = fig.subplots(1, 2)
    assert mc.plot(axes=[hist, exceed], title="study") == (hist, exceed)
    assert hist.patches and hist.get_xlabel() == "mission energy (Wh)" and hist.get_title() == "study"
    assert any(t.get_text().startswith("P90 ") for t in hist.get_legend().get_texts())
    assert len(exceed.lines) >= 5 and exceed.get_ylabel() == "P(energy > x)" and exceed.get_yscale() == "log"
    assert fig.get_suptitle() == ""
    with pytest.raises(InvalidParameterError, match="got neither"):
        mc.plot()
    with pytest.raises(InvalidParameterError, match="not both"):
        mc.plot(tmp_path / "mc.png", axes=[hist, exceed])
    with pytest.raises(InvalidParameterError, match=r"2 matplotlib Axes \(histogram, exceedance curve\), got 1"):
        mc.plot(axes=[hist])
    assert list(tmp_path.iterdir()) == []


def test_a_result_checks_its_columns():
    ok = {c: np.ones(2) for c in ("payload_kg", "capacity_ah", "internal_resistance_ohm", "speed_mps", "energy_j",
                                  "charge_mah", "duration_s", "arrival_soc", "min_soc")}
    common = dict(seed=0, entropy=0, distributions=FIXED, battery=Battery(1, 24), predicted_energy_j=1.0,
                  ground_names=("a",), ground_scale=np.ones((2, 1)), below_reserve=np.zeros(2, bool),
                  depleted=np.zeros(2, bool))
    assert MonteCarloResult(**common, **ok).n == 2
    with pytest.raises(InvalidParameterError, match=r"speed_mps must have shape \(2,\)"):
        MonteCarloResult(**common, **{**ok, "speed_mps": np.ones(3)})
    with pytest.raises(InvalidParameterError, match="below_reserve must be a bool array"):
        MonteCarloResult(**{**common, "below_reserve": np.zeros(2)}, **ok)


# ------------------------------------------------------------------ terrawatt mission --monte-carlo
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


def test_workers_open_a_local_cluster_through_the_seam(setup, monkeypatch):
    import contextlib

    import planner.missions.monte_carlo as mc_module

    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    calls = []
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:

        @contextlib.contextmanager
        def fake_dask_client(workers, scheduler):
            calls.append((workers, scheduler))
            yield client

        monkeypatch.setattr(mc_module, "dask_client", fake_dask_client)
        mc = _mc(setup, n=3, seed=1, workers=2)
    assert calls == [(2, None)] and mc.where == "local cluster" and mc.n_workers == 2
    assert np.array_equal(mc.energy_j, _mc(setup, n=3, seed=1).energy_j)


def test_a_ground_the_truth_simulator_cannot_drive_is_refused_before_any_mission():
    import terrain

    tmap = terrain.flat_map((10, 20), 1.0, ground="mud")
    cost = EnergyCost.from_model(tmap, PhysicsEnergyModel(robot_preset("husky")), {"mud": ground_preset("sand")}, 0.5)
    route = plan_route(tmap, (2.5, 2.5), (17.5, 7.5), cost=cost, planner="lattice")
    mud = {"mud": ground_preset("sand").replace(name="mud")}
    with pytest.raises(UnknownNameError, match=r"no vibration signature for ground\(s\) \['mud'\]"):
        simulate_missions_mc(tmap, route, NOMINAL, 3, grounds=mud)
    with pytest.raises(UnknownNameError, match=r"the map's grounds \['mud'\] have no preset"):
        simulate_missions_mc(tmap, route, NOMINAL, 3)


def test_with_the_planning_cost_the_forecast_prices_the_driven_profile(setup):
    # Without the cost the study compares with the route's edge energy (steady driving and turns
    # in place); with it, with the physics forecast of the whole stop-turn-go profile, which is
    # dearer and lies within the drawn missions' spread around nominal parameters.
    tmap, route = setup
    cost = EnergyCost.from_presets(tmap)
    edges = _mc(setup, n=8, seed=3)
    profile = _mc(setup, n=8, seed=3, cost=cost)
    assert edges.predicted_energy_j == route.energy_j
    assert profile.predicted_energy_j > route.energy_j
    np.testing.assert_array_equal(profile.energy_j, edges.energy_j)  # the same missions
    p50 = float(np.median(profile.energy_j))
    assert abs(profile.predicted_energy_j - p50) < abs(edges.predicted_energy_j - p50)
    assert "forecast" in profile.summary()


# ------------------------------------------------------------------ per-mission failures
def test_a_failed_mission_is_an_error_row_and_the_others_go_on(setup, tmp_path):
    # a 24 V pack of more than ~1.8 ohm cannot deliver the route's power: those missions fail alone
    d = MissionDistributions(internal_resistance_ohm=(0.0, 4.0))
    mc = _mc(setup, n=8, seed=1, distributions=d)
    failed = mc.failed
    assert 0 < mc.n_failed < mc.n and mc.n_failed == int(failed.sum())
    assert all("InvalidParameterError: power_w" in e and "maximum deliverable power" in e
               for e in np.asarray(mc.errors)[failed])
    assert not any(np.asarray(mc.errors)[~failed])
    assert np.all(np.isnan(mc.energy_j[failed])) and np.all(np.isfinite(mc.energy_j[~failed]))
    assert not mc.below_reserve[failed].any() and not mc.depleted[failed].any()
    # the failed missions kept their drawn parameters; the failures are the high-resistance draws
    assert np.all(mc.internal_resistance_ohm[failed] > mc.internal_resistance_ohm[~failed].max())
    # statistics over the completed missions
    assert mc.energy_percentile_j(50) == pytest.approx(np.percentile(mc.energy_j[~failed], 50))
    assert mc.p_below_reserve == pytest.approx(np.mean(mc.below_reserve[~failed]))
    assert f"{mc.n_failed} of 8 missions failed" in mc.summary()
    data = mc.to_dict()
    assert data["n_failed"] == mc.n_failed and data["samples"]["error"] == list(mc.errors)
    with open(mc.to_csv(tmp_path / "mc.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    assert [bool(r["error"]) for r in rows] == failed.tolist()
    assert mc.plot(tmp_path / "mc.png").is_file()  # drawn from the completed missions
    # the same rows in the same study, whatever the draws' outcome
    assert np.array_equal(_mc(setup, n=8, seed=1, distributions=d).failed, failed)


def test_a_study_where_every_mission_fails_reports_nan_statistics(setup):
    mc = _mc(setup, n=3, seed=1, distributions=MissionDistributions(internal_resistance_ohm=(500.0, 1000.0)))
    assert mc.n_failed == 3 and np.isnan(mc.p_below_reserve) and np.isnan(mc.energy_percentile_j(90))
    assert np.isnan(mc.p_below_reserve_ci95[0]) and "3 of 3 missions failed" in mc.summary()
    with pytest.raises(InvalidParameterError, match="all 3 missions failed"):
        mc.plot("unused.png")


def test_a_result_needs_error_text_exactly_for_missing_outcomes():
    ok = {c: np.ones(2) for c in ("payload_kg", "capacity_ah", "internal_resistance_ohm", "speed_mps", "energy_j",
                                  "charge_mah", "duration_s", "arrival_soc", "min_soc")}
    common = dict(seed=0, entropy=0, distributions=FIXED, battery=Battery(1, 24), predicted_energy_j=1.0,
                  ground_names=("a",), ground_scale=np.ones((2, 1)), below_reserve=np.zeros(2, bool),
                  depleted=np.zeros(2, bool))
    with pytest.raises(InvalidParameterError, match="error text exactly when its energy_j is not finite"):
        MonteCarloResult(**common, **ok, errors=("", "DataError: x"))
    with pytest.raises(InvalidParameterError, match="errors must be 2 strings"):
        MonteCarloResult(**common, **ok, errors=("",))


def test_cli_monte_carlo_with_failed_missions_writes_their_rows_and_exits_1(tmp_path, capsys):
    # a 2 V pack delivers at most 1/R W: the missions that draw a resistance above a few mohm fail
    rc = main(["mission", "--battery-ah", "50", "--battery-v", "2", "--monte-carlo", "4", "--seed", "3",
               "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert rc == 1 and "missions failed" in out and "maximum deliverable power" in out
    data = json.loads((tmp_path / "o" / "monte_carlo.json").read_text())
    assert data["n_failed"] >= 1 and len(data["samples"]["error"]) == 4
