"""The golden cases: each runs one versioned output through the CLI a user runs, on small seeded inputs."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import shutil
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

import terrain
from planner.cost_spec import CostSpec
from terrawatt_cli import main

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


#: What the commands of the running case printed: ``(argv, stdout)`` per call of :func:`_cli`.
_PRINTED: list[tuple[list[str], str]] = []


def _cli(*argv: object, expect: int = 0) -> None:
    """Run ``terrawatt *argv`` in process, its printout kept for the case's ``stdout.txt`` (stderr, where the
    progress bars go, swallowed); fail on an unexpected exit code."""
    out, err = io.StringIO(), io.StringIO()
    args = [str(a) for a in argv]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(args)
    if rc != expect:
        raise AssertionError(f"terrawatt {' '.join(args)} exited {rc}, expected {expect}:\n"
                             f"{out.getvalue()}\n{err.getvalue()}")
    _PRINTED.append((args, out.getvalue()))


def _with_printout(case: str, run: Callable[[Path], dict[str, Path]]) -> Callable[[Path], dict[str, Path]]:
    """``run``, its outputs joined by ``<case>/stdout.txt``: each command it ran (``$ terrawatt ...``) and what
    that printed, the work folder written ``<work>`` and the test fixtures' ``<fixtures>`` (the same text in every
    checkout; timings are masked when compared, ``golden_files``)."""

    def with_printout(work: Path) -> dict[str, Path]:
        _PRINTED.clear()
        files = run(work)
        if not _PRINTED:  # only the library ran: nothing printed
            return files
        text = "".join(f"$ terrawatt {' '.join(args)}\n{out}\n" for args, out in _PRINTED)
        _PRINTED.clear()
        printout = work / f"{case}.stdout.txt"
        for folder, name in ((work, "<work>"), (FIXTURES, "<fixtures>")):
            text = text.replace(str(folder.resolve()), name).replace(str(folder), name)
        printout.write_text(text, encoding="utf-8")
        return files | {f"{case}/stdout.txt": printout}

    return with_printout


def patch_map(folder: Path) -> Path:
    """60 x 24 m of 1 m cells: a gentle ramp of asphalt, a sand band across the straight line, a short wall."""
    ground = np.zeros((24, 60), dtype=int)
    ground[6:18, 20:40] = 1
    z = np.tile(0.02 * np.arange(60.0), (24, 1))
    obstacle = np.zeros((24, 60), dtype=bool)
    obstacle[0:8, 45] = True
    tmap = terrain.TerrainMap(z, 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"}, obstacle=obstacle)
    return tmap.save(folder / "patch.npz")


def case_map(work: Path) -> dict[str, Path]:
    return {"map/patch.npz": patch_map(work)}


def case_plan(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    out = work / "plan"
    _cli("plan", "--map", path, "--start", 3, 12, "--goal", 57, 12, "--planner", "lattice", "--out", out)
    return {f"plan/{p.name}": p for p in sorted(out.iterdir())}


def case_batch(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    pairs = work / "pairs.csv"
    pairs.write_text("name,start_x_m,start_y_m,goal_x_m,goal_y_m\n"
                     "across,3,12,57,12\nup,10,3,50,20\nback,55,20,5,5\n")
    out = work / "batch"
    _cli("batch", "--map", path, "--pairs", pairs, "--planner", "lattice", "--no-progress", "--out", out)
    return {f"batch/{p.name}": p for p in sorted(out.iterdir())}


def case_reach(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    out = work / "reach"
    _cli("reach", "--map", path, "--depot", 5.5, 5.5, "--battery-ah", 0.05, "--voltage", 24, "--reserve", 10,
         "--round-trip", "--out", out)
    return {f"reach/{p.name}": p for p in sorted(out.iterdir())}


def case_mission(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    out = work / "mission"
    _cli("mission", "--map", path, "--start", 16, 12, "--goal", 30, 12, "--battery-ah", 20, "--speed", 1.0, "--leg-m", 8,
         "--out", out)
    return {f"mission/{p.name}": p for p in sorted(out.iterdir())}


def case_monte_carlo(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    out = work / "monte_carlo"
    _cli("mission", "--map", path, "--start", 3, 12, "--goal", 57, 12, "--battery-ah", 5, "--monte-carlo", 4,
         "--seed", 3, "--out", out)
    return {f"monte_carlo/{p.name}": p for p in sorted(out.iterdir())}


def case_train(work: Path) -> dict[str, Path]:
    files = {}
    for kind in ("linear", "physics"):
        target = work / f"{kind}.zip"
        _cli("train", "--data", FIXTURES / "borealtc", "--model", kind, "--seed", 0, "--out", target)
        files[f"train/{kind}.zip"] = target
    return files


def case_evaluate(work: Path) -> dict[str, Path]:
    data = work / "logs"
    shutil.copytree(FIXTURES / "borealtc", data)
    for kind in ("imu", "pro"):  # a second asphalt run, so leave-one-run-out has something to train on
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    out = work / "evaluate"
    _cli("evaluate", "--data", data, "--model", "constant", "linear", "physics", "--seed", 0, "--out", out)
    return {f"evaluate/{p.name}": p for p in sorted(out.iterdir())}


def case_diagnose(work: Path) -> dict[str, Path]:
    from diagnosis_scenarios import scenario

    from energy import write_csv_log

    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    (work / "logs").mkdir()
    for k, log in enumerate(sc.make_logs(0)):
        write_csv_log(log, work / "logs" / f"run_{k}.csv")
    sc.terrain.save(work / "map.npz")
    out = work / "diagnose"
    _cli("diagnose", "--model", "physics", "--without", "turning_resistance", "--ground", "coated_wood",
         "--data", work / "logs", "--map", work / "map.npz", "--seed", 1, "--quiet", "--out", out)
    return {f"diagnose/{p.name}": p for p in sorted(out.iterdir())}




def case_tour(work: Path) -> dict[str, Path]:
    """Two robots' tours of five sites (one on the wall: an error row, exit 1), the solver stopped by no improvement."""
    path = patch_map(work)
    sites = work / "sites.csv"
    sites.write_text("name,x_m,y_m,value\npump,10.5,20.5,2\ngate,30.5,3.5,1\nshed,55.5,20.5,3\n"
                     "well,50.5,5.5,1\nrock,45.5,3.5,5\n")
    out = work / "tour"
    _cli("tour", "--map", path, "--sites", sites, "--depot", 3.5, 12.5, "--battery-ah", 0.14, "--voltage", 24,
         "--robots", 2, "--risk", 0.9, "--out", out, expect=1)
    return {f"tour/{p.name}": p for p in sorted(out.iterdir())}


