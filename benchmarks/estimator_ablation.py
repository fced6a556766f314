"""Estimator ablation on real logs: what each ingredient of the default estimator is worth.

Leave-one-run-out per ground on the BorealTC logs (``../shared/data/borealtc`` beside the
repository, or ``--data``), the same protocol as ``terrawatt evaluate``, for the default
``VibrationCurrentEstimator`` and for variants that each remove or change one ingredient:

- ``no-prior``: no fitted physics prior under the networks (they learn the currents);
- ``no-local-spectra``: no per-window vibration spectra (v and omega windows only);
- ``abs-inputs``: |v| and |omega| as the paper feeds them, instead of signed values;
- ``one-member``: one network instead of an ensemble of five;
- ``no-clip``: predictions not clipped to the training current range;
- ``no-early-stop``: no early stopping (all epochs);
- ``huber``: Huber loss instead of MSE;
- ``ten-members``: an ensemble of ten;
- ``window-2s`` / ``window-0.5s``: windows (and local spectra) of 2 s / 0.5 s instead of 1 s;
- ``run-bands``: the whole-run band spectrum added as run-level input;
- ``mlp-v-omega``: a plain network on one (v, omega) sample, nothing else;
- ``band-1-50`` / ``band-1-25`` / ``band-0-14``: the vibration features on another band
  than the default 1-12 Hz (1-50 Hz was the default before the band became an option; it
  needs a 100 Hz IMU, 1-25 Hz a 50 Hz one);
- ``yaw-slip``: each window's yaw-rate slip (gyro against wheel-derived yaw rate) added;
  ``yaw-slip-no-spectra``: the yaw-rate slip instead of the local vibration spectra;
- ``linear``: the per-ground linear baseline, for reference.

It prints, per variant, the whole-run error of the integrated current (median and p90 over
runs and sides), the 8 s section error and the RMSE, per ground and over all grounds, and
writes the evaluation as JSON. Every variant uses the same seed; the folds run on a local
dask cluster with ``--workers N`` (one torch thread each). All variants take about 40 min
with 2 workers on 2 cores; pick some with ``--variants``.

Usage::

    python benchmarks/estimator_ablation.py --workers 2 --out ablation.json
    python benchmarks/estimator_ablation.py --variants default no-prior --grounds FLOORING
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path
from typing import Any

from energy import (
    LinearCurrentModel,
    VibrationCurrentEstimator,
    estimator_preset,
    evaluate_current_models,
    read_borealtc,
)
from terrawatt_base.atomic import write_json_atomic

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "borealtc"


def variants(seed: int) -> dict[str, Any]:
    """The default estimator and its one-change variants, by name."""
    d = estimator_preset("default")
    changes: dict[str, dict[str, Any]] = {
        "default": {},
        "no-prior": {"physics_prior": None},
        "no-local-spectra": {"local_spectrum": False},
        "abs-inputs": {"absolute_inputs": True},
        "one-member": {"n_members": 1},
        "no-clip": {"clip_output": False},
        "no-early-stop": {"patience": None},
        "huber": {"loss": "huber"},
        "ten-members": {"n_members": 10},
        "window-2s": {"window_s": 2.0, "spectrum_span_s": 2.0},
        "window-0.5s": {"window_s": 0.5},
        "run-bands": {"run_features": "bands"},
        "band-1-50": {"band_hz": (1.0, 50.0)},
        "band-1-25": {"band_hz": (1.0, 25.0)},
        "band-0-14": {"band_hz": (0.0, 14.0)},
        "yaw-slip": {"use_yaw_slip": True},
        "yaw-slip-no-spectra": {"use_yaw_slip": True, "local_spectrum": False},
        "mlp-v-omega": {"window_s": 0.15, "local_spectrum": False, "physics_prior": None, "n_members": 1,
                        "clip_output": False},
    }
    out: dict[str, Any] = {
        name: VibrationCurrentEstimator(d.replace(name=name, **kw), seed=seed, n_threads=1)
        for name, kw in changes.items()
    }
    out["linear"] = LinearCurrentModel()
    return out


def main(argv: list[str] | None = None) -> int:
    all_names = list(variants(0))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help="BorealTC-layout directory")
    parser.add_argument("--grounds", nargs="+", default=None, help="ground folders (default all)")
    parser.add_argument("--variants", nargs="+", default=all_names, choices=all_names, metavar="NAME",
                        help=f"variants to run (default all: {' '.join(all_names)})")
    parser.add_argument("--workers", type=int, default=1, help="local dask worker processes (default 1: serial)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None, help="write the evaluation (all runs) as JSON here")
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"no BorealTC data at {args.data}; give --data DIR", file=sys.stderr)
        return 2
    logs = read_borealtc(args.data, grounds=args.grounds)
    models = {name: model for name, model in variants(args.seed).items() if name in args.variants}
    with contextlib.ExitStack() as stack:
        client = None
        if args.workers > 1:
            from distributed import Client, LocalCluster

            cluster = stack.enter_context(LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                                       processes=True, dashboard_address=None))
            client = stack.enter_context(Client(cluster))
        t0 = time.perf_counter()
        result = evaluate_current_models(logs, models, variants=["per_ground"], progress=True, client=client)
        elapsed = time.perf_counter() - t0
    print(f"\n{len(logs)} runs, {len(models)} variants, per-ground leave-one-run-out, {elapsed:.0f} s")
    grounds = sorted({s.ground for s in result.rows if s.ground != "all"}) + ["all"]
    print(f"{'variant':<18} {'ground':<9} {'whole med %':>11} {'p90 %':>7} {'8 s sect %':>10} {'RMSE A':>7}")
    rows = []
    for name in models:
        for g in grounds:
            s = result.row_for(g, name, variant="per_ground")
            rows.append({"variant": name, "ground": g, "whole_run_median_pct": s.whole_run_median_pct,
                         "whole_run_p90_pct": s.whole_run_p90_pct, "section_median_pct": s.section_median_pct,
                         "rmse_median_a": s.rmse_median_a})
            print(f"{name:<18} {g:<9} {s.whole_run_median_pct:11.1f} {s.whole_run_p90_pct:7.1f} "
                  f"{s.section_median_pct:10.1f} {s.rmse_median_a:7.2f}")
    if args.out is not None:
        write_json_atomic(args.out, {"elapsed_s": elapsed, "workers": args.workers, "summary": rows,
                                     "evaluation": result.to_dict()})
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
