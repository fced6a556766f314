"""Diagnosis on real robot logs: the BorealTC Husky runs, leave-runs-out, physics models and the estimator.

The BorealTC logs (``../shared/data/borealtc`` beside the repository, or ``--data``) of each
ground are split by run: the model under test is fitted on the even-numbered runs and the
diagnosis (``energy.diagnose(..., split="runs")``: effects fitted on some of the remaining
runs, scored on the others) runs on the odd-numbered ones, so neither the model nor an
effect is ever scored on a run it was fitted on. Models under test:

- ``physics as given``: the CLI's default (``terrawatt diagnose --model physics``), the
  Husky and ground presets with nothing fitted;
- ``physics``: ``PhysicsCurrentModel(robot="husky", ground=<the ground's preset>)`` with its
  default fitted coefficients (rolling resistance, lateral friction, idle current, rest level),
  per ground, fitted on the even runs (``--calibration-data`` in the CLI);
- ``physics -turning_resistance`` / ``physics -coulomb_friction``: the same with one physics
  effect switched off (deliberately reduced: the diagnosis should find it);
- ``physics (asphalt preset)`` on all grounds at once: one ground's coefficients for every
  run, so per-ground rolling resistance is a candidate;
- ``estimator``: the vibration estimator (``new_current_model("estimator")``), trained on the
  fit runs of the grounds given by ``--estimator-grounds`` (training takes minutes).

It prints one row per (model, ground): the held-out gap before (whole-set charge error %,
median 8 s section error %, RMSE A), the rest samples' mean absolute error (A), where it lies
(the two slices of largest net gap), the effects chosen (``?`` marks one whose fitted values
are flagged implausible), the held-out shrink of the squared current gap (%), the gap after,
and what is left unexplained; then writes everything (rankings with intervals, fitted values
beside their priors, flags, verdicts) as JSON.

Usage::

    python benchmarks/diagnosis_real.py --out diagnosis_real.json            # all cases, ~minutes
    python benchmarks/diagnosis_real.py --no-estimator --workers 2
    python benchmarks/diagnosis_real.py --grounds FLOORING --estimator-grounds FLOORING
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from energy import PhysicsCurrentModel, new_current_model, read_borealtc
from energy.diagnosis import FitSettings, diagnose
from energy.diagnosis.gap import largest_slices
from energy.logs import rest_samples
from energy.models.base import log_currents
from energy.physics import EFFECTS
from terrawatt_base.atomic import write_json_atomic

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "borealtc"
#: Ground folder -> the physics ground preset of that ground.
PRESETS = {"asphalt": "asphalt", "flooring": "flooring", "snow": "snow"}
#: Physics effects switched off in the reduced variants.
REDUCED = ("turning_resistance", "coulomb_friction")
#: Regime dimensions shown as "where the gap lies".
WHERE = ("turning", "speed", "acceleration", "ground", "side")
DRIVE_EFFECTS = tuple(e for e in EFFECTS if e not in ("sensor", "control"))


def _halves(logs: list[Any]) -> tuple[list[Any], list[Any]]:
    """Fit runs (even positions) and diagnosis runs (odd positions) of each ground."""
    fit, diag = [], []
    by_ground: dict[str, list[Any]] = {}
    for log in logs:
        by_ground.setdefault(str(log.meta.ground_label), []).append(log)
    for runs in by_ground.values():
        fit += runs[0::2]
        diag += runs[1::2]
    return fit, diag


def _model(kind: str, ground: str, without: str | None, seed: int) -> Any:
    if kind == "estimator":
        return new_current_model("estimator", seed=seed, n_threads=1)
    effects = None if without is None else tuple(e for e in DRIVE_EFFECTS if e != without)
    if kind == "preset":
        return PhysicsCurrentModel(robot="husky", ground=ground, effects=effects, fit_parameters=())
    return PhysicsCurrentModel(robot="husky", ground=ground, effects=effects)


def _where(d: Any, n: int = 2) -> list[dict[str, Any]]:
    rows = [r for r in largest_slices(d.localisation, 50) if r.dimension in WHERE][:n]
    return [{"dimension": r.dimension, "label": r.label, "gap_mah": r.gap_mah, "gap_pct": r.gap_pct,
             "gap_interval_mah": list(r.gap_interval_mah), "duration_s": r.duration_s, "n_runs": r.n_runs}
            for r in rows]


def rest_error_a(model: Any, logs: list[Any]) -> dict[str, Any]:
    """The model's error on the logs' rest samples (wheels still, not accelerating): count, mean per side, MAE."""
    err = [model.predict(log)[m] - log_currents(log)[m] for log in logs for m in [rest_samples(log)] if m.any()]
    if not err:
        return {"n": 0, "mean_a": [float("nan")] * 2, "mae_a": float("nan")}
    e = np.concatenate(err)
    return {"n": int(e.shape[0]), "mean_a": e.mean(axis=0).tolist(), "mae_a": float(np.abs(e).mean())}


def run_case(case: dict[str, Any], data: str, seed: int, n_bootstrap: int) -> dict[str, Any]:
    """Fit the case's model on the fit runs, diagnose it on the diagnosis runs; a JSON-ready row."""
    grounds = None if case["ground"] == "all" else [case["ground"].upper()]
    logs = read_borealtc(data, grounds=grounds)
    fit_logs, diag_logs = _halves(logs)
    if case["runs"] is not None:  # a subset (the estimator): the first runs of each half
        fit_logs, diag_logs = fit_logs[:case["runs"]], diag_logs[:case["runs"]]
    t0 = time.perf_counter()
    model = _model(case["kind"], case["preset"], case["without"], seed).fit(fit_logs)
    t_fit = time.perf_counter() - t0
    t0 = time.perf_counter()
    d = diagnose(model, diag_logs, settings=FitSettings(split="runs", seed=seed, n_bootstrap=n_bootstrap))
    t_diag = time.perf_counter() - t0
    shrink = d.current.waterfall[-1].shrink_pct
    by_name = {s.name: s for s in d.current.ranking}
    return {
        "model": case["label"], "ground": case["ground"], "n_fit_runs": len(fit_logs), "n_runs": len(diag_logs),
        "n_samples": sum(len(g) for g in diag_logs), "fit_s": t_fit, "diagnose_s": t_diag,
        "before": d.current.before.to_dict(), "after": d.current.after.to_dict(), "where": _where(d),
        "rest": rest_error_a(model, diag_logs),
        "doubtful": [n for n in d.current.chosen if getattr(by_name[n], "doubtful", False)],
        "chosen": list(d.current.chosen), "learned_chosen": any(s.kind == "learned" for s in d.current.ranking if s.name in d.current.chosen),
        "shrink_pct": shrink, "unexplained_pct": 100.0 - shrink,
        "top": [{"name": s.name, "kind": s.kind, "shrink_pct": s.shrink_pct,
                 "interval_pct": list(s.shrink_interval_pct), "parameters": dict(s.parameters),
                 "flags": list(getattr(s, "flags", ()))} for s in d.current.ranking[:5]],
        "waterfall": [w.to_dict() for w in d.current.waterfall], "verdict": list(d.verdict), "skipped": dict(d.current.skipped),
        "ties": [t.to_dict() for t in d.ties],
        "separating_drives": [x.to_dict() for x in d.separating_drives],
        "more_data": {k: v for k, v in d.more_data.items() if k != "drive"}
        | ({"drive": {"description": d.more_data["drive"]["drive"]["description"],
                      "duration_s": d.more_data["drive"]["drive"]["duration_s"],
                      "repeats": d.more_data["drive"]["repeats"]}} if d.more_data.get("drive") else {}),
    }


