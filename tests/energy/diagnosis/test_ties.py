"""Ties the runs cannot settle, the drive that separates them, and how many more runs a weak candidate needs."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from gain_samples import gained_logs_and_model

from energy import PhysicsCurrentModel, TruthSimulator, ground_preset, robot_preset
from energy.diagnosis import Effect, EffectParameter, FitSettings, diagnose
from energy.diagnosis.fit import SetScore
from energy.diagnosis.noise import residual_noise
from energy.diagnosis.selection import SIGNIFICANT_SHRINK_PCT, tied_with, units_needed
from energy.diagnosis.separating import MAX_DRIVE_S, MAX_REPEATS, manoeuvre_library, runs_to_order

GAIN = 1.3  # a current sensor reading 30 % high: at constant speed, a payload or an offset fits it as well


def _sim() -> TruthSimulator:
    return TruthSimulator(robot_preset("husky"), {"asphalt": ground_preset("asphalt")}, seed=0)


def _gained(log):
    return dataclasses.replace(log, current_left_a=GAIN * log.current_left_a, current_right_a=GAIN * log.current_right_a)


@pytest.fixture(scope="module")
def tied():
    """Straights at constant speed, one per run, read by a sensor 30 % high; diagnosed with three candidates."""
    sim = _sim()
    t = np.arange(0.0, 30.0, 0.05)
    logs = [_gained(sim.simulate_commands(t, np.full(t.size, 0.5 + 0.1 * k), np.zeros(t.size), ground="asphalt",
                                          seed=k)) for k in range(4)]
    model = PhysicsCurrentModel("husky", "asphalt", fit_parameters=()).fit(logs[:1])
    return logs, diagnose(model, logs, effects=["current_gain", "current_offset", "mass"])


def test_a_tie_is_named_with_both_explanations_and_kept_in_the_json(tied):
    _, d = tied
    assert len(d.ties) == 1
    tie = d.ties[0]
    assert tie.chosen == d.current.chosen[0]  # the corrected model is built from the first of the set
    assert set(tie.effects) == {"mass", "current_offset"}
    for alt in tie.alternatives:  # about as much as the chosen one: a fraction of a point of the gap
        assert abs(tie.added_pct[tie.chosen] - tie.added_pct[alt]) < SIGNIFICANT_SHRINK_PCT
    sentence = next(s for s in d.verdict if "cannot tell them apart" in s)
    assert all(tie.explanations[n] in sentence for n in tie.effects) and f"uses {tie.chosen}" in sentence
    doc = json.loads(json.dumps(d.to_dict(), default=float))
    assert doc["indistinguishable"][0]["effects"] == list(tie.effects)


def test_the_separating_drive_differs_most_and_a_simulated_repeat_agrees_with_its_expectation(tied, tmp_path):
    logs, d = tied
    (drive,) = d.separating_drives
    assert drive.effects == d.ties[0].effects and drive.equivalent == ()
    alt = drive.effects[1]
    assert drive.best.duration_s <= MAX_DRIVE_S
    # of the drives that settle it and reach 3 x the noise over the whole drive (the residual's correlation and the
    # run-to-run spread counted), the largest difference per sample against the noise
    settling = [c for c in drive.library if c.pairs[alt].repeats <= MAX_REPEATS and c.pairs[alt].z_per_repeat >= 3.0]
    assert drive.best.pairs[alt].noise_units == max(c.pairs[alt].noise_units for c in settling)
    assert drive.drive_noise_units == drive.best.pairs[alt].z_per_repeat >= 3.0
    assert drive.to_dict()["drive_noise_units"] == drive.drive_noise_units
    assert drive.expected_difference_a > 0 and drive.repeats >= 1
    # as many runs as the diagnosis's ordering of the runs needs: none of 4 runs orders the pair, so 3 more
    assert drive.runs_to_order == runs_to_order(len(logs)) == 3 and drive.repeats >= 3
    assert drive.to_dict()["runs_to_order"] == 3
    # within the robot's limits
    husky = robot_preset("husky")
    assert np.max(np.abs(drive.profile.omega_radps)) <= 0.8 * husky.max_omega_radps + 1e-9
    assert np.max(np.abs(drive.profile.v_mps)) <= 0.8 * husky.max_speed_mps + 1e-9
    assert any(s.startswith(f"To tell {drive.effects[0]} from {alt}") for s in d.verdict)
    # the same drive, simulated with the same sensor error: the difference measured agrees within a factor 2
    p = drive.profile
    repeat = _gained(_sim().simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt", seed=99))
    got = drive.score(repeat)[alt]
    assert 0.5 <= got["measured_difference_a"] / drive.expected_difference_a <= 2.0
    # the CSV is the command profile the robot drives, with both predictions
    path = drive.write_csv(tmp_path)
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    header = path.read_text().splitlines()[0].split(",")
    assert header[:3] == ["time_s", "v_mps", "omega_radps"] and table.shape == (len(p.time_s), 3 + 2 * len(drive.effects))
    np.testing.assert_allclose(table[:, 1], p.v_mps, atol=1e-5)
    # and diagnose's report writes it with its figure
    names = {w.name for w in d.write(tmp_path / "out", on_figure_error="raise")}
    assert f"{drive.file_stem}.csv" in names and f"{drive.file_stem}.png" in names


def test_a_clear_winner_is_no_tie():
    logs, model = gained_logs_and_model()
    d = diagnose(model, logs)
    assert d.current.chosen and d.current.chosen[0] == "current_gain"
    assert d.ties == () and d.separating_drives == ()
    assert not any("cannot tell them apart" in s for s in d.verdict)


def _set_score(sse: list[float]) -> SetScore:
    sse = np.asarray(sse, float)
    return SetScore((), sse, np.full(sse.size, 100), (), ())


class _Named(Effect):
    """A one-parameter candidate for the tie rule's scores."""

    kind = "physics"
    parameters = (EffectParameter("size", 1.0, 0.0, 10.0, "1", None, 0.0, 10.0, "any"),)

    def __init__(self, name: str) -> None:
        self.name = name


