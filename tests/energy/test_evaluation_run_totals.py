"""Tests of energy.evaluation.run_totals: both sides through the pack, and whether the intervals held."""

import math

import numpy as np
import pytest
from evaluation_samples import adapt_log, adapt_logs, adapt_settings

from energy import Battery, LinearCurrentModel, robot_preset
from energy.budget import log_battery_power_w
from energy.evaluation import (
    AdaptSettings,
    RunTotal,
    ScoredRun,
    evaluate_few_shot,
    few_shot_scores,
    pack_energy_j,
    run_totals,
    summarise_totals,
)
from energy.models import fit_interval
from energy.models.base import log_currents
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

HUSKY = robot_preset("husky")


def test_pack_energy_is_the_drive_sides_battery_power_and_pays_the_pack_loss():
    log = adapt_log(0, "grass")
    cur = log_currents(log)
    p = log_battery_power_w(log, HUSKY, electronics=False)
    expected = float(np.sum((p[1:] + p[:-1]) / 2 * np.diff(log.time_s)))
    assert pack_energy_j(log, cur, HUSKY) == pytest.approx(expected, rel=1e-12)
    lossy = pack_energy_j(log, cur, HUSKY, Battery(20.0, HUSKY.battery_voltage_v, internal_resistance_ohm=0.1))
    assert lossy > expected  # the cells give the terminal energy plus R I^2
    assert pack_energy_j(log, 2 * cur, HUSKY) > 1.5 * expected  # more current, more energy
    half = log.time_s < log.time_s[0] + 20.0
    assert 0 < pack_energy_j(log, cur, HUSKY, mask=half) < expected
    with pytest.raises(InvalidParameterError, match="currents_a must be finite, of shape"):
        pack_energy_j(log, cur[:, :1], HUSKY)


def test_run_totals_score_each_variant_and_only_intervals_get_a_z():
    log = adapt_log(1, "grass")
    cur = log_currents(log)
    model = fit_interval(LinearCurrentModel(), [adapt_log(i, "grass", offset_a=0.1 * i) for i in range(2, 7)], folds=5)
    fc = model.predict_distribution(log)
    rows = run_totals(log, {"unadapted": (fc.mean_a, fc), "adapted": (cur, None), "gain": (1.1 * cur, None)},
                      ScoredRun("few_shot", "b", "a", "m", "20 s"), robot=HUSKY)
    by = {r.variant: r for r in rows}
    assert by["adapted"].energy_error_pct == pytest.approx(0.0, abs=1e-9)  # the truth itself
    assert by["adapted"].charge_error_pct == pytest.approx(0.0, abs=1e-9)
    assert by["gain"].charge_error_pct == pytest.approx(10.0, rel=1e-9)
    assert math.isnan(by["gain"].z) and math.isnan(by["gain"].sd_as)
    assert by["unadapted"].sd_as > 0 and math.isfinite(by["unadapted"].z)
    assert by["unadapted"].sd_as == pytest.approx(fc.charge().total_sd_as)
    with pytest.raises(UnknownNameError, match="variant must be one of"):
        RunTotal("few_shot", "g", "b", "a", "m", "20 s", "best", 1.0, 1.0, 1.0, 1.0, 1.0)


def test_summaries_count_coverage_from_z():
    # |z| = 0.1, 1.0, 1.5, 3.0 against the central 50 / 80 / 95 % half-widths 0.674, 1.282, 1.960
    zs = [0.1, -1.0, 1.5, 3.0]
    rows = [RunTotal("per_ground", "sand", f"r{i}", f"r{i}", "m", "20 s", "adapted", 100.0, 100.0 + 10 * i,
                     50.0 + z, 50.0, 1.0) for i, z in enumerate(zs)]
    rows.append(RunTotal("per_ground", "sand", "r9", "r9", "m", "20 s", "gain", 100.0, 90.0, 50.0, 45.0, math.nan))
    summary = {(s["ground"], s["variant"]): s for s in summarise_totals(rows)}
    s = summary[("sand", "adapted")]
    assert s["n"] == 4 and s["n_interval"] == 4
    assert (s["coverage_50_pct"], s["coverage_80_pct"], s["coverage_95_pct"]) == (25.0, 50.0, 75.0)
    assert s["median_abs_z"] == pytest.approx(1.25)
    assert s["energy_median_pct"] == pytest.approx(15.0)
    g = summary[("all", "gain")]
    assert g["n_interval"] == 0 and math.isnan(g["coverage_80_pct"]) and g["charge_median_pct"] == pytest.approx(10.0)


def test_the_few_shot_protocol_scores_what_the_battery_pays():
    logs = adapt_logs()
    model = fit_interval(LinearCurrentModel(), logs[:3], folds=3)  # grass only, with an interval
    scores, totals, _ = few_shot_scores(model, logs[3:5], ["sand/a", "sand/b"], model_name="m",
                                        settings=adapt_settings(trigger=False))
    assert len(totals) == 3 * len(scores) // 2  # three forecasts per scored run, two sides per score
    for t in totals:
        per_side = [s for s in scores if (s.run, s.adapt_run, s.schedule) == (t.run, t.adapt_run, t.schedule)]
        assert len(per_side) == 2
    unadapted = [t for t in totals if t.variant == "unadapted"]
    adapted = [t for t in totals if t.variant == "adapted"]
    assert all(t.sd_as > 0 for t in unadapted + adapted)  # the base's interval, carried by the update
    # sand draws twice grass's current: the unadapted forecast is far off, the adapted one much closer (the default
    # update learns straight driving's and turning's levels each from its own seconds of the prefix: 0.54 of it here)
    assert np.median([t.charge_error_pct for t in unadapted]) > 30.0
    assert np.median([t.charge_error_pct for t in adapted]) < 0.6 * np.median([t.charge_error_pct for t in unadapted])
    res = evaluate_few_shot(logs, LinearCurrentModel(), name="linear", settings=adapt_settings(trigger=False))
    doc = res.to_dict()
    assert {r["variant"] for r in doc["total_summary"]} == {"unadapted", "adapted", "gain"}
    assert len(doc["totals"]) == len(res.totals) > 0
    md = res.summary()
    assert md.index("Both sides through the pack") < md.index("Per side")
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    assert res.plot(ax=ax) is ax and ax.get_xlabel().startswith("nominal coverage")
    with pytest.raises(InvalidParameterError, match="got neither"):
        res.plot()


def test_settings_check_the_robot_and_battery():
    with pytest.raises(UnknownNameError):
        AdaptSettings(robot="no-such-robot")
    with pytest.raises(InvalidParameterError, match="battery must be a Battery or None"):
        AdaptSettings(battery=24.0)
    assert AdaptSettings(robot=HUSKY).to_dict()["robot"] == HUSKY.name
