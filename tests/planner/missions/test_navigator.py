"""Tests of planner.missions.navigator: the ride-along loop fed chunk by chunk, its decisions, its state on disk."""

import math
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from energy import Battery, LinearCurrentModel, TruthSimulator, excitation_commands, ground_preset, robot_preset
from planner import AdaptiveSettings, Navigator, run_adaptive_mission
from planner.missions import MissionDrive, MissionGoal, NavigatorModels, ReplayFeed
from planner.missions.legs import split_polyline
from planner.missions.replay import replay_drive
from planner.missions.simulate import simulate_mission
from planner.registry import CellModelRegistry
from planner.route import evaluate_route
from terrain import DataError, InvalidParameterError, OutOfBoundsError, TerrainMap, UnitError

SETTINGS = AdaptiveSettings(leg_length_m=8.0, seed=0, max_updates=2)
ASPHALT = NavigatorModels(physics_ground=ground_preset("asphalt"))
GOAL = (37.5, 8.0)
START = (2.5, 8.0)


def _world(seed: int = 0):
    robot = robot_preset("husky")
    grounds = {"asphalt": ground_preset("asphalt"), "sand": ground_preset("sand")}
    truth = TruthSimulator(robot, grounds, seed=seed)
    ground = np.zeros((16, 40), int)
    ground[4:12, 12:34] = 1
    tmap = TerrainMap(np.zeros((16, 40)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})
    a = excitation_commands(20.0, speed_levels_mps=(0.2, 0.5, 0.8), omega_levels_radps=(0.0,), rest_s=0.0, seed=1)
    b = excitation_commands(8.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
                            hold_s=(2.0, 3.0), rest_s=0.0, seed=2)
    prior = LinearCurrentModel().fit([truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt",
                                                              seed=3 + i) for i, p in enumerate((a, b))])
    return robot, truth, tmap, prior


def _navigator(settings=SETTINGS, **kw):
    robot, truth, tmap, prior = _world()
    nav = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0), GOAL,
                    settings=settings, models=ASPHALT, **kw)
    return nav, truth, tmap


def _drive_leg(nav, truth, tmap, seed):
    """The navigator's next leg driven in the simulator, on the robot's clock."""
    head, _ = split_polyline(np.asarray(nav.route.waypoints_m), nav.settings.leg_length_m)
    leg = evaluate_route(nav.cost, head, status="exact", planner="leg")
    mr = simulate_mission(tmap, leg, nav.robot, nav.battery.replace(initial_soc=nav.soc), truth, nav.cost,
                          drive=MissionDrive(speed_mps=nav.settings.speed_mps, start_heading_rad=nav.heading_rad,
                                             seed=seed))
    return mr.log.shifted(nav.time_s + 0.01 - float(mr.log.time_s[0]))


def _chunks(log, chunk_s):
    t0, t1 = float(log.time_s[0]), float(log.time_s[-1])
    edges = np.append(np.arange(t0, t1, chunk_s), t1 + 1e-6)
    return [log.slice(a, b) for a, b in zip(edges[:-1], edges[1:]) if np.any((log.time_s >= a) & (log.time_s < b))]


# ------------------------------------------------------------------ the loop, fed in chunks
def test_chunks_of_a_leg_give_the_decisions_of_the_whole_leg():
    # A leg fed in 0.5 s chunks with the checkpoint at its end is the leg fed at once.
    whole, truth, tmap = _navigator()
    chunked, _, _ = _navigator()
    whole.plan(START)
    chunked.plan(START)
    for k in range(3):
        log = _drive_leg(whole, truth, tmap, seed=100 + k)
        dw = whole.observe(log, checkpoint=True)
        pieces = _chunks(log, 0.5)
        for piece in pieces[:-1]:
            assert chunked.observe(piece, checkpoint=False).action == "continue"
        dc = chunked.observe(pieces[-1], checkpoint=True)
        assert (dc.action, dc.reason) == (dw.action, dw.reason)
        if dw.action == "manoeuvre":
            break
    assert chunked.soc == pytest.approx(whole.soc, abs=1e-9)  # the control board's start-up priced across chunks
    assert len(chunked.legs) == len(whole.legs) == 3
    for a, b in zip(chunked.legs, whole.legs):
        assert a.actual_energy_j == pytest.approx(b.actual_energy_j, rel=1e-9) and a.n_samples == b.n_samples
    assert np.array_equal(np.asarray(chunked.registry.model_id_map), np.asarray(whole.registry.model_id_map))
    np.testing.assert_allclose(chunked.registry.evidence.measured_charge_c, whole.registry.evidence.measured_charge_c, rtol=1e-12)


