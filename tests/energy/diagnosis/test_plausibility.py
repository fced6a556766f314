"""Plausibility of fitted effect values: priors, physical ranges, flags, and a verdict that doubts implausible fits."""

import dataclasses
import json

import numpy as np
import pytest
from diagnosis_scenarios import scenario

from energy import PhysicsCurrentModel, TruthSimulator, robot_preset
from energy.diagnosis import EFFECTS_CATALOGUE, EffectParameter, FitSettings, diagnose, effect
from energy.diagnosis.effects_physics import MassEffect
from energy.sim import PAPER_GROUNDS, NoiseModel


def test_every_catalogued_effect_states_physical_ranges_narrower_than_its_fit():
    expected = {
        "mass": {"mass_scale": (0.5, 3.0)},
        "motor_constant": {"torque_constant_scale": (0.8, 1.25)},
        "current_gain": {"gain_left": (0.7, 1.4), "gain_right": (0.7, 1.4)},
        "current_offset": {"offset_left_a": (-1.0, 1.0), "offset_right_a": (-1.0, 1.0)},
        "idle_current": {"idle_current_a": (-1.0, 1.0)},
        "time_lag": {"lag_s": (-0.5, 0.5)},
        "inertia": {"gain": (0.8, 1.25)},
        "turning_resistance": {"gain": (0.8, 1.25)},
    }
    for name, ranges in expected.items():
        e = effect(name)
        assert {p.name: (p.plausible_low, p.plausible_high) for p in e.parameters} == ranges, name
    rolling = effect("rolling_resistance").with_labels(["snow", "asphalt"])
    assert {(p.plausible_low, p.plausible_high) for p in rolling.parameters} == {(0.005, 0.4)}
    for name in EFFECTS_CATALOGUE:
        for p in effect(name).parameters:  # the start value is believable; the range says why when it is physical
            assert p.plausible(p.initial), (name, p.name)
            assert p.plausible_note or name == "learned_residual", (name, p.name)
    mass = effect("mass").parameters[0]
    assert mass.low < mass.plausible_low and mass.high > mass.plausible_high  # the fit can leave the range


@pytest.fixture(scope="module")
def physics():
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=0.0)
    t = np.arange(300) * 0.01
    log = sim.simulate_commands(t, np.where(t < 2, 0.4, 0.0), np.where(t < 2, 0.3, 0.8), ground="coated_wood", seed=1)
    model = PhysicsCurrentModel(ground=PAPER_GROUNDS["coated_wood"], fit_parameters=(), clip_negative=False).fit([log])
    return log, model


def test_priors_are_the_models_own_values(physics):
    log, model = physics
    for name, prior in (("mass", 1.0), ("motor_constant", 1.0),
                        ("rolling_resistance", model.ground_.rolling_resistance_coef),
                        ("track_width", model.robot_.track_width_multiplier)):
        e = effect(name).bind([log])
        prepared = [e.prepare(model, log)]
        np.testing.assert_allclose(e.priors(prepared), np.full(e.n_parameters, prior), err_msg=name)
    assert effect("current_gain").priors().tolist() == [1.0, 1.0]
    assert effect("current_offset").priors().tolist() == [0.0, 0.0]
    assert effect("time_lag").priors().tolist() == [0.0]
    mass = effect("mass").bind([log])
    text = mass.describe(np.array([1.8]), [mass.prepare(model, log)])
    kg = model.robot_.mass_kg
    assert text.startswith(f"mass +{0.8 * kg:.3g} kg") and "x1.8" in text


def test_a_vanishing_rolling_resistance_is_flagged_at_its_bound_and_below_its_range():
    e = effect("rolling_resistance").with_labels(["snow"])
    flags = e.plausibility_flags(np.array([7e-16]))
    assert len(flags) == 2
    assert "outside its plausible 0.005 … 0.4" in flags[0] and "pinned at its fitting bound 0" in flags[1]
    assert e.plausibility_flags(np.array([0.05])) == ()


class StandInMass(MassEffect):
    """The mass effect under another name with a tight plausible range: the same fit, flagged."""

    name = "stand_in"
    parameters = (EffectParameter("mass_scale", 1.0, 0.25, 4.0, "1", None, 0.9, 1.1, "a test's tight range"),)