def _trial(sse: list[float]) -> SetScore:
    sse = np.asarray(sse, float)
    return SetScore(("x",), sse, np.full(sse.size, 100), tuple((np.array([1.0]),) for _ in range(3)), ())


@pytest.mark.parametrize(("leads", "tie"), [
    ([1.79, 1.75, 2.25, 1.69, 2.38, -1.21], True),  # every resample leads, but by 1.4 points on average: below 2
    ([1.5, 1.2, 1.8, 0.9, 1.6, 1.1], True),  # every run leads, by less than 2 points
    ([3.1, 2.4, 4.0, 2.9, 3.5, 2.2], False),  # every run leads, by 3 points on average: ordered
    ([9.0, -3.0, 8.0, -4.0, 10.0, -5.0], True),  # 2.5 points on average, but the runs disagree
])
def test_a_pair_is_ordered_only_by_a_lead_the_diagnosis_would_call_significant(leads, tie):
    none = _trial([100.0] * 6)  # each run's gap before: 100, so a lead in sse is a lead in points
    best, alt = _Named("best"), _Named("alt")
    trials = {"best": _trial([50.0] * 6), "alt": _trial([50.0 + g for g in leads])}
    assert tied_with(best, [best, alt], trials, none, none, 200, 0) == ((alt,) if tie else ())


def test_units_needed_follows_the_spread_of_the_per_unit_gains():
    none = _set_score([100.0] * 4)
    trial = _set_score([90.0, 96.0, 92.0, 98.0])  # gains 10, 4, 8, 2 points: mean 6, sd 3.65
    mean, sd, n = units_needed(none, none, trial)
    assert mean == pytest.approx(6.0) and sd == pytest.approx(np.std([10, 4, 8, 2], ddof=1))
    assert n == max(math.ceil((1.959963984540054 * sd / mean) ** 2), 5)
    weak = _set_score([99.0, 99.5, 98.5, 99.0])  # 1 point on average: below what a finding needs
    assert units_needed(none, none, weak)[2] is None and units_needed(none, none, weak)[0] < SIGNIFICANT_SHRINK_PCT


