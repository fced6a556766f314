"""Fitting on calibration data and scoring on held-out data: recovered values, shrink, intervals, errors."""

import dataclasses

import numpy as np
import pytest
from gain_samples import gained_logs_and_model

from energy import InteractionLog
from terrawatt_base.errors import DataError
from energy.diagnosis import effect, make_split
from energy.diagnosis.fit import (
    bootstrap_shrink_interval_pct,
    fit_effect_set,
    prepare_data,
    score_effect_set,
    shrink_pct,
)


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
    from energy.diagnosis.effects_physics import MassEffect
    from diagnosis_scenarios import scenario

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