@pytest.fixture(scope="module")
def payload():
    sc = dataclasses.replace(scenario("mass"), n_runs=4, run_duration_s=8.0)
    return sc, sc.make_logs(0), sc.make_model(0)


def test_of_two_effects_the_data_cannot_tell_apart_the_plausible_one_is_chosen(payload, tmp_path):
    """The stand-in fits exactly as the mass effect (same physics, listed first: it wins a tie on the
    fit) but its value lies outside its range: mass, whose same value is plausible and which the
    stand-in does not beat significantly on held-out runs, is chosen; the stand-in stays in the
    ranking, doubted, with its flags."""
    sc, logs, model = payload
    d = diagnose(model, logs, terrain=sc.terrain, effects=[StandInMass(), "mass", "current_gain"],
                 settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[0] == "mass" and "stand_in" not in d.current.chosen
    first = d.current.score("stand_in")
    assert first.doubtful and first.flags and "outside its plausible 0.9 … 1.1" in first.flags[0]
    assert first.alone_parameters["mass_scale"] == pytest.approx(65.0 / 50.0, rel=0.05)  # on its own: the payload
    assert first.alone_flags and "outside its plausible 0.9 … 1.1" in first.alone_flags[0]
    assert first.priors == {"mass_scale": 1.0} and first.plausible == {"mass_scale": (0.9, 1.1)}
    mass = d.current.score("mass")
    assert mass.parameters["mass_scale"] == pytest.approx(65.0 / 50.0, rel=0.05)
    assert not mass.doubtful and not mass.alone_flags and mass.alone_summary.startswith("mass +")
    assert not any("is doubtful" in s for s in d.verdict)  # what is chosen is plausible
    assert any(s.startswith("mass (parameter) explains") for s in d.verdict)
    # the current gain fits the 15 kg payload too (1.29 alone, a plausible sensor error): mass fits better
    assert d.current.score("current_gain").alone_parameters["gain_left"] == pytest.approx(1.29, abs=0.03)
    doc = json.loads(json.dumps(d.to_dict()))
    row = next(r for r in doc["ranking"] if r["name"] == "stand_in")
    assert row["doubtful"] is True and row["flags"] == list(first.flags)
    assert row["priors"] == {"mass_scale": 1.0} and row["plausible"] == {"mass_scale": [0.9, 1.1]}
    assert {"alone_parameters", "alone_flags", "alone_summary", "summary"} <= set(row)
    md = d.to_markdown()
    assert f"mass_scale = {first.parameters['mass_scale']:.4g} (prior 1; plausible 0.9 … 1.1)" in md
    assert "| flags |" in md and "outside its plausible 0.9 … 1.1" in md


def test_without_a_plausible_alternative_the_verdict_says_so(payload):
    sc, logs, model = payload
    # nothing plausible is significant: the implausible stand-in is taken, doubted, and the verdict says so
    d = diagnose(model, logs, terrain=sc.terrain, effects=[StandInMass(), "time_lag"],
                 settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[0] == "stand_in"
    doubt = next(s for s in d.verdict if s.startswith("stand_in is doubtful"))
    assert "No candidate with plausible values explains a similar held-out gap" in doubt


def test_a_plausible_candidate_goes_first_only_when_it_explains_a_comparable_part(payload):
    # the idle current explains 42 % of a payload's gap with a plausible value, the stand-in (the payload
    # itself, with a value outside its tight range) 96 %: not comparable, the stand-in goes first, doubted
    sc, logs, model = payload
    d = diagnose(model, logs, terrain=sc.terrain, effects=[StandInMass(), "idle_current"],
                 settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[0] == "stand_in" and d.current.score("stand_in").doubtful
    assert d.current.score("idle_current").shrink_pct < 0.5 * d.current.score("stand_in").shrink_pct


def test_a_plausible_choice_is_not_doubted(payload):
    sc, logs, model = payload
    d = diagnose(model, logs, terrain=sc.terrain, effects=["mass", "current_gain"],
                 settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[0] == "mass"
    s = d.current.score("mass")
    assert not s.doubtful and s.flags == () and s.summary.startswith("mass +")
    assert not any("doubtful" in v for v in d.verdict)
