"""Tests of a point update's interval given its prefix (AdaptedCurrentModel.correct_distribution)."""

import dataclasses

import numpy as np
import pytest
from interval_samples import fit_two_ground_estimator, interval_log, with_carry

from energy import AdaptedCurrentModel
from energy.models import ModelRecord
from terrawatt_base.errors import FileFormatError


@pytest.fixture(scope="module")
def two_ground_estimator():
    return fit_two_ground_estimator()


def _with_currents(log, currents):
    return dataclasses.replace(log, current_left_a=currents[:, 0], current_right_a=currents[:, 1])


def _parts(est, log):
    """The base forecast's run spread split as the update splits it: own run, new ground, members (A², (N, 2))."""
    fc = est.predict_distribution(log)
    iv = est.interval_
    own2 = iv.run_sd_a(log, fc.mean_a, known=True) ** 2
    ground2 = iv.run_sd_a(log, fc.mean_a, known=True, cov=iv.new_ground_cov) ** 2
    return fc, own2, ground2, np.maximum(fc.run_sd_a**2 - own2 - ground2, 0.0)


def test_a_prefix_near_its_forecast_narrows_the_new_ground_part_to_its_posterior(two_ground_estimator):
    est, _ = two_ground_estimator
    drive = interval_log(40, "c", vibration=0.5).slice(0.0, 20.0)  # a ground the model never drove
    rng = np.random.default_rng(3)
    quiet = _with_currents(drive, est.predict(drive) + 0.05 * rng.standard_normal((len(drive), 2)))
    ad = AdaptedCurrentModel(est, scope="ground").fit(quiet)
    obs, noise, run, ground = ad.evidence_
    later = interval_log(41, "c", vibration=0.5)
    fc, own2, ground2, ens2 = _parts(est, later)
    after = ad.predict_distribution(later)
    # the documented factor, computed here from its parts
    t = later.time_s
    v_sd = np.trapezoid(np.sqrt(ground2), t, axis=0)
    d = np.trapezoid(after.mean_a - fc.mean_a, t, axis=0)
    total = ground + run + noise
    factor = (run + noise) / total + (ground / total * obs / np.sqrt(ground) - d / v_sd) ** 2
    np.testing.assert_allclose(after.run_sd_a**2, own2 + ens2 + factor * ground2, rtol=1e-9, atol=1e-12)
    assert np.all(factor < 1.0)  # a prefix on its forecast: the ground lies near, the interval narrows
    assert after.charge().total_sd_as < fc.charge().total_sd_as
    np.testing.assert_array_equal(after.sample_sd_a, fc.sample_sd_a)  # per-sample noise is not the ground's
    assert after.dof == fc.dof


def test_a_far_prefix_the_update_holds_back_from_keeps_a_wide_interval_that_holds_the_next_run(two_ground_estimator):
    est, _ = two_ground_estimator
    drive = interval_log(40, "c", vibration=0.5).slice(0.0, 20.0)
    near = AdaptedCurrentModel(est, scope="ground").fit(_with_currents(drive, est.predict(drive)))
    far = AdaptedCurrentModel(est, scope="ground").fit(_with_currents(drive, est.predict(drive) + 3.0))
    later = interval_log(41, "c", vibration=0.5, offset_a=3.0)  # the next run on that ground, as far off
    sd_near = near.predict_distribution(later).charge().total_sd_as
    wide = far.predict_distribution(later).charge()
    assert wide.total_sd_as > sd_near  # the shrink holds back from 3 A: that share of the offset is left unknown
    true = float(np.sum(np.trapezoid(np.column_stack([later.current_left_a, later.current_right_a]),
                                     later.time_s, axis=0)))
    lo, hi = wide.interval(0.95)
    assert lo < true < hi


def test_with_nothing_to_carry_the_base_spread_is_kept(two_ground_estimator):
    est, train = two_ground_estimator
    prefix = _with_currents(train[1].slice(0.0, 20.0), est.predict(train[1].slice(0.0, 20.0)) + 3.0)
    other_runs = AdaptedCurrentModel(est, scope="ground").fit(prefix)  # a ground the model drove: G = 0
    np.testing.assert_array_equal(other_runs.predict_distribution(train[2]).run_sd_a,
                                  est.predict_distribution(train[2]).run_sd_a)
    new_ground = interval_log(40, "c", vibration=0.5, offset_a=3.0)
    unlearned = with_carry(est, None)  # no carry learned along a run (a file from before, too few runs)
    same_run = AdaptedCurrentModel(unlearned, scope="run").fit(new_ground.slice(0.0, 20.0))
    rest = new_ground.slice(20.0, float(new_ground.time_s[-1]))
    np.testing.assert_array_equal(same_run.predict_distribution(rest).run_sd_a,
                                  unlearned.predict_distribution(rest).run_sd_a)
    other = AdaptedCurrentModel(est, scope="ground").fit(new_ground.slice(0.0, 20.0))
    assert not np.allclose(other.predict_distribution(rest).run_sd_a, est.predict_distribution(rest).run_sd_a)