def _tour_with_a_charger(work: Path, name: str, *extra: object) -> Path:
    """One robot's tour of three sites with a charger (``tour`` with ``extra`` flags) into ``work / name``."""
    path = patch_map(work)
    sites = work / "sites.csv"
    sites.write_text("name,x_m,y_m,value\npump,10.5,20.5,2\nshed,55.5,20.5,3\nwell,50.5,5.5,1\n")
    chargers = work / "chargers.csv"
    chargers.write_text("name,x_m,y_m,power_w,connection_time_s,max_visits\ndock,36.5,21.5,60,15,2\n")
    out = work / name
    _cli("tour", "--map", path, "--sites", sites, "--chargers", chargers, "--depot", 3.5, 12.5, "--battery-ah", 0.08,
         "--voltage", 24, "--risk", 0.9, "--time-limit", 1, *extra, "--out", out)
    return out


def case_tour_chargers(work: Path) -> dict[str, Path]:
    """One robot's tour of three sites with a charger: the far shed visited after a charge (OR-Tools)."""
    out = _tour_with_a_charger(work, "tour_chargers")
    return {f"tour_chargers/{p.name}": p for p in sorted(out.iterdir())}


def case_tour_check(work: Path) -> dict[str, Path]:
    """The tour of ``tour_chargers`` driven 8 times (``--monte-carlo 8``): the share above the reserve at each stop."""
    out = _tour_with_a_charger(work, "tour_check", "--monte-carlo", 8)
    return {f"tour_check/{name}": out / name for name in ("tour_check.json", "tour_check.png")}