def test_when_nothing_is_significant_the_verdict_says_how_many_runs_would_settle_the_likeliest():
    sim = _sim()
    t = np.arange(0.0, 20.0, 0.05)
    v = np.where((t % 10) < 6, 0.6, 0.0)
    logs = [sim.simulate_commands(t, v, np.zeros(t.size), ground="asphalt", seed=10 + k) for k in range(3)]
    model = PhysicsCurrentModel("husky", "asphalt").fit(logs)
    rng = np.random.default_rng(5)
    # currents of the model itself, 3 % high, in noise of 0.4 A: a weak gain these runs cannot show
    logs = [dataclasses.replace(log, current_left_a=p[:, 0], current_right_a=p[:, 1]) for log, p in
            ((log, 1.03 * model.predict(log) + rng.normal(0.0, 0.4, (len(log), 2))) for log in logs)]
    d = diagnose(model, logs, effects=["current_gain", "current_offset", "mass"])
    assert not d.current.chosen
    more = d.more_data
    assert more["effect"] in {"current_gain", "current_offset", "mass"} and more["n_units"] == 3
    assert more["sentence"] in d.verdict
    if more["units_needed"] is None:
        assert "would not make it one" in more["sentence"]
    else:
        assert more["units_needed"] > 3 and f"about {more['units_needed']} runs" in more["sentence"]


def test_the_manoeuvre_library_stays_within_the_limits_and_a_minute():
    lib = manoeuvre_library(1.0, 1.2)
    names = [n for n, _, _ in lib]
    assert any(n.startswith("straight") for n in names) and any(n.startswith("arc") for n in names)
    assert any(n.startswith("pivot") for n in names) and "stop_and_go" in names
    for _, _, p in lib:
        assert p.duration_s <= MAX_DRIVE_S and np.max(np.abs(p.v_mps)) <= 1.0 + 1e-9
        assert np.max(np.abs(p.omega_radps)) <= 1.2 + 1e-9
        assert p.v_mps[0] == p.v_mps[-1] == 0.0 and p.omega_radps[-1] == 0.0  # from rest to rest
    assert manoeuvre_library(0.0, 0.0) == [] and manoeuvre_library(0.01, 0.01) == []  # never drove, never turned
    assert all(n.startswith("pivot") for n, _, _ in manoeuvre_library(0.01, 1.0))


def test_residual_noise_separates_the_noise_from_a_run_to_run_offset():
    rng = np.random.default_rng(0)
    offsets = rng.normal(0.0, 0.5, size=(40, 1))
    measured = [np.full((400, 2), 2.0) + off + rng.normal(0.0, 0.1, (400, 2)) for off in offsets]
    predicted = [np.full((400, 2), 2.0)] * 40
    got = residual_noise(measured, predicted)
    assert got.noise_a == pytest.approx(0.1, rel=0.05)
    assert got.run_spread_a == pytest.approx(float(np.std(offsets, ddof=1)), rel=0.1)
    assert got.autocorrelation < 0.1 and got.kappa == pytest.approx(1.0, abs=0.25)


def test_two_explanations_that_predict_the_same_currents_everywhere_are_called_equivalent(tied):
    """No drive of the library separates a model from itself: the pair is equivalent, and the sentence says so."""
    from energy.diagnosis import ResidualNoise, separating_drive

    logs, d = tied
    model = d.corrected_model
    noise = ResidualNoise(0.1, 0.0, 0.0)
    drive = separating_drive(("a", "b"), {"a": model, "b": model}, logs[0], noise, 1.0, 1.0)
    assert drive.equivalent == ("b",) and drive.separated == {} and drive.repeats == 0
    assert "No drive of the library separates a from b" in drive.sentence()
    assert not drive.sentence().startswith("To tell")


