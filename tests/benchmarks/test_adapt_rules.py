"""benchmarks/adapt_rules.py: the cached charges give exactly what the library's update forecasts."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "energy"))  # interval_samples

import adapt_rules  # noqa: E402  (benchmarks/ is on sys.path: tests/conftest.py)
from interval_samples import fit_two_ground_estimator, interval_log  # noqa: E402

from energy.models import AdaptedCurrentModel, log_currents  # noqa: E402


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


def test_the_cached_normal_equations_refit_the_update(fold):
    ar, _, _, cache = fold
    for p in cache["prefixes"]:
        np.testing.assert_allclose(ar.ridge(p, 20.0), p["coef"], rtol=1e-8, atol=1e-10)
        assert not np.allclose(ar.ridge(p, 200.0), p["coef"])  # a larger penalty moves less


def test_the_unadapted_rule_is_the_base_and_harm_is_measured_against_it(fold):
    ar, _, _, cache = fold
    rows = ar.charges(ar.rule_unadapted, cache)
    assert all(r["err"] == pytest.approx(r["base"]) for r in rows)
    assert ar.harm(ar.rule_unadapted, [cache], (20.0,))[0] == pytest.approx(0.0)


def test_report_prints_and_writes_every_rule(fold, tmp_path, capsys):
    ar, _, _, cache = fold
    ar.report({"outer": {"c": cache}, "inner": {"c": {"c": cache}}}, (20.0,), tmp_path / "rules.json")
    text = capsys.readouterr().out
    assert "prior, moving" in text and "scale (LOGO)" in text and "gain" in text
    assert (tmp_path / "rules.json").exists()
