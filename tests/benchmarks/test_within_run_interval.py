"""benchmarks/within_run_interval.py: its cached pieces give exactly the library's within-run interval."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "energy"))  # interval_samples

import within_run_interval as wr  # noqa: E402  (benchmarks/ is on sys.path: tests/conftest.py)
from interval_samples import fit_two_ground_estimator, with_carry  # noqa: E402

from energy.models import AdaptedCurrentModel  # noqa: E402


@pytest.fixture(scope="module")
def fold():
    fitted, train = fit_two_ground_estimator()
    est = with_carry(fitted, 0.6)  # its runs' offsets are noise only: no carry learned
    run = train[1]  # a ground the model drove, as in the adapt protocol
    own = est.interval_.run_sd_a(run, est.predict(run), known=True)
    shift = 2.0 * np.sqrt(np.median(own**2, axis=0))  # an offset of two of its learned run spreads
    shifted = dataclasses.replace(run, current_left_a=run.current_left_a + shift[0],
                                  current_right_a=run.current_right_a + shift[1])
    return est, shifted, wr.fold_rows(est, shifted, "a/1", (10.0, 20.0))


def test_the_learned_rule_is_the_library_interval_and_kept_is_the_base(fold):
    est, log, rows = fold
    assert [r["T"] for r in rows] == [10.0, 20.0] and est.interval_.run_carry == 0.6
    base = est.predict_distribution(log)
    for r in rows:
        upd = AdaptedCurrentModel(est, scope="run").fit(log.slice(0.0, r["T"]))
        lib = upd.predict_distribution(log)
        run_sd, mean = wr.RULES["learned"](r)
        np.testing.assert_allclose(run_sd, lib.run_sd_a, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(mean, lib.mean_a, rtol=1e-12)
        charge = lib.charge(r["rem"])
        q_true = float(np.sum(np.trapezoid(wr.log_currents(log)[r["rem"]], log.time_s[r["rem"]], axis=0)))
        assert wr.score(r, run_sd, mean)["z"] == pytest.approx((q_true - charge.total_mean_as) / charge.total_sd_as,
                                                              rel=1e-9)
        kept, _ = wr.RULES["kept"](r)
        np.testing.assert_allclose(kept, base.run_sd_a, rtol=1e-12)
        constant, _ = wr.RULES["constant"](r)
        assert np.sum(constant) < np.sum(run_sd) <= np.sum(kept) + 1e-9  # carry < 1 conditions less than a constant


def test_the_tables_count_every_row_and_score_coverage(fold):
    _, _, rows = fold
    out = wr.tables(rows, (10.0, 20.0))
    assert set(out) == set(wr.RULES)
    cell = out["learned"]["all"]["20"]
    assert cell["n"] == 1 and all(c in (0.0, 100.0) for c in cell["coverage"])
    assert cell["coverage"] == sorted(cell["coverage"])  # a wider interval covers at least as much