@pytest.mark.parametrize("carry", [0.0, 0.6, 1.0])
def test_the_rest_of_a_run_is_conditioned_on_its_prefix_by_the_learned_carry(two_ground_estimator, carry):
    est, train = two_ground_estimator
    model = with_carry(est, carry)
    run = train[1]  # a ground the model drove: G = 0, the run's own offset is what the prefix tells of
    rng = np.random.default_rng(7)
    offset = 2.0 * np.sqrt(np.median(_parts(model, run)[1], axis=0))  # an offset of two of its learned run spreads
    shifted = _with_currents(run, np.column_stack([run.current_left_a, run.current_right_a]) + offset
                             + 0.05 * rng.standard_normal((len(run), 2)))
    ad = AdaptedCurrentModel(model, scope="run").fit(shifted.slice(0.0, 20.0))
    obs, noise, own, ground = ad.evidence_
    assert np.all(ground == 0)
    rest = shifted.slice(20.0, float(run.time_s[-1]) + 1.0)
    fc, own2, _, _ = _parts(model, rest)
    ens2 = np.maximum(fc.run_sd_a**2 - own2, 0.0)  # a ground the model drove: no new-ground part
    after = ad.predict_distribution(rest)
    # the documented factor, computed here from its parts: C = carry sqrt(Vr R), posterior P - C² / total, departure b
    t = rest.time_s
    prior = np.trapezoid(np.sqrt(own2), t, axis=0)
    cross = carry * prior * np.sqrt(own)
    total = own + noise
    d = np.trapezoid(after.mean_a - fc.mean_a, t, axis=0)
    factor = (prior**2 - cross**2 / total + (cross / total * obs - d) ** 2) / prior**2
    np.testing.assert_allclose(after.run_sd_a**2, ens2 + factor * own2, rtol=1e-9, atol=1e-12)
    if carry == 1.0:  # the update carries (R / (R + E)) what the posterior does: the interval narrows
        assert np.all(factor < 1.0)
    if carry == 0.0:  # nothing carries, yet the update moved the forecast: its departure widens the interval
        assert np.all(factor > 1.0)
    np.testing.assert_array_equal(after.sample_sd_a, fc.sample_sd_a)


def test_the_prefix_evidence_is_saved_and_a_file_without_it_keeps_the_base_spread(two_ground_estimator, tmp_path):
    est, _ = two_ground_estimator
    drive = interval_log(40, "c", vibration=0.5, offset_a=1.0).slice(0.0, 20.0)
    ad = AdaptedCurrentModel(est, scope="ground").fit(drive)
    later = interval_log(41, "c", vibration=0.5)
    back = AdaptedCurrentModel.load(ad.save(tmp_path / "adapted.zip"))
    np.testing.assert_array_equal(back.evidence_, ad.evidence_)
    np.testing.assert_allclose(back.predict_distribution(later).run_sd_a, ad.predict_distribution(later).run_sd_a)
    rec = ad.to_record()
    old = AdaptedCurrentModel.from_record(ModelRecord(rec.model_class, rec.params,
                                                      {k: v for k, v in rec.state.items() if k != "evidence"}), "old")
    assert old.evidence_ is None
    np.testing.assert_array_equal(old.predict_distribution(later).run_sd_a, est.predict_distribution(later).run_sd_a)
    for bad in (np.zeros((3, 2)), np.array([[1.0, 1.0], [-1.0, 0.0], [0.0, 0.0], [0.0, 0.0]]),
                np.array([[1e300, 1.0], [1.0, 1.0], [1.0, 1.0], [1.0, 1.0]])):
        with pytest.raises(FileFormatError, match="evidence"):
            AdaptedCurrentModel.from_record(ModelRecord(rec.model_class, rec.params, {**rec.state, "evidence": bad}))


def test_the_bayesian_update_of_the_rest_of_a_run_carries_its_offset_as_learned(two_ground_estimator):
    est, _ = two_ground_estimator
    prefix = interval_log(40, "c", vibration=0.5, offset_a=2.0).slice(0.0, 20.0)
    rest = interval_log(40, "c", vibration=0.5, offset_a=2.0).slice(20.0, 40.0)
    parts = {}
    for carry in (None, 1.0, 0.5, 0.0):
        ad = AdaptedCurrentModel(with_carry(est, carry), method="bayes", scope="run").fit(prefix)
        ground, own = ad.coefficients_[:, :4], ad.coefficients_[:, 4:]
        coef, cov = ad._bayes_parts()
        c = 1.0 if carry is None else carry  # none learned: the offset taken as constant along the run
        np.testing.assert_allclose(coef, ground + c * own, rtol=1e-12)
        post = ad.posterior_cov_
        run_cov = ad.noise_ratio_ * est.interval_.covariance("c", known=True)
        expected = post[:, :4, :4] + c * (post[:, :4, 4:] + post[:, 4:, :4]) + c**2 * post[:, 4:, 4:] + (1 - c**2) * run_cov
        np.testing.assert_allclose(cov, expected, rtol=1e-10, atol=1e-14)
        parts[carry] = ad.predict_distribution(rest).charge().total_sd_as
    assert parts[None] == parts[1.0] < parts[0.5] < parts[0.0]  # the less carries, the less the prefix narrows