def test_on_a_map_the_library_drives_up_a_slope_where_a_payload_and_a_rolling_resistance_part():
    """A payload seen on level straights across an inclined plane: on the slope (gravity scales with the mass, not
    with the rolling resistance) the two fitted models part by about an ampere; every drive is placed on the map."""
    from terrain import TerrainMap

    husky = robot_preset("husky")
    n = 60
    plane = TerrainMap(0.15 * np.tile(np.arange(n, dtype=float), (n, 1)), 1.0, ground=np.zeros((n, n), int),
                       ground_names={0: "asphalt"})  # rising 0.15 m per metre of x: 8.5 degrees
    laden = TruthSimulator(husky.replace(mass_kg=1.6 * husky.mass_kg), {"asphalt": ground_preset("asphalt")},
                           velocity_time_constant_s=0.0, seed=0)
    t = np.arange(0.0, 30.0, 0.05)
    runs = []
    for k in range(4):  # along +y: level
        v = 0.4 + 0.1 * k
        pose = np.column_stack([np.full(t.size, 10.0 + 10 * k), np.minimum(5.0 + v * t, 55.0), np.full(t.size, np.pi / 2)])
        runs.append(laden.simulate_commands(t, np.full(t.size, v), 0 * t, ground="asphalt", seed=k, pose_xyh=pose))
    model = PhysicsCurrentModel("husky", "asphalt", fit_parameters=(), terrain=plane).fit(runs[:1])
    d = diagnose(model, runs, effects=["mass", "rolling_resistance", "current_offset"], terrain=plane,
                 settings=FitSettings(seed=0))
    (drive,) = d.separating_drives
    assert drive.effects[0] == "mass" and "rolling_resistance" in drive.effects
    (slope,) = [c for c in drive.library if c.name == "slope"]
    assert "8.5° slope" in slope.description and slope.duration_s <= MAX_DRIVE_S
    assert slope.pairs["rolling_resistance"].difference_rms_a > 0.5 and slope.pairs["rolling_resistance"].repeats == 1
    # the slope drive's own commands: up along the gradient (+x), a stop, back down in reverse, on the map
    from energy.diagnosis.separating import slope_drive

    _, _, profile = slope_drive(plane, 0.8)
    x = profile.pose_xyh[:, 0]
    assert np.all(plane.contains(x, profile.pose_xyh[:, 1])) and np.ptp(profile.pose_xyh[:, 1]) < 1e-9
    assert x[np.argmax(x)] - x[0] == pytest.approx(x[np.argmax(x)] - x[-1], abs=0.05)  # back where it started
    assert np.max(profile.v_mps) > 0 > np.min(profile.v_mps)
    assert slope_drive(TerrainMap(np.zeros((20, 20)), 1.0), 0.8) is None  # a level map has no slope to drive


def test_runs_to_order_leaves_under_2_5_percent_of_resamples_without_a_driven_run():
    from energy.diagnosis.separating import ORDER_TAIL

    for n_units, per in ((2, 1), (4, 1), (6, 1), (12, 1), (30, 5)):
        n = runs_to_order(n_units, per)
        total = n_units + n * per
        assert (n_units / total) ** total < ORDER_TAIL  # enough
        if n > 1:
            fewer = n_units + (n - 1) * per
            assert (n_units / fewer) ** fewer >= ORDER_TAIL  # and no more than needed
    assert runs_to_order(6) == 4 and runs_to_order(0) == 1


class _SpeedModel:
    """A fitted model's stand-in: ``gain * v`` A on each side."""

    def __init__(self, gain: float) -> None:
        self.gain = gain

    def predict(self, log):
        return np.column_stack([self.gain * log.v_mps, self.gain * log.v_mps])


def test_the_drive_reaches_3_x_its_noise_per_drive_with_a_longer_form_where_a_short_one_falls_short(tied):
    """Two explanations that part in proportion to the speed, against a residual that puts the fastest 20 s
    straight just under 3 x its noise over the whole drive: of the drives that reach it (the manoeuvres' 40 s
    forms), the largest difference per sample, not the 20 s straight that differs most per sample."""
    from energy.diagnosis import ResidualNoise, separating_drive
    from energy.diagnosis.separating import DRIVE_Z

    logs, _ = tied
    noise = ResidualNoise(0.1, 0.0, 0.0, residual_a=0.1)
    models = {"a": _SpeedModel(1.0), "b": _SpeedModel(1.01)}
    short = separating_drive(("a", "b"), models, logs[0], noise, 1.0, 1.0).library
    straight = next(c for c in short if c.name == "straight_0.95")
    scale = straight.pairs["b"].z_per_repeat / (0.85 * DRIVE_Z)  # the 20 s straight: 0.85 x DRIVE_Z
    noise = ResidualNoise(0.1 * scale, 0.0, 0.0, residual_a=0.1 * scale)
    drive = separating_drive(("a", "b"), models, logs[0], noise, 1.0, 1.0)
    straight = next(c for c in drive.library if c.name == "straight_0.95")
    assert straight.pairs["b"].z_per_repeat == pytest.approx(0.85 * DRIVE_Z, rel=1e-6)
    assert drive.drive_noise_units >= DRIVE_Z and drive.best.name.endswith("_long")
    assert drive.best.duration_s <= MAX_DRIVE_S
    reaching = [c for c in drive.library if c.pairs["b"].z_per_repeat >= DRIVE_Z]
    assert drive.best.pairs["b"].noise_units == max(c.pairs["b"].noise_units for c in reaching)
    assert max(c.pairs["b"].noise_units for c in drive.library) > drive.best.pairs["b"].noise_units * 0.9


