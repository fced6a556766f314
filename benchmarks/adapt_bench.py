"""Adaptation and evaluation-speed benchmark on the BorealTC logs (issue 11).

Two parts, each printed as a table and written to one JSON file (``--out``):

- ``speed``: leave-one-run-out per ground of the default estimator (fit every fold, predict
  the held-out run), timed in four ways in the same run: members trained one after another
  with torch's default thread count (the code before this benchmark; the baseline of the
  ratios), the same with one torch thread, the members in lockstep
  (:func:`energy.models.train_ensemble`) with one thread, and that on a local dask cluster of
  ``--workers`` processes with one thread each.
- ``adapt``: the ``adapt`` protocol with the default estimator (each fold fitted once, then
  adapted with every update method on the first T = 10 / 20 / 40 s and by the running-error
  trigger; the remainder scored unadapted, adapted and with the gain baseline), and the
  cross-ground few-shot table (train on two grounds, adapt on 10 / 20 / 40 s of one run of
  the third, test on its other runs), against the issue's targets at T = 20 s.

``--quick`` uses asphalt and flooring only (15 runs) and skips the first speed variant.

Usage::

    nice -n 5 python benchmarks/adapt_bench.py --out bench_adapt.json            # ~30-40 min on 2 cores
    python benchmarks/adapt_bench.py --quick --parts speed --out quick.json
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

import energy.models.estimator as estimator_module
from energy import VibrationCurrentEstimator, evaluate_few_shot, read_borealtc
from energy.evaluation import (
    AdaptSettings,
    EvaluationResult,
    adaptation_scores,
    run_names,
    summarise_adapt_scores,
    trim_to_overlap,
)
from energy.models import ADAPT_METHODS, train_network
from terrawatt_base.atomic import write_json_atomic
from terrawatt_base.dask_client import run_tasks

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "borealtc"
TARGETS = {"median_pct": 5.0, "p90_pct": 15.0, "sections_pct": 8.0}


def _members_one_after_another(nets, train, val, config, seeds, progress=False, description=""):  # noqa: ANN001, ANN202
    """The estimator's member loop before ``train_ensemble``: one ``train_network`` per member."""
    return [train_network(n, train, val, config, s, progress, description) for n, s in zip(nets, seeds)]


@contextlib.contextmanager
def _sequential_members(enabled: bool):  # noqa: ANN202
    """Swap the estimator's ensemble trainer for the per-member loop (a benchmark baseline only)."""
    original = estimator_module.train_ensemble
    if enabled:
        estimator_module.train_ensemble = _members_one_after_another
    try:
        yield
    finally:
        estimator_module.train_ensemble = original


def _fit_and_predict(proto: VibrationCurrentEstimator, train: list, test: Any) -> float:
    t0 = time.perf_counter()
    proto.clone().fit(train).predict(test)
    return time.perf_counter() - t0


def _folds(logs: list) -> list[tuple[int, list[int]]]:
    out = []
    for g in dict.fromkeys(lg.meta.ground_label for lg in logs):
        idx = [i for i, lg in enumerate(logs) if lg.meta.ground_label == g]
        out += [(i, [j for j in idx if j != i]) for i in idx]
    return out


def _local_client(workers: int):  # noqa: ANN202
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    return cluster, Client(cluster)


def speed(logs: list, *, quick: bool, workers: int, seed: int, skip_default_threads: bool = False) -> list[dict[str, Any]]:
    """Wall time of the whole leave-one-run-out per ground, per variant."""
    folds = _folds(logs)
    variants = [("one after another, default threads", None, True, 1),
                ("one after another, 1 thread", 1, True, 1),
                ("lockstep ensemble, 1 thread", 1, False, 1),
                (f"lockstep ensemble, {workers} dask workers x 1 thread", 1, False, workers)]
    if quick or skip_default_threads:
        variants = variants[1:]
    rows = []
    for name, threads, sequential, n_workers in variants:
        proto = VibrationCurrentEstimator("default", seed=seed, n_threads=threads)
        tasks = [(_fit_and_predict, (proto, [logs[j] for j in train], logs[test])) for test, train in folds]
        t0 = time.perf_counter()
        with _sequential_members(sequential):
            if n_workers > 1:
                cluster, client = _local_client(n_workers)
                with cluster, client:
                    fold_s = list(run_tasks(tasks, client=client))
            else:
                fold_s = list(run_tasks(tasks))
        wall = time.perf_counter() - t0
        rows.append({"variant": name, "folds": len(folds), "wall_s": wall, "fold_sum_s": float(np.sum(fold_s)),
                     "fold_max_s": float(np.max(fold_s))})
        print(f"  {name}: {wall:.1f} s", flush=True)
    base = rows[0]["wall_s"]
    for r in rows:
        r["speedup_vs_first"] = base / r["wall_s"]
    return rows


