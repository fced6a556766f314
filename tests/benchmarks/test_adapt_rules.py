"""benchmarks/adapt_rules.py: the cached charges give exactly what the library's update forecasts."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "energy"))  # interval_samples

import adapt_rules  # noqa: E402  (benchmarks/ is on sys.path: tests/conftest.py)
from interval_samples import fit_two_ground_estimator, interval_log  # noqa: E402

from energy import InteractionLog, LogMeta  # noqa: E402
from energy.models import AdaptedCurrentModel, log_currents  # noqa: E402
from energy.models.forecast import central_level  # noqa: E402


@pytest.fixture(scope="module")
def fold():
    ar = adapt_rules
    est, _ = fit_two_ground_estimator()
    runs = [interval_log(40 + s, "c", vibration=0.5, offset_a=1.0 + s) for s in range(3)]  # a ground never driven
    return ar, est, runs, ar.fold_cache(est, runs, ["c/0", "c/1", "c/2"], (20.0,))


@pytest.mark.parametrize(("method", "shrink"), [("regime", "prior"), ("regime", "evidence"), ("regime", "none"),
                                                ("partition", "none"), ("partition", "prior")])
def test_cached_charges_equal_the_library_update(fold, method, shrink):
    ar, est, runs, cache = fold
    rule = {("regime", "prior"): ar.rule_prior, ("regime", "evidence"): ar.rule_evidence,
            ("regime", "none"): ar.rule_none, ("partition", "none"): ar.rule_partition,
            ("partition", "prior"): ar.rule_partition_prior}[method, shrink]
    rows = ar.charges(rule, cache)
    assert len(rows) == 6 and ar.clamp_effect(cache) < 1e-9
    for r in rows:
        upd = AdaptedCurrentModel(est, method=method, shrink=shrink, scope="ground").fit(runs[r["a"]].slice(0.0, 20.0))
        b = runs[r["b"]]
        q = float(np.sum(np.trapezoid(upd.predict(b), b.time_s, axis=0)))
        q_true = float(np.sum(np.trapezoid(log_currents(b), b.time_s, axis=0)))
        assert r["err"] == pytest.approx(100.0 * abs(q - q_true) / q_true, abs=1e-6)
        q0 = float(np.sum(np.trapezoid(est.predict(b), b.time_s, axis=0)))
        assert r["base"] == pytest.approx(100.0 * abs(q0 - q_true) / q_true, abs=1e-6)


def test_cached_regime_gains_equal_the_library_update(fold):
    ar, est, runs, cache = fold
    rows = ar.charges(ar.rule_regime_gain_prior, cache)
    assert len(rows) == 6
    for r in rows:
        upd = AdaptedCurrentModel(est, method="regime_gain", scope="ground").fit(runs[r["a"]].slice(0.0, 20.0))
        b = runs[r["b"]]
        q = float(np.sum(np.trapezoid(upd.predict(b), b.time_s, axis=0)))
        q_true = float(np.sum(np.trapezoid(log_currents(b), b.time_s, axis=0)))
        assert r["err"] == pytest.approx(100.0 * abs(q - q_true) / q_true, abs=1e-6)
        assert np.any(upd.coefficients_ != 0)  # the update moved: the check compares two non-trivial charges


def test_cached_intervals_equal_the_library_forecast(fold):
    ar, est, runs, cache = fold
    rows = ar.interval_rows(cache, ar.rule_partition_prior, ar.interval_given_prefix)
    kept = ar.interval_rows(cache, ar.rule_partition_prior, ar.interval_kept)
    pairs = [(p["a"], b) for p in cache["prefixes"] for b in range(len(runs)) if b != p["a"]]
    assert len(rows) == len(pairs) == 6
    for (a, b), r, k in zip(pairs, rows, kept):
        upd = AdaptedCurrentModel(est, scope="ground").fit(runs[a].slice(0.0, 20.0))
        fc = upd.predict_distribution(runs[b]).charge()
        q_true = float(np.sum(np.trapezoid(log_currents(runs[b]), runs[b].time_s, axis=0)))
        assert r["z"] == pytest.approx((q_true - fc.total_mean_as) / fc.total_sd_as, rel=1e-6)
        assert r["level"] == pytest.approx(float(central_level(r["z"], fc.dof)), abs=1e-12)
        base = est.predict_distribution(runs[b]).charge()
        assert k["z"] == pytest.approx((q_true - fc.total_mean_as) / base.total_sd_as, rel=1e-6)
    table = ar.interval_table({"outer": {"c": cache}}, ar.rule_partition_prior, (20.0,))
    assert table["c"]["given the prefix"]["20"] == ar.coverage(rows)
    assert len(table["all"]["unadapted"]) == len(ar.LEVELS) + 2  # and the median |z|, the mean log score


def test_the_cached_normal_equations_refit_the_update(fold):
    ar, _, _, cache = fold
    for p in cache["prefixes"]:
        np.testing.assert_allclose(ar.ridge(p, 20.0), p["coef"], rtol=1e-8, atol=1e-10)
        assert not np.allclose(ar.ridge(p, 200.0), p["coef"])  # a larger penalty moves less


def test_the_scale_candidate_scales_by_the_prefix_standardised_charge_and_adds_a_degree(fold):
    ar, _, _, cache = fold
    p, rb = cache["prefixes"][0], cache["runs"][1]
    coef = ar._resolve(ar.rule_partition_prior(p, cache))[0]
    g_prefix, own_prefix, dof = ar.interval_given_prefix(p, coef, rb)
    g_scale, own_scale, dof_scale = ar.interval_given_scale(p, coef, rb)
    assert np.isfinite(dof) and np.all(own_prefix == 1.0)
    kappa = (dof + p["obs"] ** 2 / (p["G"] + p["R"] + p["E"])) / (dof + 1.0)
    np.testing.assert_allclose(own_scale, kappa)
    assert dof_scale == dof + 1.0
    gaussian = {**rb, "spread": {**rb["spread"], "dof": float("inf")}}  # a file from before the counts: no update
    assert ar.interval_given_scale(p, coef, gaussian)[2] == float("inf")
    np.testing.assert_array_equal(ar.interval_given_scale(p, coef, gaussian)[0], g_prefix)
    assert not np.allclose(g_scale, g_prefix)  # the candidate differs from the library's where the dof is finite


def test_the_unadapted_rule_is_the_base_and_harm_is_measured_against_it(fold):
    ar, _, _, cache = fold
    rows = ar.charges(ar.rule_unadapted, cache)
    assert all(r["err"] == pytest.approx(r["base"]) for r in rows)
    assert ar.harm(ar.rule_unadapted, [cache], (20.0,))[0] == pytest.approx(0.0)


def test_report_prints_and_writes_every_rule(fold, tmp_path, capsys):
    ar, _, _, cache = fold
    ar.report({"outer": {"c": cache, "d": cache}, "inner": {"c": {"c": cache}}}, (20.0,), tmp_path / "rules.json")
    text = capsys.readouterr().out
    assert "prior, moving" in text and "scale (LOGO)" in text and "gain" in text
    assert "hierarchical, prior" in text and "overlap, prior" in text and "switch (others)" in text
    assert "partition, once" in text and "once, levels" in text
    assert (tmp_path / "rules.json").exists()


def _entry(turning: np.ndarray, residual_a: float = -1.0) -> dict:
    """A prefix entry of the cache (its normal equations and basis integrals) for 0.1-s samples of ``turning`` (rad/s,
    0 straight) at 0.5 m/s whose residual current is ``residual_a`` on both sides; spreads that keep half of it."""
    t = np.arange(turning.size) * 0.1
    n = t.size
    log = InteractionLog(t, np.full(n, 0.5), turning, np.ones(n), np.ones(n), t, np.full(n, 9.81),
                         meta=LogMeta(source="c/0", ground_label="c", robot="husky_a200"))
    ar = adapt_rules
    normal = ar.normal_equations(log, np.full((n, 2), residual_a), False)
    p = {"normal": normal, "xint": ar.basis_integrals(log), "G": np.ones(2), "R": np.full(2, 0.5),
         "E": np.full(2, 0.5), "obs": np.full(2, residual_a * t[-1])}
    p["coef"] = ar.ridge(p)
    return p


def _levels(coef: np.ndarray) -> np.ndarray:
    """Per side the straight level (offset) and the turning level (offset + turning) of regime coefficients."""
    return np.stack([coef[:, 0], coef[:, 0] + coef[:, 2]], axis=1)


def test_the_hierarchical_level_is_the_partition_where_the_prefix_drove_one_regime():
    ar = adapt_rules
    p = _entry(np.zeros(200))  # 20 s straight
    assert ar.balance(p["xint"]) == 0.0
    np.testing.assert_allclose(ar.hierarchical_coef(p), ar.partition_coef(p), atol=1e-12)
    assert np.allclose(_levels(ar.hierarchical_coef(p))[:, 1], 0.0)  # the turns keep no correction
    assert np.all(_levels(p["coef"])[:, 1] < -0.1)  # the default moves them with the straight offset


def test_the_hierarchical_level_shares_strength_where_the_prefix_drove_both():
    ar = adapt_rules
    p = _entry(np.r_[np.zeros(100), np.full(100, 3.0)])  # 10 s straight, 10 s turning
    assert ar.balance(p["xint"]) == pytest.approx(1.0, abs=1e-6)
    hier, part = _levels(ar.hierarchical_coef(p)), _levels(ar.partition_coef(p))
    assert np.all(hier < part - 0.01) and np.all(hier > -1.0)  # each level nearer the residual, never beyond it


def test_the_overlap_rule_moves_a_run_as_the_default_only_where_it_drove_like_the_prefix():
    ar = adapt_rules
    p = _entry(np.r_[np.zeros(150), np.full(50, 3.0)])
    alike = {"xint": p["xint"]}
    straight = {"xint": _entry(np.zeros(200))["xint"]}
    default = ar.rule_prior(p, {})
    moved = np.sum(default * straight["xint"], axis=1)  # the default's correction of a straight run's charge (A s)
    assert np.all(np.abs(moved) > 0.1)
    for rule in (ar.rule_overlap_prior, ar.rule_overlap_regime_prior):
        at = rule(p, {})
        np.testing.assert_allclose(at(alike), default, atol=1e-9)
        # the prefix drove straight 3/4 of its time: a run that only drives straight is moved 3/4 as far
        np.testing.assert_allclose(np.sum(at(straight) * straight["xint"], axis=1), 0.75 * moved, rtol=0.01)


def test_the_switch_grid_runs_from_the_default_to_the_partition():
    ar = adapt_rules
    p = _entry(np.r_[np.zeros(150), np.full(50, 3.0)])
    np.testing.assert_allclose(ar.switch_rule(ar.SWITCH_GRID[0])(p, {}), ar.rule_prior(p, {}))
    np.testing.assert_allclose(ar.switch_rule(ar.SWITCH_GRID[-1])(p, {}), ar.rule_partition_prior(p, {}))
    assert not np.allclose(ar.rule_prior(p, {}), ar.rule_partition_prior(p, {}))


def test_shrinking_once_is_the_posterior_mean_of_the_offset_carried_by_the_ground_share():
    ar = adapt_rules
    p = _entry(np.zeros(200))  # 20 s straight at 0.5 m/s, residual -1 A: the offset and |v| columns move as one level
    seconds, weight = p["xint"][0, 0], p["normal"][0][0][0, 0]
    np.testing.assert_allclose(ar.once_penalty(p), 0.5 * seconds / 1.5)  # E T / (G + R)
    level = lambda coef: coef[:, 0] + 0.5 * coef[:, 1]  # noqa: E731  (the correction of a straight run at 0.5 m/s)
    # the ridge along the level's direction (1, 0.5): the posterior mean of g + u, then the ground's share G / (G + R)
    pen = 0.5 * seconds / 1.5
    expected = -1.0 * 1.25 * weight / (1.25 * weight + pen) * (1.0 / 1.5)
    np.testing.assert_allclose(level(ar.rule_once(p, {})), expected, rtol=1e-9)
    default = level(ar.rule_prior(p, {}))  # the 20-s ridge, then G / (G + R + E): shrunk twice
    assert np.all(default > expected + 0.1)
    np.testing.assert_allclose(level(ar.rule_partition_once(p, {})), expected, rtol=1e-9)  # straight only: one level
    no_ground = dict(p, G=np.zeros(2))
    np.testing.assert_allclose(ar.rule_once(no_ground, {}), ar.rule_evidence(no_ground, {}))
