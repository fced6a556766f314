"""Tests of energy.diagnosis.fit: the folds (disjoint, every sample held out once, contiguous blocks), fitting on
calibration data and scoring on held-out data (recovered values, shrink, intervals, errors), SetRunner serially and
on a dask client."""

import dataclasses

import numpy as np
import pytest
from gain_samples import gained_logs_and_model

from energy import InteractionLog
from energy.diagnosis import Fold, effect, make_split
from energy.diagnosis.fit import (
    SetRunner,
    bootstrap_shrink_interval_pct,
    fit_effect_set,
    prepare_data,
    score_effect_set,
    shrink_pct,
)
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError


@pytest.fixture(scope="module")
def setup():
    return gained_logs_and_model()


def test_gain_is_recovered_and_shrinks_the_held_out_gap(setup):
    logs, model = setup
    gain, offset = effect("current_gain"), effect("idle_current")
    data = prepare_data(model, logs, [gain, offset])
    values = fit_effect_set([gain], data)
    np.testing.assert_allclose(values[0], [1.3, 0.8], rtol=0.02)
    sp = make_split(logs, "runs", n_blocks=4)
    none = score_effect_set([], data, sp)
    s_gain = score_effect_set([gain], data, sp)
    s_off = score_effect_set([offset], data, sp)
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
    data = prepare_data(model, logs, [gain])
    sp = make_split(logs, "blocks", n_blocks=3)
    s = score_effect_set([gain], data, sp)
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
    data = prepare_data(model, logs, [fast])
    (v_fast,) = fit_effect_set([fast], data)
    (v_exact,) = fit_effect_set([exact], prepare_data(model, logs, [exact]))
    np.testing.assert_allclose(v_fast, v_exact, rtol=1e-3)
    np.testing.assert_allclose(v_fast, [65.0 / 50.0], rtol=0.05)  # the scenario's payload
    table = data.prepared["mass"][0].table
    assert 2 <= table.n_computed <= 8 < table.nodes.size  # only the nodes around the visited values
    sp = make_split(logs, "runs", n_blocks=3)
    s = score_effect_set([fast], data, sp)
    for k, fold in enumerate(sp.folds):  # held-out predictions are the exact physics at the fold's values
        for i, h in enumerate(fold.held_out):
            if h.any():
                exact_pred = fast.apply(s.fold_values[k][0], data.base[i], data.prepared["mass"][i])
                np.testing.assert_allclose(s.held_out_a[i][h], np.maximum(exact_pred, 0.0)[h], atol=1e-12)


# ---------------------------------------------------------------- folds
def _split_log(n, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    return InteractionLog(t, rng.random(n), np.zeros(n), rng.random(n) + 1, rng.random(n) + 1, t, np.full(n, 9.81))


@pytest.mark.parametrize("kind", ["runs", "blocks"])
def test_folds_are_disjoint_and_cover_every_sample_once(kind):
    logs = [_split_log(50, 1), _split_log(37, 2), _split_log(64, 3)]
    sp = make_split(logs, kind, n_blocks=4)
    counts = [np.zeros(len(log), dtype=int) for log in logs]
    for fold in sp.folds:
        for k, (c, h) in enumerate(zip(fold.calibration, fold.held_out)):
            assert not np.any(c & h)  # never scored on the data it was fitted on
            assert np.all(c | h)
            counts[k] += h
        assert fold.n_held_out > 0 and fold.n_calibration > 0
    assert all(np.all(c == 1) for c in counts)


def test_blocks_are_contiguous():
    sp = make_split([_split_log(100)], "blocks", n_blocks=5)
    assert sp.n_units == 5
    for fold in sp.folds:
        idx = np.flatnonzero(fold.held_out[0])
        assert np.all(np.diff(idx) == 1) and idx.size == 20


def test_runs_fold_whole_runs():
    sp = make_split([_split_log(10, k) for k in range(7)], "runs", n_blocks=3)
    assert len(sp.folds) == 3
    for fold in sp.folds:
        assert all(h.all() or not h.any() for h in fold.held_out)


def test_bad_splits():
    with pytest.raises(DataError, match="at least 2 runs"):
        make_split([_split_log(10)], "runs")
    with pytest.raises(DataError, match="no held-out data"):
        make_split([_split_log(3)], "blocks", n_blocks=5)
    with pytest.raises(UnknownNameError, match="split"):
        make_split([_split_log(10)], "interleaved")
    with pytest.raises(InvalidParameterError, match="n_blocks"):
        make_split([_split_log(10)], "blocks", n_blocks=1)
    with pytest.raises(InvalidParameterError, match="both calibration and held out"):
        Fold((np.ones(3, bool),), (np.ones(3, bool),))


# ---------------------------------------------------------------- SetRunner
@pytest.fixture(scope="module")
def case():
    logs, model = gained_logs_and_model()
    effects = [effect("current_gain"), effect("idle_current")]
    return effects, prepare_data(model, logs, effects), make_split(logs, "runs", n_blocks=4)


def test_serial_scores_are_the_scores_of_each_set_in_order(case):
    effects, data, split = case
    sets = [[], [effects[0]], [effects[1]], effects]
    runner = SetRunner(data, split)
    scores = runner.score(sets)
    assert len(scores) == 4
    for got, s in zip(scores, sets):
        np.testing.assert_array_equal(got.sse_units, score_effect_set(s, data, split).sse_units)
    assert scores[1].sse_units.sum() < scores[0].sse_units.sum()  # the gain explains the gap


def test_a_client_that_is_not_one_is_refused(case):
    _, data, split = case
    with pytest.raises(InvalidParameterError):
        SetRunner(data, split, client="tcp://localhost:8786")


def test_on_a_dask_client_equals_serial(case):
    distributed = pytest.importorskip("distributed", reason="the client path needs the distributed extra")
    effects, data, split = case
    sets = [[effects[0]], [effects[1]]]
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=":0") as client:
        runner = SetRunner(data, split, client=client)
        remote = runner.score(sets)
    serial = SetRunner(data, split).score(sets)
    for a, b in zip(remote, serial):
        np.testing.assert_array_equal(a.sse_units, b.sse_units)