def test_checkpoints_come_every_leg_length_driven_without_being_told():
    nav, truth, tmap = _navigator()
    nav.plan(START)
    log = _drive_leg(nav, truth, tmap, seed=7)
    decisions = [nav.observe(piece) for piece in _chunks(log, 0.5)]
    closing = [d for d in decisions if d.checkpoint is not None]
    assert len(closing) == 1 and len(nav.legs) == 1  # one 8 m leg: one checkpoint, by distance
    assert nav.legs[0].actual_energy_j > 0 and nav.decisions[-1]["checkpoint"] == 0


def test_the_sand_patch_is_learned_from_the_driving_alone_and_the_forecast_then_holds():
    # update_source="driven": no manoeuvre is driven (each request is declined); the model of the sand
    # patch is fitted on what the robot drove there, validated on its last quarter, and the forecast of
    # the rest is then close to what the rest costs.
    settings = AdaptiveSettings(leg_length_m=8.0, seed=0, max_updates=2, update_source="driven", min_driven_s=8.0)
    nav, truth, tmap = _navigator(settings)
    d = nav.plan(START)
    forecasts = []
    for k in range(40):
        if nav.finished:
            break
        if d.action == "manoeuvre":
            d = nav.decline_manoeuvre()
            continue
        log = _drive_leg(nav, truth, tmap, seed=200 + k)
        for piece in _chunks(log, 1.0)[:-1]:
            nav.observe(piece, checkpoint=False)
        d = nav.observe(_chunks(log, 1.0)[-1], checkpoint=True)
        forecasts.append((len(nav.legs) - 1, d.forecast))
    assert nav.status == "completed"
    driven = [u for u in nav.updates if u.kind == "driven" and u.accepted]
    assert driven and driven[0].ground == "sand" and driven[0].excitation_energy_j == 0.0
    assert driven[0].validation_error_new < driven[0].validation_error_old
    after = driven[0].after_leg
    fc = dict(forecasts)[after]
    actual = sum(leg.actual_energy_j for leg in nav.legs if leg.index > after)
    assert fc.energy_j == pytest.approx(actual, rel=0.10)


def test_a_drive_without_currents_forecasts_only():
    nav, truth, tmap = _navigator()
    nav.plan(START)
    log = _drive_leg(nav, truth, tmap, seed=9)
    blind = log.__class__(log.time_s, log.v_mps, log.omega_radps, None, None, log.accel_time_s, log.accel_z_mps2,
                          pose_xyh=log.pose_xyh)
    d = nav.observe(blind, checkpoint=True)
    assert d.evidence["mode"].startswith("forecast only") and nav.updates == []
    assert 0.0 < 1.0 - nav.soc  # the models' currents drew the battery
    assert float(np.sum(nav.registry.evidence.sample_count)) == 0.0  # nothing learned


def test_plain_arrays_with_gps_positions_are_placed_through_the_maps_crs():
    robot, truth, _, prior = _world()
    tmap = TerrainMap(np.zeros((16, 40)), 1.0, origin_xy_m=(500_000.0, 5_000_000.0), crs="EPSG:32632")
    nav = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0),
                    (500_037.5, 5_000_008.0), settings=SETTINGS)
    nav.plan((500_002.5, 5_000_008.0))
    x = 500_002.5 + 0.5 * np.arange(20) * 0.1
    lon, lat = tmap.xy_to_lonlat(x, np.full(20, 5_000_008.0))
    d = nav.observe({"time_s": 0.1 + 0.1 * np.arange(20), "lon_deg": lon, "lat_deg": lat,
                     "heading_rad": np.zeros(20), "v_mps": np.full(20, 0.5), "omega_radps": np.zeros(20),
                     "current_left_a": np.full(20, 3.0), "current_right_a": np.full(20, 3.0)})
    assert d.action == "continue"
    np.testing.assert_allclose(nav.position_xy_m, (x[-1], 5_000_008.0), atol=1e-6)