def test_surges_accelerate_as_stops_and_starts_do_without_standing_still():
    lib = {n: p for n, _, p in manoeuvre_library(1.0, 1.2, max_accel_mps2=0.7)}
    surges, stops = lib["surges"], lib["stop_and_go"]
    low = 0.3 * 0.8  # 0.3 of the stop-and-go speed (0.8 of the top speed)
    up = np.nonzero(surges.v_mps >= low - 1e-9)[0]
    assert np.all(surges.v_mps[up[0]:up[-1] + 1] >= low - 1e-9)  # from the start to the stop, never below it
    assert np.sum(np.diff((stops.v_mps > 1e-9).astype(int)) == 1) > 1  # where stop and go starts again and again
    assert np.max(np.diff(surges.v_mps)) == pytest.approx(np.max(np.diff(stops.v_mps)))  # the same accelerations
    assert surges.duration_s <= MAX_DRIVE_S
    long = {n: p for n, _, p in manoeuvre_library(1.0, 1.2, hold_s=40.0, max_accel_mps2=0.7)}
    assert long["stop_and_go"].duration_s <= MAX_DRIVE_S and long["surges"].duration_s <= MAX_DRIVE_S
    assert long["stop_and_go"].duration_s > 1.5 * stops.duration_s  # more cycles, as many as fit in a minute


class _TurnModel:
    """A fitted model's stand-in: ``gain * |omega|`` A on each side (nothing on a straight)."""

    def __init__(self, gain: float) -> None:
        self.gain = gain

    def predict(self, log):
        return np.column_stack([self.gain * np.abs(log.omega_radps)] * 2)


def test_on_a_map_the_slope_goes_first_among_the_drives_that_settle_every_pair(tied):
    """Two explanations that part in proportion to the speed, against little noise: every drive settles them, and
    the top-speed straight differs most per sample, but the slope (gravity: a force no fit sized) is driven. Where
    the slope does not part them (a difference only in turns), it is not."""
    from energy.diagnosis import ResidualNoise, separating_drive
    from energy.diagnosis.separating import DRIVE_Z, SLOPE_DRIVE
    from terrain import TerrainMap

    logs, _ = tied
    n = 60
    plane = TerrainMap(0.15 * np.tile(np.arange(n, dtype=float), (n, 1)), 1.0, ground=np.zeros((n, n), int),
                       ground_names={0: "asphalt"})
    noise = ResidualNoise(0.01, 0.0, 0.0, residual_a=0.01)
    drive = separating_drive(("a", "b"), {"a": _SpeedModel(1.0), "b": _SpeedModel(1.5)}, logs[0], noise, 1.0, 1.0,
                             terrain=plane)
    slope = next(c for c in drive.library if c.name == SLOPE_DRIVE)
    assert slope.pairs["b"].repeats <= MAX_REPEATS and slope.pairs["b"].z_per_repeat >= DRIVE_Z  # it settles them
    assert max(c.pairs["b"].noise_units for c in drive.library) > slope.pairs["b"].noise_units  # not the largest
    assert drive.best.name == SLOPE_DRIVE and drive.profile.pose_xyh is not None
    turns = separating_drive(("a", "b"), {"a": _TurnModel(1.0), "b": _TurnModel(1.5)}, logs[0], noise, 1.0, 1.0,
                             terrain=plane)
    assert turns.best.name != SLOPE_DRIVE
    assert next(c for c in turns.library if c.name == SLOPE_DRIVE).pairs["b"].repeats > MAX_REPEATS