def _adapt_fold(proto: VibrationCurrentEstimator, train: list, test: Any, run: str,
                settings: list[tuple[str, AdaptSettings]]) -> tuple[list, list]:
    """Fit once, score every update method on the held-out run (module-level for dask)."""
    model = proto.clone().fit(train)
    rows, notes = [], []
    for name, st in settings:
        r, _, n = adaptation_scores(model, test, run=run, model_name=name, settings=st)
        rows += r
        notes += n if name == settings[0][0] else []
    return rows, notes


def adapt(logs: list, *, workers: int, seed: int) -> tuple[EvaluationResult, EvaluationResult]:
    """The adapt protocol per update method, and the few-shot table (default method)."""
    names = run_names(logs)
    settings = [(m, AdaptSettings(method=m)) for m in ADAPT_METHODS]
    proto = VibrationCurrentEstimator("default", seed=seed, n_threads=1)
    tasks = [(_adapt_fold, (proto, [logs[j] for j in train], logs[test], names[test], settings))
             for test, train in _folds(logs)]
    cluster, client = _local_client(workers) if workers > 1 else (contextlib.nullcontext(), None)
    with cluster, (client if client is not None else contextlib.nullcontext()):
        scores, skipped = [], []
        for rows, notes in run_tasks(tasks, client=client, progress=True, description="adapt folds"):
            scores += rows
            skipped += notes
        per_ground = EvaluationResult(tuple(scores), summarise_adapt_scores(scores), protocol="adapt",
                                      settings={"methods": list(ADAPT_METHODS), **settings[0][1].to_dict()},
                                      skipped=tuple(skipped))
        few = evaluate_few_shot(logs, proto, name="regime", settings=AdaptSettings(trigger=False), client=client,
                                progress=True)
    return per_ground, few


def _target_rows(result: EvaluationResult) -> list[dict[str, Any]]:
    out = []
    for s in result.rows:
        if s.schedule != "20 s" or s.protocol != "per_ground":
            continue
        out.append({
            "ground": s.ground, "method": s.model, "median_pct": s.adapted_median_pct, "p90_pct": s.adapted_p90_pct,
            "sections_pct": s.adapted_section_median_pct,
            "meets_targets": bool(s.adapted_median_pct <= TARGETS["median_pct"] and s.adapted_p90_pct <= TARGETS["p90_pct"]
                                  and s.adapted_section_median_pct <= TARGETS["sections_pct"]),
            "beats_gain": bool(s.adapted_median_pct < s.gain_median_pct and s.adapted_p90_pct < s.gain_p90_pct),
        })
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path("bench_adapt.json"))
    parser.add_argument("--quick", action="store_true", help="asphalt and flooring only; skip the slowest speed variant")
    parser.add_argument("--parts", nargs="+", default=["speed", "adapt"], choices=["speed", "adapt"])
    parser.add_argument("--workers", type=int, default=2, help="dask worker processes (one thread each)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--skip-default-threads", action="store_true",
                        help="leave out the slowest speed variant (torch's default thread count)")
    parser.add_argument("--data", type=Path, default=DATA)
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"BorealTC data not found at {args.data}; give --data DIR")
        return 2
    grounds = ["ASPHALT", "FLOORING"] if args.quick else None
    logs = [trim_to_overlap(lg) for lg in read_borealtc(args.data, grounds=grounds)]
    report: dict[str, Any] = {"machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
                              "runs": len(logs), "quick": args.quick, "targets_at_20_s": TARGETS}
    if "speed" in args.parts:
        print(f"speed: leave-one-run-out per ground of the default estimator, {len(logs)} runs", flush=True)
        rows = speed(logs, quick=args.quick, workers=args.workers, seed=args.seed,
                     skip_default_threads=args.skip_default_threads)
        report["speed"] = rows
        print("\n| variant | folds | wall s | sum of folds s | speed-up |\n|---|---:|---:|---:|---:|")
        for r in rows:
            print(f"| {r['variant']} | {r['folds']} | {r['wall_s']:.1f} | {r['fold_sum_s']:.1f} | {r['speedup_vs_first']:.2f}x |")
    if "adapt" in args.parts:
        per_ground, few = adapt(logs, workers=args.workers, seed=args.seed)
        report["adapt"] = per_ground.to_dict()
        report["few_shot"] = few.to_dict()
        report["targets"] = _target_rows(per_ground)
        print("\n" + per_ground.summary().split("\n\nSkipped")[0])
        print("\nfew-shot on a ground left out of training:\n" + few.summary().split("\n\nSkipped")[0])
        print("| ground | method | median % | p90 % | sections % | meets 5/15/8 | beats gain (median and p90) |")
        print("|---|---|---:|---:|---:|---|---|")
        for r in report["targets"]:
            print(f"| {r['ground']} | {r['method']} | {r['median_pct']:.1f} | {r['p90_pct']:.1f} | {r['sections_pct']:.1f} | "
                  f"{r['meets_targets']} | {r['beats_gain']} |")
    write_json_atomic(args.out, report)
    print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