# ------------------------------------------------------------------ decisions
def test_the_rest_that_does_not_fit_turns_back_to_the_depot_when_that_fits():
    # From (20, 8) the goal is 17.5 m away and the depot 5 m: a charge that covers about 10 m turns back.
    robot, _, tmap, prior = _world()
    big = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0), GOAL,
                    settings=SETTINGS)
    per_m = big.plan((20.0, 8.0)).forecast.energy_j / 17.5
    soc = 0.2 + 10.0 * per_m / (1.0 * 24.0 * 3600.0)
    nav = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(1.0, 24.0, initial_soc=soc),
                    MissionGoal(xy_m=GOAL, depot_xy_m=(15.0, 8.0)), settings=SETTINGS)
    d = nav.plan((20.0, 8.0))
    assert d.action == "return" and "the way back to the depot fits" in d.reason
    assert nav.returning and np.allclose(d.route.waypoints_m[-1], (15.0, 8.0))
    assert d.forecast.energy_j < d.forecast.available_j
    far = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(1.0, 24.0, initial_soc=soc),
                    MissionGoal(xy_m=GOAL, depot_xy_m=(2.5, 8.0)), settings=SETTINGS)  # 17.5 m back: does not fit
    assert far.plan((20.0, 8.0)).action == "stop" and far.status == "budget_exceeded"


def test_without_a_depot_the_rest_that_does_not_fit_stops():
    robot, _, tmap, prior = _world()
    nav = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(0.01, 24.0), GOAL,
                    settings=SETTINGS)
    d = nav.plan(START)
    assert d.action == "stop" and nav.status == "budget_exceeded" and "reserve" in d.reason
    with pytest.raises(InvalidParameterError, match="already"):
        nav.plan(START)


def test_a_risk_level_decides_on_the_upper_quantile():
    nav, _, _ = _navigator(AdaptiveSettings(leg_length_m=8.0, seed=0, risk=0.95))
    fc = nav.plan(START).forecast
    assert fc.risk == 0.95 and fc.risk_j > fc.energy_j and fc.low_j < fc.energy_j < fc.high_j


# ------------------------------------------------------------------ bad input: a clear error, nothing kept
def _planned():
    nav, truth, tmap = _navigator()
    nav.plan(START)
    log = _drive_leg(nav, truth, tmap, seed=11)
    return nav, log


@pytest.mark.parametrize("mutate, error, match", [
    (lambda log: log.__class__(log.time_s, log.v_mps, log.omega_radps, log.current_left_a, log.current_right_a,
                               log.accel_time_s, log.accel_z_mps2), DataError, "holds no poses"),
    (lambda log: log.__class__(log.time_s, log.v_mps, log.omega_radps, log.current_left_a, log.current_right_a,
                               log.accel_time_s, log.accel_z_mps2, pose_xyh=log.pose_xyh + [100.0, 0.0, 0.0]),
     OutOfBoundsError, "off the map"),
    (lambda log: log.__class__(log.time_s, log.v_mps, log.omega_radps, 1000.0 * log.current_left_a,
                               1000.0 * log.current_right_a, log.accel_time_s, log.accel_z_mps2,
                               pose_xyh=log.pose_xyh), UnitError, "look like mA"),
    (lambda log: log.shifted(-100.0), DataError, "time went backwards between chunks"),
])
def test_a_refused_chunk_is_named_and_changes_nothing(mutate, error, match):
    nav, log = _planned()
    nav.observe(log.slice(float(log.time_s[0]), float(log.time_s[0]) + 2.0), checkpoint=False)
    before = (nav.soc, nav.time_s, len(nav.segment), nav.n_chunks)
    with pytest.raises(error, match=match):
        nav.observe(mutate(log.slice(float(log.time_s[0]) + 2.0, float(log.time_s[-1]) + 1.0)))
    assert (nav.soc, nav.time_s, len(nav.segment), nav.n_chunks) == before


def test_plain_arrays_are_checked():
    nav, log = _planned()
    ok = {"time_s": log.time_s[:10], "pose_xyh": log.pose_xyh[:10], "v_mps": log.v_mps[:10],
          "omega_radps": log.omega_radps[:10]}
    with pytest.raises(DataError, match="NaN"):
        nav.observe({**ok, "v_mps": np.where(np.arange(10) == 3, np.nan, log.v_mps[:10])})
    with pytest.raises(DataError, match="strictly increasing"):
        nav.observe({**ok, "time_s": log.time_s[:10][::-1]})
    with pytest.raises(InvalidParameterError, match="unknown field"):
        nav.observe({**ok, "speed": 1.0})
    with pytest.raises(InvalidParameterError, match="v_mps is missing"):
        nav.observe({k: v for k, v in ok.items() if k != "v_mps"})
    d = nav.observe(ok)  # no IMU stream: gravity, and the log says so
    assert d.action == "continue" and "standard gravity" in nav.segment[-1].meta.notes


