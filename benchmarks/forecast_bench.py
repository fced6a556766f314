"""A new ground in seconds, and forecast intervals that hold: the estimator on the 42 shared BorealTC runs (issue 19).

One run measures, with the default estimator (cross-validation ensemble, seed 0):

- **Leave one run out** (train on the 41 other runs, every ground): the held-out run's
  whole-run charge interval (known ground), and adaptation on its first 20 s — the
  remainder's charge error per side with the gain baseline (one gain per side from the same
  20 s), the regime update and the Bayesian update (``method="bayes"``, ``scope="run"``),
  plus the Bayesian update's interval of the remainder.
- **Few shots on a new ground** (train on the other grounds): each run of the target ground
  adapts the model on its first 10 / 20 / 40 s and every *other* run of the ground is
  forecast whole — unadapted, gain baseline, regime, Bayesian (``scope="ground"``) — with
  the interval of the unadapted (new-ground) and the Bayesian forecast.
- **The oracle** (few shots): one gain per side fitted on every *other* run of the target
  ground, whole — a reference: what one ground-level gain could reach if every other run
  of the ground were known, not just one run's first seconds.

Coverage of the 50 / 80 / 95 % central intervals per group, median / p90 charge errors
per ground, a reliability plot (``--plot``) and all numbers as JSON (``--out``).

Usage::

    python benchmarks/forecast_bench.py --out out/forecast.json --plot out/reliability.png   # ~5 min, 2 workers
    python benchmarks/forecast_bench.py --quick --out out/forecast_quick.json               # asphalt + flooring
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

from energy import read_borealtc
from energy.evaluation import trim_to_overlap
from energy.evaluation.intervals import DEFAULT_LEVELS, IntervalRecord, coverage, plot_reliability
from energy.models import AdaptedCurrentModel, log_currents
from terrawatt_base.atomic import write_json_atomic
from terrawatt_base.dask_client import run_tasks
from terrawatt_base.errors import DataError

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "borealtc"
ADAPT_SECONDS = (10.0, 20.0, 40.0)
METHODS = ("gain", "regime", "bayes")
TARGETS = {"few_shot_median_pct": 10.0, "few_shot_p90_pct": 30.0, "coverage_80": (75.0, 85.0), "coverage_95": 90.0}
_trapezoid = getattr(np, "trapezoid", None) or np.trapz


def _estimator() -> Any:
    from energy import VibrationCurrentEstimator

    return VibrationCurrentEstimator("default", seed=0, n_threads=1)


def _charges(t: np.ndarray, cur: np.ndarray, sel: np.ndarray) -> np.ndarray:
    return _trapezoid(cur[sel], t[sel], axis=0) if np.count_nonzero(sel) > 1 else np.zeros(2)


def _err_pct(q_pred: np.ndarray, q_true: np.ndarray) -> list[float]:
    return [float(100.0 * abs(p - q) / q) if q > 0 else float("nan") for p, q in zip(q_pred, q_true)]


def _record(group: str, log: Any, run: str, fc: Any, sel: np.ndarray) -> IntervalRecord:
    q = fc.charge(sel)
    return IntervalRecord(group, str(log.meta.ground_label), run, float(_charges(log.time_s, log_currents(log), sel).sum()),
                          q.total_mean_as, q.total_sd_as)


def _updates(model: Any, prefix: Any, base_pred_prefix: np.ndarray, scope: str) -> dict[str, Any]:
    """Every update of one prefix: the gain vector and the fitted adapted models (None where the prefix cannot serve)."""
    out: dict[str, Any] = {}
    truth = log_currents(prefix)
    sel = np.ones(len(prefix), dtype=bool)
    qp, qt = _charges(prefix.time_s, base_pred_prefix, sel), _charges(prefix.time_s, truth, sel)
    out["gain"] = np.where(qp > 0, qt / np.where(qp > 0, qp, 1.0), 1.0)
    for method in ("regime", "bayes"):
        try:
            out[method] = AdaptedCurrentModel(model, method=method, scope=scope).fit(prefix)
        except DataError:
            out[method] = None
    return out


def _apply(upd: dict[str, Any], method: str, log: Any, base_fc: Any) -> Any:
    """The forecast of ``log`` under one update (None: the update could not be fitted)."""
    from energy.models.forecast import CurrentForecast

    if method == "gain":
        return CurrentForecast(log.time_s, base_fc.mean_a * upd["gain"][None, :], base_fc.run_sd_a, base_fc.sample_sd_a)
    model = upd[method]
    return None if model is None else model.correct_distribution(log, base_fc)


def loo_fold(logs: list, i: int, name: str, adapt_s: float) -> dict[str, Any]:
    """Fit on every run but ``i``; score run ``i``'s interval, and its remainder after ``adapt_s`` seconds of adaptation."""
    model = _estimator().fit([lg for j, lg in enumerate(logs) if j != i])
    log = logs[i]
    t, truth = log.time_s, log_currents(log)
    fc = model.predict_distribution(log)
    whole = np.ones(len(log), dtype=bool)
    recs = [_record("known ground, unadapted", log, name, fc, whole)]
    rows = []
    whole_row = {"ground": str(log.meta.ground_label), "run": name,
                 "unadapted": _err_pct(_charges(t, fc.mean_a, whole), _charges(t, truth, whole))}
    rest = t >= t[0] + adapt_s
    if t[-1] - (t[0] + adapt_s) >= 10.0:
        prefix = log.slice(float(t[0]), float(t[0] + adapt_s))
        upd = _updates(model, prefix, fc.mean_a[~rest], "run")
        q_true = _charges(t, truth, rest)
        row = {"ground": str(log.meta.ground_label), "run": name, "unadapted": _err_pct(_charges(t, fc.mean_a, rest), q_true)}
        for method in METHODS:
            f = _apply(upd, method, log, fc)
            row[method] = _err_pct(_charges(t, (fc if f is None else f).mean_a, rest), q_true)
            if method == "bayes" and f is not None:
                recs.append(_record(f"known ground, after {adapt_s:g} s", log, name, f, rest))
        rows.append(row)
    return {"rows": rows, "whole": whole_row, "records": [r.to_dict() for r in recs]}