def case_tour_windows(work: Path) -> dict[str, Path]:
    """One robot's tour of four sites with service energy and time, two time windows and a duration limit."""
    path = patch_map(work)
    sites = work / "sites.csv"
    sites.write_text("name,x_m,y_m,value,service_energy_j,service_time_s,tw_start_s,tw_end_s\n"
                     "pump,10.5,20.5,2,50,5,,\ngate,30.5,3.5,1,0,0,100,400\nshed,55.5,20.5,3,80,10,0,300\n"
                     "well,50.5,5.5,1,20,3,,\n")
    out = work / "tour_windows"
    _cli("tour", "--map", path, "--sites", sites, "--depot", 3.5, 12.5, "--battery-ah", 0.2, "--voltage", 24,
         "--max-duration", 600, "--risk", 0.9, "--time-limit", 1, "--out", out)
    return {f"tour_windows/{p.name}": p for p in sorted(out.iterdir())}


def case_plan_exports(work: Path) -> dict[str, Path]:
    """The route and map for ROS 2 / Nav2 (needs the ros and geo extras: rosbags, rasterio)."""
    path = patch_map(work)
    out = work / "plan_exports"
    _cli("plan", "--map", path, "--start", 3, 12, "--goal", 57, 12, "--planner", "lattice", "--ros2-out",
         out / "route.mcap", "--nav2-map", out / "nav2" / "", "--energy-costmap", out / "energy.tif",
         "--map-frame-origin", 2, 1, "--out", out)
    return {f"plan_exports/{p.name}": p for p in sorted(out.iterdir()) if p.name not in ("route.json", "route.geojson",
                                                                                      "route.png")}


def case_plan_coarse(work: Path) -> dict[str, Path]:
    """Coarse-to-fine (the route.json of another door): the lattice on a map 4 times coarser, then a corridor."""
    path = patch_map(work)
    out = work / "plan_coarse"
    _cli("plan", "--map", path, "--start", 3, 12, "--goal", 57, 12, "--coarse-factor", 4, "--out", out)
    return {f"plan_coarse/{p.name}": p for p in sorted(out.iterdir())}


def _simulated_runs(folder: Path) -> None:
    """Two simulated 25 s runs on asphalt and two on sand, as CSV logs in one folder per ground."""
    from energy import TruthSimulator, excitation_commands, ground_preset, robot_preset, write_csv_log

    truth = TruthSimulator(robot_preset("husky"), {g: ground_preset(g) for g in ("asphalt", "sand")}, seed=0)
    for g, ground in enumerate(("asphalt", "sand")):
        (folder / ground.upper()).mkdir(parents=True)
        for k in range(2):
            p = excitation_commands(25.0, seed=10 * g + k)
            log = truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=ground, seed=100 + 10 * g + k)
            write_csv_log(log, folder / ground.upper() / f"run_{k}.csv")


def case_evaluate_adapt(work: Path) -> dict[str, Path]:
    """The adapt protocol on simulated 25 s runs (the BorealTC fixture's runs are too short to adapt on)."""
    _simulated_runs(work / "logs")
    out = work / "evaluate_adapt"
    _cli("evaluate", "--data", work / "logs", "--model", "linear", "--protocol", "adapt", "--adapt-seconds", 10,
         "--seed", 0, "--out", out)
    return {f"evaluate_adapt/{p.name}": p for p in sorted(out.iterdir())}


