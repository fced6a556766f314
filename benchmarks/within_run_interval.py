"""The interval of the rest of a run given its prefix: the base's spread, a constant offset, the learned carry.

``terrawatt evaluate --protocol adapt`` fits the model on a ground's other runs, adapts it on the held-out run's
first T s (``scope="run"``) and scores the remainder. This benchmark runs the same folds once, caches per fold and
T what the remainder's interval is made of (the base forecast's run spread, its own-run part, the per-sample
spread, the point update's mean, the prefix's evidence ``obs, E, R, G`` and the model's learned
:attr:`~energy.models.uncertainty.IntervalModel.run_carry`), and scores interval rules on the cache:

- ``kept``: the base forecast's spread (the library before the carry);
- ``constant``: the posterior of one offset constant along the run (``carry = 1``);
- ``learned``: the library's (:meth:`energy.models.AdaptedCurrentModel.correct_distribution`, the learned carry;
  the base's spread where none was learned);
- ``learned, shrink x carry``: the point update's shrink scaled by the carry too (its mean moves);
- ``learned, no members``: the members' disagreement left out of the run spread.

Printed and written (``--out``): per ground and pooled, per T, the coverage of the total charge's 50 / 80 / 95 %
intervals (each forecast's own predictive: a Student-t where it is one), the median |z|, the mean log score (the log predictive density of the measured charge relative to
itself: a proper score, higher is better) and the total-charge error median / p90 %.

Usage::

    python benchmarks/within_run_interval.py --data ../shared/data/borealtc --cache out/within_boreal.pkl
    python benchmarks/within_run_interval.py --data generated --cache out/within_gen.pkl   # forecast_grounds' 6 x 4
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the generator beside this file

from energy import read_borealtc  # noqa: E402
from energy.evaluation.scoring import trim_to_overlap  # noqa: E402
from energy.logs import run_names  # noqa: E402
from energy.models import AdaptedCurrentModel, ModelOptions, log_currents  # noqa: E402
from energy.power import trapezoid  # noqa: E402

#: Prefix durations (s), as the adapt protocol's default.
ADAPT_SECONDS = (10.0, 20.0, 40.0)
#: A remainder shorter than this (s) is not scored (the protocol's ``min_remainder_s``).
MIN_REMAINDER_S = 10.0
#: The central levels whose coverage is scored.
LEVELS = (0.5, 0.8, 0.95)


def fold_rows(model: Any, log: Any, name: str, adapt_seconds: tuple[float, ...]) -> list[dict[str, Any]]:
    """Per T, what the held-out ``log``'s remainder forecast is made of (``model`` fitted without it)."""
    t = log.time_s
    fc = model.predict_distribution(log)
    interval = model.interval_
    out = []
    for T in adapt_seconds:
        rem = t >= t[0] + T
        if t[-1] - (t[0] + T) < MIN_REMAINDER_S or np.count_nonzero(rem) < 3:
            continue
        upd = AdaptedCurrentModel(model, scope="run").fit(log.slice(float(t[0]), float(t[0] + T)))
        out.append({"ground": str(log.meta.ground_label), "run": name, "T": float(T), "t": t, "rem": rem,
                    "truth": log_currents(log), "base": fc.mean_a, "mean": upd.correct(log, fc.mean_a),
                    "run_sd": fc.run_sd_a, "sample_sd": fc.sample_sd_a,
                    "run2": interval.run_sd_a(log, fc.mean_a, known=True) ** 2, "evidence": upd.evidence_,
                    "carry": interval.run_carry, "known": model.knows_ground(log.meta.ground_label),
                    "dof": float(fc.dof)})
    return out


def build(logs: list, seed: int, adapt_seconds: tuple[float, ...] = ADAPT_SECONDS) -> list[dict[str, Any]]:
    """Leave one run out per ground (the adapt protocol's folds) with the default estimator."""
    names = run_names(logs)
    proto = ModelOptions(seed=seed).new_model("estimator")
    rows: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for g in dict.fromkeys(lg.meta.ground_label for lg in logs):
        idx = [i for i, lg in enumerate(logs) if lg.meta.ground_label == g]
        for i in idx if len(idx) >= 2 else ():
            model = proto.clone().fit([logs[j] for j in idx if j != i])
            rows += fold_rows(model, logs[i], names[i], adapt_seconds)
            print(f"  {names[i]}: carry {model.interval_.run_carry}  ({time.perf_counter() - t0:.0f} s)", flush=True)
    return rows