def few_shot_fold(logs: list, names: list[str], ground: str) -> dict[str, Any]:
    """Fit on the other grounds; adapt on each target run's first seconds, forecast every other target run whole."""
    model = _estimator().fit([lg for lg in logs if str(lg.meta.ground_label) != ground])
    idx = [i for i, lg in enumerate(logs) if str(lg.meta.ground_label) == ground]
    fcs = {i: model.predict_distribution(logs[i]) for i in idx}
    recs, rows = [], []
    q_true = {i: _charges(logs[i].time_s, log_currents(logs[i]), np.ones(len(logs[i]), dtype=bool)) for i in idx}
    q_pred = {i: _charges(logs[i].time_s, fcs[i].mean_a, np.ones(len(logs[i]), dtype=bool)) for i in idx}
    oracle = {}  # the best one gain per side could do: fitted on every *other* run of the ground, whole
    for b in idx:
        gain = np.mean([q_true[i] / q_pred[i] for i in idx if i != b], axis=0)
        oracle[b] = _err_pct(q_pred[b] * gain, q_true[b])
    for i in idx:
        whole = np.ones(len(logs[i]), dtype=bool)
        recs.append(_record("new ground, unadapted", logs[i], names[i], fcs[i], whole))
    for a in idx:
        ta = logs[a].time_s
        for T in ADAPT_SECONDS:
            if logs[a].duration_s < T:
                continue
            prefix = logs[a].slice(float(ta[0]), float(ta[0] + T))
            upd = _updates(model, prefix, fcs[a].mean_a[ta < ta[0] + T], "ground")
            for b in idx:
                if b == a:
                    continue
                log, fc = logs[b], fcs[b]
                whole = np.ones(len(log), dtype=bool)
                q_true = _charges(log.time_s, log_currents(log), whole)
                row = {"ground": ground, "adapt_run": names[a], "run": names[b], "T": T,
                       "unadapted": _err_pct(_charges(log.time_s, fc.mean_a, whole), q_true),
                       "oracle": oracle[b]}
                for method in METHODS:
                    f = _apply(upd, method, log, fc)
                    row[method] = _err_pct(_charges(log.time_s, (fc if f is None else f).mean_a, whole), q_true)
                    if method == "bayes" and f is not None:
                        recs.append(_record(f"new ground, after {T:g} s", log, names[b], f, whole))
                rows.append(row)
    return {"rows": rows, "records": [r.to_dict() for r in recs]}


def _stats(values: list[float]) -> str:
    v = np.array([x for x in values if np.isfinite(x)])
    return f"{np.median(v):.1f} / {np.percentile(v, 90):.1f}" if v.size else "-"