def case_evaluate_few_shot(work: Path) -> dict[str, Path]:
    """The few-shot protocol on the adapt case's simulated runs: train on one ground, adapt on 10 s of a run of the other."""
    _simulated_runs(work / "logs")
    out = work / "evaluate_few_shot"
    _cli("evaluate", "--data", work / "logs", "--model", "linear", "--protocol", "few-shot", "--adapt-seconds", 10,
         "--seed", 0, "--out", out)
    return {f"evaluate_few_shot/{p.name}": p for p in sorted(out.iterdir())}


def case_predict_unscored(work: Path) -> dict[str, Path]:
    """``predict`` on a log without measured currents: a ``terrawatt-predictions`` document, not scores."""
    from energy import TruthSimulator, excitation_commands, ground_preset, robot_preset, write_csv_log

    model = work / "linear.zip"
    _cli("train", "--data", FIXTURES / "borealtc", "--model", "linear", "--seed", 0, "--out", model)
    truth = TruthSimulator(robot_preset("husky"), {"asphalt": ground_preset("asphalt")}, seed=0)
    p = excitation_commands(6.0, seed=1)
    log = truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt", seed=5)
    (work / "logs").mkdir()
    write_csv_log(dataclasses.replace(log, current_left_a=None, current_right_a=None), work / "logs" / "run.csv")
    out = work / "predict_unscored"
    with contextlib.chdir(work):
        _cli("predict", "--model", model.name, "--data", "logs", "--out", out)
    return {f"predict_unscored/{p.name}": p for p in sorted(out.iterdir()) if p.is_file()}


def case_library(work: Path) -> dict[str, Path]:
    """The versioned files only the library writes: a robot file, a simulated mission's ``MissionResult``."""
    from energy import Battery, TruthSimulator, ground_preset, robot_preset
    from energy.params import write_robot_file
    from planner import plan_route, simulate_mission
    from planner.missions import MissionDrive

    tmap = terrain.read_map(patch_map(work))
    husky = robot_preset("husky")
    cost = CostSpec(robot=husky, speed_mps=0.5).build(tmap)
    route = plan_route(tmap, (3.0, 12.0), (57.0, 12.0), cost=cost, planner="lattice")
    truth = TruthSimulator(husky, {g: ground_preset(g) for g in ("asphalt", "sand")}, seed=0)
    mission = simulate_mission(tmap, route, husky, Battery(20.0, husky.battery_voltage_v), truth, cost,
                               drive=MissionDrive(seed=1))
    return {"library/husky.json": write_robot_file(husky, work / "husky.json"),
            "library/mission.json": mission.write(work / "library", series_every=200)[0]}