def conditioned(row: dict[str, Any], carry: float | None, shrink_scale: float = 1.0,
                members: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The run spread (N, 2) and mean (N, 2) of the forecast given the prefix, the run's offset carried by ``carry``
    (None: the base's spread), over the whole log as the library computes it (a ground the model drove: ``G = 0``)."""
    mean = row["base"] + (row["mean"] - row["base"]) * shrink_scale
    held = row["run2"]
    members2 = np.maximum(row["run_sd"] ** 2 - held, 0.0) if members else 0.0
    if carry is None or row["evidence"] is None or not row["known"]:
        return np.sqrt(held + members2), mean
    obs, noise, run, ground = row["evidence"]
    t = row["t"]
    prior_sd = trapezoid(np.sqrt(held), t, axis=0)
    cross = carry * prior_sd * np.sqrt(run)
    d = trapezoid(mean - row["base"], t, axis=0)
    total = ground + run + noise
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.where(total > 0, cross / total, 0.0)
        post = np.maximum(prior_sd**2 - gain * cross, 0.0)
        factor = np.where(prior_sd > 0, (post + (gain * obs - d) ** 2) / prior_sd**2, 1.0)
    return np.sqrt(members2 + factor[None, :] * held), mean


RULES = {
    "kept": lambda r: conditioned(r, None),
    "constant": lambda r: conditioned(r, 1.0),
    "learned": lambda r: conditioned(r, r["carry"]),
    "learned, shrink x carry": lambda r: conditioned(r, r["carry"], 1.0 if r["carry"] is None else r["carry"]),
    "learned, no members": lambda r: conditioned(r, r["carry"], members=False),
}


def score(row: dict[str, Any], run_sd: np.ndarray, mean: np.ndarray) -> dict[str, float]:
    """The remainder's total charge (both sides) against the forecast (as :meth:`CurrentForecast.charge`)."""
    from scipy.stats import norm
    from scipy.stats import t as student_t

    from energy.models.forecast import central_level

    m = row["rem"]
    t = row["t"][m]
    q_true = float(np.sum(trapezoid(row["truth"][m], t, axis=0)))
    q_mean = float(np.sum(trapezoid(mean[m], t, axis=0)))
    q_run = trapezoid(run_sd[m], t, axis=0)
    q_white = np.sqrt(np.sum((row["sample_sd"][m] * np.gradient(t)[:, None]) ** 2, axis=0))
    sd = math.sqrt(float(q_run.sum()) ** 2 + float(np.sum(q_white**2)))
    z = (q_true - q_mean) / sd
    dof = row.get("dof", math.inf)  # the forecast's Student-t (a cache from before: Gaussian)
    density = float(norm.logpdf(z)) if math.isinf(dof) else float(student_t.logpdf(z, dof))
    return {"z": z, "level": float(central_level(z, dof)), "err": 100.0 * abs(q_true - q_mean) / abs(q_true),
            "log_score": density - math.log(sd / abs(q_true))}


def summary(scores: list[dict[str, float]]) -> dict[str, Any]:
    """Coverage % of the :data:`LEVELS` intervals, median |z|, mean log score, error median / p90 %, count."""
    az = np.abs([s["z"] for s in scores])
    level = np.array([s["level"] for s in scores])
    errs = [s["err"] for s in scores]
    return {"coverage": [100.0 * float(np.mean(level <= lv)) for lv in LEVELS],
            "median_abs_z": float(np.median(az)), "log_score": float(np.mean([s["log_score"] for s in scores])),
            "err_median": float(np.median(errs)), "err_p90": float(np.percentile(errs, 90)), "n": len(scores)}


def tables(rows: list[dict[str, Any]], adapt_seconds: tuple[float, ...] = ADAPT_SECONDS) -> dict[str, Any]:
    """Per rule, ground (then ``"all"``) and T: :func:`summary`."""
    grounds = sorted({r["ground"] for r in rows}) + ["all"]
    out: dict[str, Any] = {}
    for name, rule in RULES.items():
        out[name] = {}
        for g in grounds:
            out[name][g] = {}
            for T in adapt_seconds:
                sel = [r for r in rows if r["T"] == T and g in ("all", r["ground"])]
                if sel:
                    out[name][g][f"{T:g}"] = summary([score(r, *rule(r)) for r in sel])
    return out


def print_tables(out: dict[str, Any]) -> None:
    for name, by_ground in out.items():
        print(f"\n## {name}   (per T: coverage 50 / 80 / 95 %, median |z|, log score, error median / p90 %, n)")
        for g, by_t in by_ground.items():
            cells = [f"{c['coverage'][0]:3.0f} /{c['coverage'][1]:4.0f} /{c['coverage'][2]:4.0f}  "
                     f"{c['median_abs_z']:.2f}  {c['log_score']:5.2f}  {c['err_median']:4.1f} / {c['err_p90']:5.1f}  "
                     f"{c['n']}" for c in by_t.values()]
            print(f"{g:10s} " + " | ".join(cells))


def load_logs(data: str, seed: int) -> list:
    """The shared BorealTC logs (a folder), or ``"generated"``: the independent generator's 6 grounds x 4 runs."""
    if data == "generated":
        from forecast_grounds import draw_grounds, ground_logs

        return [trim_to_overlap(lg) for lg in ground_logs(draw_grounds(6, seed), 4, seed)]
    return [trim_to_overlap(lg) for lg in read_borealtc(data)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="a BorealTC folder, or 'generated'")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cache", type=Path, default=None, help="pickle of the folds' pieces (built if absent)")
    parser.add_argument("--out", type=Path, default=None, help="JSON of every number")
    args = parser.parse_args(argv)
    if args.cache is not None and args.cache.exists():
        with args.cache.open("rb") as fh:
            rows = pickle.load(fh)
    else:
        rows = build(load_logs(args.data, args.seed), args.seed)
        if args.cache is not None:
            args.cache.parent.mkdir(parents=True, exist_ok=True)
            with args.cache.open("wb") as fh:
                pickle.dump(rows, fh)
    out = tables(rows)
    print_tables(out)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