def test_calls_out_of_order_are_refused():
    nav, truth, tmap = _navigator()
    with pytest.raises(InvalidParameterError, match="plan"):
        nav.observe({"time_s": [0.0], "pose_xyh": [[1.0, 1.0, 0.0]], "v_mps": [0.0], "omega_radps": [0.0]})
    with pytest.raises(InvalidParameterError, match="no manoeuvre"):
        nav.decline_manoeuvre()
    with pytest.raises(InvalidParameterError, match="exactly one"):
        Navigator(tmap, nav.registry, nav.robot, nav.battery, MissionGoal(depot_xy_m=(1.0, 1.0)))
    with pytest.raises(InvalidParameterError, match="models must be a NavigatorModels"):
        Navigator(tmap, nav.registry, nav.robot, nav.battery, GOAL, models="asphalt")
    nav.plan(START)
    with pytest.raises(InvalidParameterError, match="plan\\(\\) was already called"):
        run_adaptive_mission(nav, truth, START)  # a navigator follows one mission


# ------------------------------------------------------------------ one loop: the simulated mission replayed
def test_the_simulated_missions_own_logs_replayed_give_its_updates_and_route():
    robot, truth, tmap, prior = _world()
    res = run_adaptive_mission(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0),
                                         GOAL, settings=SETTINGS, models=ASPHALT), truth, START)
    assert res.status == "completed" and res.accepted_updates >= 1
    items = [("drive", log) for log in res.leg_logs] + [("manoeuvre", log) for _, log in res.manoeuvre_logs]
    out = replay_drive(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0), GOAL,
                                 settings=SETTINGS, models=ASPHALT), items)
    nav = out.navigator
    assert nav.status == "completed"
    assert out.summary().splitlines()[:3:2] == ["map: map", "status: completed (reached the goal)"]
    assert [(u.kind, u.ground, u.accepted, u.model_id) for u in nav.updates] == \
        [(u.kind, u.ground, u.accepted, u.model_id) for u in res.updates]
    assert [(p.after_leg, p.route_changed) for p in nav.replans] == [(p.after_leg, p.route_changed) for p in res.replans]
    assert nav.replans[-1].predicted_energy_j == pytest.approx(res.replans[-1].predicted_energy_j, rel=1e-9)
    assert nav.charge.driven_j == pytest.approx(res.driven_energy_j, rel=1e-9)


# ------------------------------------------------------------------ state on disk
def _replay_script(tmp_path, kill_after):
    return textwrap.dedent(f"""
        import os, signal, sys, json
        sys.path.insert(0, {str(os.path.dirname(__file__))!r})
        from test_navigator import _world, SETTINGS, START, GOAL, ASPHALT
        from energy import Battery
        from planner.missions import Navigator, ReplayFeed
        from planner.missions.replay import replay_drive
        from energy.io import read_logs
        from planner.registry import CellModelRegistry
        robot, truth, tmap, prior = _world()
        logs = read_logs({str(tmp_path / "logs")!r})
        seen = []
        def on_decision(d):
            seen.append(d.action)
            if {kill_after} and len(seen) == {kill_after}:
                os.kill(os.getpid(), signal.SIGKILL)
        feed = ReplayFeed(state_path={str(tmp_path / "state")!r}, on_decision=on_decision)
        if feed.resumes:
            nav = Navigator.load(feed.state_path, tmap)
        else:
            nav = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0), GOAL,
                            settings=SETTINGS, models=ASPHALT)
        out = replay_drive(nav, logs, feed=feed)
        print(json.dumps([[d["action"], d["reason"], d["checkpoint"]] for d in out.decisions]))
    """)