def cases(grounds: list[str], estimator_grounds: list[str], estimator_runs: int | None) -> list[dict[str, Any]]:
    """The (model, ground) cases."""
    out = []
    for g in grounds:
        preset = PRESETS.get(g, "asphalt")
        out.append({"label": "physics as given", "kind": "preset", "ground": g, "preset": preset, "without": None,
                    "runs": None})
        out.append({"label": "physics", "kind": "physics", "ground": g, "preset": preset, "without": None, "runs": None})
        for w in REDUCED:
            out.append({"label": f"physics -{w}", "kind": "physics", "ground": g, "preset": preset, "without": w,
                        "runs": None})
    if len(grounds) > 1:
        out.append({"label": "physics (asphalt preset)", "kind": "physics", "ground": "all", "preset": "asphalt",
                    "without": None, "runs": None})
    for g in estimator_grounds:
        out.append({"label": "estimator", "kind": "estimator", "ground": g, "preset": "asphalt", "without": None,
                    "runs": estimator_runs})
    return out


def _where_text(where: list[dict[str, Any]]) -> str:
    return "; ".join(f"{w['dimension']} {w['label']} {w['gap_mah']:+.0f} mAh" for w in where)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA, help="BorealTC-layout directory")
    ap.add_argument("--grounds", nargs="+", default=["ASPHALT", "FLOORING", "SNOW"], help="ground folders")
    ap.add_argument("--estimator-grounds", nargs="*", default=["FLOORING"],
                    help="grounds on which the estimator is trained and diagnosed (none: skip it)")
    ap.add_argument("--estimator-runs", type=int, default=None,
                    help="at most this many fit and diagnosis runs for the estimator (default all of the ground)")
    ap.add_argument("--no-estimator", action="store_true", help="skip the estimator")
    ap.add_argument("--n-bootstrap", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1, help="processes running cases in parallel")
    ap.add_argument("--out", type=Path, default=None, help="write the rows as JSON here")
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        print(f"no BorealTC data at {args.data}; give --data DIR", file=sys.stderr)
        return 2
    grounds = [g.lower() for g in args.grounds]
    est = [] if args.no_estimator else [g.lower() for g in args.estimator_grounds]
    todo = cases(grounds, est, args.estimator_runs)
    t0 = time.perf_counter()
    params = [(c, str(args.data), args.seed, args.n_bootstrap) for c in todo]
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            rows = list(pool.map(run_case, *zip(*params)))
    else:
        rows = [run_case(*p) for p in params]
    wall = time.perf_counter() - t0

    print(f"{'model':<28} {'ground':<9} {'runs':>4} | {'before: Q %':>11} {'sect %':>6} {'RMSE':>5} {'rest':>5} | "
          f"{'shrink %':>8} | {'after: Q %':>10} {'sect %':>6} {'RMSE':>5} | chosen; where the gap lies")
    for r in rows:
        b, a = r["before"], r["after"]
        chosen = ", ".join(n + ("?" if n in r["doubtful"] else "") for n in r["chosen"]) or "-"
        print(f"{r['model']:<28} {r['ground']:<9} {r['n_runs']:>4} | {b['charge_error_pct']:>11.1f} "
              f"{b['section_error_pct']:>6.1f} {b['rmse_a']:>5.2f} {r['rest']['mae_a']:>5.2f} | {r['shrink_pct']:>8.1f} | "
              f"{a['charge_error_pct']:>10.1f} {a['section_error_pct']:>6.1f} {a['rmse_a']:>5.2f} | "
              f"{chosen}; {_where_text(r['where'])}")
    print("\nbest candidates alone (held-out shrink %, 95 % interval):")
    for r in rows:
        top = ", ".join(f"{t['name']} {t['shrink_pct']:.1f} [{t['interval_pct'][0]:.1f}, {t['interval_pct'][1]:.1f}]"
                        for t in r["top"][:3])
        print(f"  {r['model']:<28} {r['ground']:<9} {top}")
    print("\nwhat would settle the top candidate (significant: settled on these runs; otherwise the runs like these "
          "that would make it significant, and the test drive that would show it):")
    for r in rows:
        more, ties = r["more_data"], r["ties"]
        if r["chosen"]:
            text = f"settled: {r['chosen'][0]} significant on {r['n_runs']} runs"
            if ties:
                text += "; tied with " + ", ".join(ties[0]["alternatives"])
        elif more:
            need = more["units_needed"]
            text = (f"{more['effect']} +{more['mean_gain_pct']:.1f} points (spread {more['unit_sd_pct']:.1f}): "
                    + (f"~{need} runs" if need is not None else "more runs would not do (below 2 points)"))
            if more.get("drive"):
                text += f", or {more['drive']['repeats']} x {more['drive']['description']}"
        else:
            text = "no candidate"
        print(f"  {r['model']:<28} {r['ground']:<9} {text}")
    print(f"\n{len(rows)} cases, wall {wall:.0f} s, {args.workers} worker(s), {os.cpu_count()} cores")
    if args.out is not None:
        write_json_atomic(args.out, {"protocol": "per ground: model fitted on the even-numbered runs, diagnosed "
                                                 "(split='runs') on the odd-numbered runs",
                                     "seed": args.seed, "n_bootstrap": args.n_bootstrap, "wall_s": wall, "rows": rows})
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