def case_plan_model(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    model = work / "linear.zip"
    _cli("train", "--data", FIXTURES / "borealtc", "--model", "linear", "--seed", 0, "--out", model)
    out = work / "plan_model"
    _cli("plan", "--map", path, "--start", 3, 12, "--goal", 57, 12, "--planner", "lattice", "--model", model,
         "--model-ground", "sand=snow", "--risk", 0.9, "--out", out)
    return {f"plan_model/{p.name}": p for p in sorted(out.iterdir())}


def case_predict(work: Path) -> dict[str, Path]:
    model = work / "linear.zip"
    _cli("train", "--data", FIXTURES / "borealtc", "--model", "linear", "--seed", 0, "--out", model)
    out = work / "predict"
    with contextlib.chdir(work):  # predictions.json records --model as given: a relative path, the same in every run
        _cli("predict", "--model", model.name, "--data", FIXTURES / "borealtc", "--out", out)
    return {f"predict/{p.name}": p for p in sorted(out.iterdir()) if p.is_file()}


def case_diagnose_power(work: Path) -> dict[str, Path]:
    from diagnosis_scenarios import scenario

    from energy import write_csv_log

    sc = dataclasses.replace(scenario("control"), n_runs=3, run_duration_s=8.0)
    (work / "logs").mkdir()
    for k, log in enumerate(sc.make_logs(0)):
        write_csv_log(log, work / "logs" / f"run_{k}.csv")
    out = work / "diagnose_power"
    _cli("diagnose", "--model", "physics", "--ground", "coated_wood", "--data", work / "logs", "--seed", 1, "--quiet",
         "--effects", "idle_current", "sensor", "control", "--out", out)
    return {f"diagnose_power/{p.name}": p for p in sorted(out.iterdir())}


def case_diagnose_ties(work: Path) -> dict[str, Path]:
    """The library's diagnosis where the runs cannot settle the chosen effect (a tie) and the drive that separates
    it: straights at constant speed read by a current sensor 30 % high, three candidates."""
    from energy import PhysicsCurrentModel, TruthSimulator, ground_preset, robot_preset
    from energy.diagnosis import diagnose

    sim = TruthSimulator(robot_preset("husky"), {"asphalt": ground_preset("asphalt")}, seed=0)
    t = np.arange(0.0, 30.0, 0.05)
    logs = []
    for k in range(4):
        log = sim.simulate_commands(t, np.full(t.size, 0.5 + 0.1 * k), np.zeros(t.size), ground="asphalt", seed=k)
        logs.append(dataclasses.replace(log, current_left_a=1.3 * log.current_left_a,
                                        current_right_a=1.3 * log.current_right_a))
    model = PhysicsCurrentModel("husky", "asphalt", fit_parameters=()).fit(logs[:1])
    d = diagnose(model, logs, effects=["current_gain", "current_offset", "mass"])
    return _diagnosis_files(d, work / "diagnose_ties", "diagnose_ties")


def case_diagnose_learned(work: Path) -> dict[str, Path]:
    """The library's diagnosis where no catalogued effect is significant: the learned correction scored and noted
    (never added unless named), how many more runs the likeliest candidate needs."""
    from diagnosis_scenarios import null_scenario

    from energy.diagnosis import FitSettings, diagnose

    sc = dataclasses.replace(null_scenario(), n_runs=4, run_duration_s=12.0)
    logs = []
    for log in sc.make_logs(seed=0):  # 3 A per m/s x rad/s less than the model in arcs: no catalogued law's shape
        dip = 3.0 * np.abs(log.v_mps * log.omega_radps)
        logs.append(dataclasses.replace(log, current_left_a=np.maximum(log.current_left_a - dip, 0.0),
                                        current_right_a=np.maximum(log.current_right_a - dip, 0.0)))
    d = diagnose(sc.make_model(seed=0), logs, settings=FitSettings(seed=0, n_bootstrap=50))
    return _diagnosis_files(d, work / "diagnose_learned", "diagnose_learned")


def _diagnosis_files(diagnosis: object, out: Path, case: str) -> dict[str, Path]:
    """A diagnosis' JSON and markdown (its figures and model file are compared in the CLI cases), and its summary."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        written = diagnosis.write(out)
    (out / "summary.txt").write_text(diagnosis.summary(), encoding="utf-8")
    keep = ("diagnosis.json", "diagnosis.md", "summary.txt")
    return {f"{case}/{p.name}": p for p in [*written, out / "summary.txt"] if p.name in keep}


def case_replay(work: Path) -> dict[str, Path]:
    path = patch_map(work)
    mission = work / "mission"
    _cli("mission", "--map", path, "--start", 16, 12, "--goal", 30, 12, "--battery-ah", 20, "--speed", 1.0,
         "--leg-m", 8, "--logs", "--out", mission)
    out = work / "replay"
    with contextlib.chdir(work):  # the navigator's state records the logs' paths as given: relative, the same in every run
        _cli("replay", "--data", "mission/logs", "--map", path.name, "--registry", "mission/start_registry",
             "--goal", 30, 12, "--battery-ah", 20, "--speed", 1.0, "--no-mcap", "--state", "state", "--out", "replay")
    files = {f"replay/logs/{p.name}": p for p in sorted((mission / "logs").iterdir())}
    files |= {f"replay/start_registry/{p.name}": p for p in sorted((mission / "start_registry").iterdir())}
    files |= {f"replay/state/{p.name}": p for p in sorted((work / "state").iterdir())}
    return files | {f"replay/{p.name}": p for p in sorted(out.iterdir())}


def case_mission_variants(work: Path) -> dict[str, Path]:
    """The mission paths the other cases do not take: a Monte Carlo study drawn from a model's predictive
    distribution, a replay of a drive in chunks, and ``simulate_mission`` replaying a log against a small battery
    (edge forecast, stopped at the reserve, no sensor offset)."""
    from energy import Battery, TruthSimulator, ground_preset, robot_preset
    from planner import plan_route, simulate_mission
    from planner.missions import MissionAccounting, MissionDrive

    path = patch_map(work)
    model = work / "linear.zip"
    _cli("train", "--data", FIXTURES / "borealtc", "--model", "linear", "--seed", 0, "--out", model)
    mc = work / "mc_model"
    _cli("mission", "--map", path, "--start", 3, 12, "--goal", 57, 12, "--battery-ah", 5, "--monte-carlo", 6,
         "--mc-draw", "model", "--model", model, "--model-ground", "sand=snow", "--seed", 2, "--out", mc)
    mission = work / "mission"
    _cli("mission", "--map", path, "--start", 16, 12, "--goal", 30, 12, "--battery-ah", 20, "--speed", 1.0,
         "--leg-m", 8, "--logs", "--out", mission)
    replay = work / "replay_chunks"
    with contextlib.chdir(work):
        _cli("replay", "--data", "mission/logs", "--map", path.name, "--registry", "mission/start_registry",
             "--goal", 30, 12, "--battery-ah", 20, "--speed", 1.0, "--mode", "drive", "--chunk-s", 2.5, "--no-mcap",
             "--out", "replay_chunks")
    tmap = terrain.read_map(path)
    husky = robot_preset("husky")
    cost = CostSpec(robot=husky, speed_mps=0.5).build(tmap)
    route = plan_route(tmap, (3.0, 12.0), (57.0, 12.0), cost=cost, planner="lattice")
    truth = TruthSimulator(husky, {g: ground_preset(g) for g in ("asphalt", "sand")}, seed=0)
    driven = simulate_mission(tmap, route, husky, Battery(20.0, husky.battery_voltage_v), truth, cost,
                              drive=MissionDrive(seed=4))
    small = Battery(0.04, husky.battery_voltage_v, min_reserve_pct=30.0)
    replayed = simulate_mission(tmap, route, husky, small, driven.log, cost,
                                accounting=MissionAccounting(forecast="edges", current_offset_a=0.0),
                                drive=MissionDrive(stop_at_reserve=True, speed_mps=0.5, accel_mps2=0.8))
    files = {f"mission_variants/mc_model/{p.name}": p for p in sorted(mc.iterdir())}
    files |= {f"mission_variants/replay_chunks/{p.name}": p for p in sorted(replay.iterdir())}
    return files | {"mission_variants/replayed.json": replayed.write(work / "replayed", series_every=50)[0]}


#: Outputs compared by digest rather than in full (``fnmatch`` patterns of golden paths): the replay's inputs
#: and saved state hold seconds of samples (the CSV logs' format shows in a digest's first lines).
DIGESTED = ("replay/logs/*", "replay/state/state.npz/*", "replay/*/registry.npz/*charge_c.npy",
            "replay/*/registry.npz/sample_count.npy")

#: The optional packages a case needs (the extras a user installs for those outputs): skipped without them.
NEEDS = {"plan_exports": ("rasterio", "rosbags")}

#: Each case by name: a function of an empty work folder returning its outputs, ``{"<case>/<name>": path}``.
#: Each runs through :func:`_with_printout`: what its commands print is an output too (``<case>/stdout.txt``).
CASES: dict[str, Callable[[Path], dict[str, Path]]] = {
    name.removeprefix("case_"): _with_printout(name.removeprefix("case_"), fn)
    for name, fn in sorted(globals().items()) if name.startswith("case_")
}