def test_a_replay_killed_mid_drive_resumes_and_decides_as_one_that_ran_through(tmp_path):
    from energy.io import write_csv_log

    robot, truth, tmap, prior = _world()
    res = run_adaptive_mission(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0),
                                         GOAL, settings=SETTINGS, models=ASPHALT), truth, START)
    (tmp_path / "logs").mkdir()
    for k, log in enumerate(res.leg_logs):
        write_csv_log(log, tmp_path / "logs" / f"leg_{k:03d}.csv")
    runs: dict[int, int] = {}
    for after, log in res.manoeuvre_logs:
        runs[after] = runs.get(after, -1) + 1
        write_csv_log(log, tmp_path / "logs" / f"manoeuvre_{after:03d}_{runs[after]}.csv")
    env = {**os.environ, "PYTHONPATH": os.getcwd()}
    # killed (SIGKILL) at its third decision that is not "continue", after the state of the checkpoint before
    killed = subprocess.run([sys.executable, "-c", _replay_script(tmp_path, 3)], env=env, capture_output=True,
                            text=True, timeout=300)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert (tmp_path / "state" / "navigator.json").is_file()
    resumed = subprocess.run([sys.executable, "-c", _replay_script(tmp_path, 0)], env=env, capture_output=True,
                             text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    (tmp_path / "state2").mkdir()
    straight = subprocess.run([sys.executable, "-c", _replay_script(tmp_path, 0).replace("/ \"state\"", "")
                               .replace(str(tmp_path / "state"), str(tmp_path / "state2"))], env=env,
                              capture_output=True, text=True, timeout=300)
    assert straight.returncode == 0, straight.stderr
    assert resumed.stdout.strip() == straight.stdout.strip() and len(resumed.stdout) > 10


def test_the_state_round_trips_mid_manoeuvre(tmp_path):
    nav, truth, tmap = _navigator()
    d = nav.plan(START)
    for k in range(10):
        d = nav.observe(_drive_leg(nav, truth, tmap, seed=300 + k), checkpoint=True)
        if d.action == "manoeuvre":
            break
    assert d.action == "manoeuvre"
    nav.save(tmp_path / "nav")
    back = Navigator.load(tmp_path / "nav", tmap)
    assert back.pending_manoeuvre is not None and back.pending_manoeuvre.ground == d.manoeuvre.ground
    assert back.soc == nav.soc and back.time_s == nav.time_s and back.decisions == nav.decisions
    runs = []
    for i, p in enumerate(d.manoeuvre.profiles):
        xl = truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=d.manoeuvre.ground, seed=40 + i)
        start = (runs[-1].time_s[-1] if runs else nav.time_s) + 0.01
        runs.append(xl.shifted(start - float(xl.time_s[0])))
    a, b = nav.observe_manoeuvre(runs), back.observe_manoeuvre(runs)
    assert (a.action, a.reason) == (b.action, b.reason)
    assert [vars(u) | {"wall_time_s": 0} for u in nav.updates] == [vars(u) | {"wall_time_s": 0} for u in back.updates]
    assert np.array_equal(a.route.waypoints_m if a.route is not None else [], b.route.waypoints_m if b.route else [])


def test_a_broken_state_is_a_file_format_error(tmp_path):
    from terrain import FileFormatError

    nav, _, tmap = _navigator()
    nav.plan(START)
    nav.save(tmp_path / "nav")
    (tmp_path / "nav" / "state.npz").write_bytes(b"not a zip")
    with pytest.raises(FileFormatError):
        Navigator.load(tmp_path / "nav", tmap)
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "x.txt").write_text("mine")
    with pytest.raises(InvalidParameterError, match="refusing"):
        nav.save(tmp_path / "other")
    assert (tmp_path / "other" / "x.txt").read_text() == "mine"
    assert math.isfinite(nav.soc)


def test_a_drive_cut_in_chunks_loses_no_sample():
    from energy import InteractionLog
    from planner.missions.replay import drive_chunks

    t = np.arange(300) / 15.0  # 15 Hz drive, 10 Hz IMU: many 0.05 s windows hold no IMU sample
    log = InteractionLog(t, np.full(300, 0.5), np.zeros(300), np.ones(300), np.ones(300), np.arange(200) / 10.0,
                         np.full(200, 9.81), pose_xyh=np.column_stack([t, t, t]))
    for chunk_s, after in ((0.05, -1.0), (1.0, -1.0), (0.05, 3.0)):
        pieces = drive_chunks(log, chunk_s, after)
        joined = np.concatenate([p.time_s for p in pieces])
        np.testing.assert_array_equal(joined, t[t > after])
        assert all(len(p.accel_time_s) for p in pieces)


def test_a_long_drive_is_replayed_in_chunks_with_checkpoints_by_distance():
    from energy import InteractionLog

    robot, truth, tmap, prior = _world()
    res = run_adaptive_mission(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0),
                                         GOAL, settings=SETTINGS, models=ASPHALT), truth, START)
    drive = InteractionLog.concatenate(res.leg_logs)  # one recording: the legs' rests kept, no manoeuvre in it
    out = replay_drive(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0), GOAL,
                                 settings=SETTINGS, models=ASPHALT), [drive], feed=ReplayFeed(chunk_s=0.5))
    nav = out.navigator
    assert out.mode == "drive" and out.chunks > 50 and nav.status == "completed"
    assert len(nav.legs) >= 4 and any(u.accepted for u in nav.updates)  # manoeuvres declined: learned from driving
    assert nav.charge.driven_j == pytest.approx(res.driven_energy_j, rel=0.02)
