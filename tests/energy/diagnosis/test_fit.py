"""Tests of energy.diagnosis.fit: fitting on calibration data and scoring on held-out data (recovered values, shrink,
intervals, errors), SetRunner serially and on a dask client."""

import dataclasses

import numpy as np
import pytest
from gain_samples import gained_logs_and_model

from energy import InteractionLog
from energy.diagnosis import effect, make_split
from energy.diagnosis.case import prepare_data
from energy.diagnosis.fit import SetRunner, fit_effect_set, score_effect_set
from energy.diagnosis.selection import bootstrap_shrink_interval_pct, shrink_pct
from terrawatt_base.errors import DataError, InvalidParameterError


@pytest.fixture(scope="module")
def setup():
    return gained_logs_and_model()


def test_gain_is_recovered_and_shrinks_the_held_out_gap(setup):
    logs, model = setup
    gain, offset = effect("current_gain"), effect("idle_current")
    data = prepare_data(model, logs, [gain, offset], split=make_split(logs, "runs", n_blocks=4))
    values = fit_effect_set([gain], data)
    np.testing.assert_allclose(values[0], [1.3, 0.8], rtol=0.02)
    none = score_effect_set([], data)
    s_gain = score_effect_set([gain], data)
    s_off = score_effect_set([offset], data)
    assert shrink_pct(none, s_gain) > 95.0
    assert shrink_pct(none, s_gain) > shrink_pct(none, s_off)
    lo, hi = bootstrap_shrink_interval_pct(none, s_gain, n_bootstrap=50, seed=1)
    assert 90.0 < lo <= hi <= 100.0
    assert bootstrap_shrink_interval_pct(none, s_gain, n_bootstrap=50, seed=1) == (lo, hi)  # seeded
    for fv in s_gain.fold_values:
        np.testing.assert_allclose(fv[0], [1.3, 0.8], rtol=0.03)


def test_held_out_prediction_comes_from_the_fold_that_held_it_out(setup):
    logs, model = setup
    gain = effect("current_gain")
    sp = make_split(logs, "blocks", n_blocks=3)
    data = prepare_data(model, logs, [gain], split=sp)
    s = score_effect_set([gain], data)
    assert s.sse_units.shape == (sp.n_units,) and s.n_units_samples.sum() == data.n_samples
    assert len(s.fold_values) == 3 and all(h.shape == m.shape for h, m in zip(s.held_out_a, data.measured))


def test_fewer_samples_than_parameters(setup):
    logs, model = setup
    tiny = [InteractionLog(g.time_s[:3], g.v_mps[:3], g.omega_radps[:3], g.current_left_a[:3], g.current_right_a[:3],
                           g.time_s[:3], g.accel_z_mps2[:3]) for g in logs[:1]]
    learned = effect("learned_residual")
    data = prepare_data(model, tiny, [learned])
    with pytest.raises(DataError, match="parameters but the calibration data holds only"):
        fit_effect_set([learned], data)


def test_parameter_errors_fit_on_the_interpolated_physics_as_on_the_exact():
    from diagnosis_scenarios import scenario

    from energy.diagnosis.effects_physics import MassEffect

    class ExactMass(MassEffect):
        apply_surrogate = MassEffect.apply  # re-predicts the physics at every evaluation

    sc = dataclasses.replace(scenario("mass"), n_runs=3, run_duration_s=6.0)
    logs, model = sc.make_logs(0), sc.make_model(0)
    fast, exact = effect("mass"), ExactMass()
    sp = make_split(logs, "runs", n_blocks=3)
    data = prepare_data(model, logs, [fast], split=sp)
    (v_fast,) = fit_effect_set([fast], data)
    (v_exact,) = fit_effect_set([exact], prepare_data(model, logs, [exact]))
    np.testing.assert_allclose(v_fast, v_exact, rtol=1e-3)
    np.testing.assert_allclose(v_fast, [65.0 / 50.0], rtol=0.05)  # the scenario's payload
    table = data.prepared["mass"][0].table
    assert 2 <= table.n_computed <= 8 < table.nodes.size  # only the nodes around the visited values
    s = score_effect_set([fast], data)
    for k, fold in enumerate(sp.folds):  # held-out predictions are the exact physics at the fold's values
        for i, h in enumerate(fold.held_out):
            if h.any():
                exact_pred = fast.apply(s.fold_values[k][0], data.base[i], data.prepared["mass"][i])
                np.testing.assert_allclose(s.held_out_a[i][h], np.maximum(exact_pred, 0.0)[h], atol=1e-12)


# ---------------------------------------------------------------- SetRunner
@pytest.fixture(scope="module")
def case():
    logs, model = gained_logs_and_model()
    effects = [effect("current_gain"), effect("idle_current")]
    return effects, prepare_data(model, logs, effects, split=make_split(logs, "runs", n_blocks=4))


def test_serial_scores_are_the_scores_of_each_set_in_order(case):
    effects, data = case
    sets = [[], [effects[0]], [effects[1]], effects]
    runner = SetRunner(data)
    scores = runner.score(sets)
    assert len(scores) == 4
    for got, s in zip(scores, sets):
        np.testing.assert_array_equal(got.sse_units, score_effect_set(s, data).sse_units)
    assert scores[1].sse_units.sum() < scores[0].sse_units.sum()  # the gain explains the gap


def test_a_client_that_is_not_one_is_refused(case):
    _, data = case
    with pytest.raises(InvalidParameterError):
        SetRunner(data, client="tcp://localhost:8786")


def test_scoring_needs_a_split(case):
    effects, data = case
    with pytest.raises(InvalidParameterError, match="prepared with a split"):
        score_effect_set(effects[:1], dataclasses.replace(data, split=None))


def test_on_a_dask_client_equals_serial(case):
    distributed = pytest.importorskip("distributed", reason="the client path needs the distributed extra")
    effects, data = case
    sets = [[effects[0]], [effects[1]]]
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=":0") as client:
        runner = SetRunner(data, client=client)
        remote = runner.score(sets)
    serial = SetRunner(data).score(sets)
    for a, b in zip(remote, serial):
        np.testing.assert_array_equal(a.sse_units, b.sse_units)