def summarise(rows: list[dict[str, Any]], key_T: float | None) -> dict[str, dict[str, list[float]]]:
    """Per ground (and "all"), per method: median and p90 of the per-side charge errors (%)."""
    sel = [r for r in rows if key_T is None or r.get("T") == key_T]
    out: dict[str, dict[str, list[float]]] = {}
    for g in [*dict.fromkeys(r["ground"] for r in sel), "all"]:
        rs = [r for r in sel if g == "all" or r["ground"] == g]
        out[g] = {}
        for m in ("unadapted", *METHODS, "oracle"):
            if not any(m in r for r in rs):
                continue
            v = np.array([x for r in rs for x in r[m] if np.isfinite(x)])
            out[g][m] = [float(np.median(v)), float(np.percentile(v, 90)), int(v.size)] if v.size else [np.nan, np.nan, 0]
    return out


def _table(title: str, summary: dict[str, dict[str, list[float]]]) -> None:
    cols = [m for m in ("unadapted", *METHODS, "oracle") if m in next(iter(summary.values()))]
    print(f"\n{title}  (per-side whole-charge error %, median / p90; run-sides)")
    print(f"{'ground':<10}" + "".join(f"{m:>16}" for m in cols) + f"{'n':>6}")
    for g, row in summary.items():
        print(f"{g:<10}" + "".join(f"{row[m][0]:>8.1f} /{row[m][1]:>6.1f}" for m in cols) + f"{row['unadapted'][2]:>6d}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--out", type=Path, default=Path("out/forecast_bench.json"))
    ap.add_argument("--plot", type=Path, default=None, help="write the reliability plot (PNG)")
    ap.add_argument("--workers", type=int, default=2, help="local dask workers, 1 thread each (0: in this process)")
    ap.add_argument("--quick", action="store_true", help="asphalt and flooring only")
    args = ap.parse_args(argv)
    logs = [trim_to_overlap(lg) for lg in read_borealtc(args.data)]
    if args.quick:
        logs = [lg for lg in logs if lg.meta.ground_label in ("asphalt", "flooring")]
    names = [f"{lg.meta.ground_label}/{Path(str(lg.meta.source)).stem}" for lg in logs]
    grounds = list(dict.fromkeys(str(lg.meta.ground_label) for lg in logs))
    client = cluster = None
    if args.workers > 0:
        from distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    t0 = time.perf_counter()
    tasks = [(few_shot_fold, (logs, names, g)) for g in grounds]
    tasks += [(loo_fold, (logs, i, names[i], 20.0)) for i in range(len(logs))]
    try:
        results = list(run_tasks(tasks, client=client, progress=True, description="folds"))
    finally:
        if client is not None:
            client.close()
            cluster.close()
    wall = time.perf_counter() - t0
    few = [r for res in results[: len(grounds)] for r in res["rows"]]
    loo = [r for res in results[len(grounds):] for r in res["rows"]]
    loo_whole = [res["whole"] for res in results[len(grounds):]]
    records = [IntervalRecord(**{k: v for k, v in d.items() if k != "z"}) for res in results for d in res["records"]]
    few_summary = {f"{T:g} s": summarise(few, T) for T in ADAPT_SECONDS}
    loo_summary = summarise(loo, None)
    whole_summary = summarise(loo_whole, None)
    cov = coverage(records, DEFAULT_LEVELS)
    for T in ADAPT_SECONDS:
        _table(f"Few shots on a new ground, T = {T:g} s", few_summary[f"{T:g} s"])
    _table("Leave one run out, the held-out run whole (no adaptation)", whole_summary)
    _table("Leave one run out, 20 s of the held-out run, scored on its remainder", loo_summary)
    print("\nCoverage of held-out whole-run charge (both sides):")
    print(f"{'group':<30}" + "".join(f"{k:>9}" for k in ("50 %", "80 %", "95 %", "n", "median |z|")))
    for g, row in cov.items():
        print(f"{g:<30}" + "".join(f"{100 * row[k]:>8.1f}%" for k in ("50 %", "80 %", "95 %"))
              + f"{row['n']:>9.0f}{row['median |z|']:>10.2f}")
    print(f"\nwall {wall:.1f} s on {os.cpu_count()} cores ({args.workers} workers)")
    if args.plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5.5, 5.0))
        plot_reliability(records, ax, title="Estimator intervals on held-out BorealTC runs")
        args.plot.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(args.plot, dpi=120, bbox_inches="tight")
        print(f"wrote {args.plot}")
    write_json_atomic(args.out, {
        "benchmark": "forecast_bench", "targets": TARGETS, "wall_s": wall, "workers": args.workers,
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "few_shot": few_summary, "loo_whole": whole_summary, "loo_adapt_20s": loo_summary, "coverage": cov,
        "few_shot_rows": few, "loo_rows": loo, "records": [r.to_dict() for r in records],
    })
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
