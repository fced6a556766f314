"""Training benchmark: fit time of the current models on one 160 s run at 100 Hz.

The target (issue 3) is that training the vibration-conditioned estimator on one 160 s
interaction run at 100 Hz takes at most 20 s on 2 CPU cores. Two runs are timed:

- ``synthetic``: a seeded 160 s run with drive and IMU streams at 100 Hz (stepped v/omega
  commands as in the paper's Fig. 5, currents from a known relation plus noise, vertical
  vibration of white noise plus a wheel-rate tone);
- ``borealtc``: the first 160 s of ``FLOORING/pro_00.csv`` (6.5 Hz drive stream) resampled
  explicitly to 100 Hz (linear), when ``../shared/data/borealtc`` exists beside the repo.

For every model (the ``paper`` and ``default`` presets of ``VibrationCurrentEstimator``,
the linear and the fitted-physics baselines) the script reports the fit time, the
prediction time on the same run, the number of training windows and epochs, and whether
the fit met the 20 s target. Times depend on the machine and on its load.

Usage::

    python benchmarks/train_bench.py --out bench_train.json     # ~1-2 minutes
    python benchmarks/train_bench.py --threads 1 --models paper
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from energy import (
    CurrentModel,
    InteractionLog,
    LinearCurrentModel,
    LogMeta,
    PhysicsCurrentModel,
    VibrationCurrentEstimator,
)
from energy.io import read_borealtc_run
from terrawatt_base.atomic import write_json_atomic

TARGET_S = 20.0
DURATION_S = 160.0
RATE_HZ = 100.0
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "borealtc"


def synthetic_run(seed: int = 0) -> InteractionLog:
    """A 160 s run at 100 Hz: stepped commands, a known current relation, vibration."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(DURATION_S * RATE_HZ)) / RATE_HZ
    step = (t // 10.0).astype(int)  # a new (v, omega) pair every 10 s
    v_levels = rng.choice([0.0, 0.1, 0.2, 0.3, 0.4], size=step.max() + 1)
    w_levels = rng.choice([0.0, 0.35, 0.7, 1.05], size=step.max() + 1) * rng.choice([-1, 1], size=step.max() + 1)
    v, w = v_levels[step], w_levels[step]
    base = 0.6 + 5.0 * np.abs(v) + 4.0 * np.abs(w)
    left = base + 2.0 * np.maximum(-w, 0) + 0.3 * rng.standard_normal(t.size)
    right = base + 2.0 * np.maximum(w, 0) + 0.3 * rng.standard_normal(t.size)
    az = 9.81 + (0.2 + np.abs(v)) * (rng.standard_normal(t.size) + np.sin(2 * np.pi * 17.0 * t))
    return InteractionLog(t, v, w, np.abs(left), np.abs(right), t, az,
                          meta=LogMeta(source="synthetic", ground_label="synthetic"))


def borealtc_run() -> InteractionLog | None:
    """First 160 s of BorealTC FLOORING run 00 resampled to 100 Hz, or None without data."""
    imu, pro = DATA / "FLOORING" / "imu_00.csv", DATA / "FLOORING" / "pro_00.csv"
    if not (imu.is_file() and pro.is_file()):
        return None
    log = read_borealtc_run(imu, pro, ground_label="flooring")
    return log.slice(0.0, DURATION_S + 1e-9).resample(RATE_HZ, "linear")


def make_models(names: list[str], threads: int) -> dict[str, CurrentModel]:
    """Fresh, unfitted models by name."""
    table: dict[str, Any] = {
        "paper": lambda: VibrationCurrentEstimator("paper", seed=0, n_threads=threads),
        "default": lambda: VibrationCurrentEstimator("default", seed=0, n_threads=threads),
        "linear": LinearCurrentModel,
        "physics": PhysicsCurrentModel,
    }
    unknown = sorted(set(names) - set(table))
    if unknown:
        raise SystemExit(f"unknown model(s) {unknown!r}; choose from {sorted(table)!r}")
    return {n: table[n]() for n in names}


def bench(run_name: str, log: InteractionLog, names: list[str], threads: int) -> list[dict[str, Any]]:
    rows = []
    for name, model in make_models(names, threads).items():
        t0 = time.perf_counter()
        model.fit(log)
        fit_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        model.predict(log)
        predict_s = time.perf_counter() - t0
        row: dict[str, Any] = {
            "run": run_name, "model": name, "samples": len(log), "duration_s": round(log.duration_s, 2),
            "drive_rate_hz": round(log.drive_rate_hz, 3), "fit_s": round(fit_s, 3),
            "predict_s": round(predict_s, 3), "meets_target": bool(fit_s <= TARGET_S),
        }
        if isinstance(model, VibrationCurrentEstimator):
            row["train_windows"] = model.n_train_windows_
            row["window_samples"] = model.window_.length_samples
            row["members"] = len(model.networks_)
            row["epochs"] = [len(h.train_loss) for h in model.history_]
            row["inputs"] = model.networks_[0].n_inputs
        rows.append(row)
        print(f"  {run_name:<9} {name:<8} fit {fit_s:7.2f} s   predict {predict_s:6.3f} s", file=sys.stderr)
    return rows


def table(rows: list[dict[str, Any]]) -> str:
    lines = [f"{'run':<10}{'model':<9}{'samples':>8}{'windows':>9}{'inputs':>8}{'epochs':>16}{'fit s':>9}{'predict s':>11}  <= {TARGET_S:g} s",
             "-" * 88]
    for r in rows:
        ep = r.get("epochs")
        eps = "-" if ep is None else (str(ep[0]) if len(set(ep)) == 1 and len(ep) == 1 else f"{min(ep)}-{max(ep)} x{len(ep)}")
        lines.append(
            f"{r['run']:<10}{r['model']:<9}{r['samples']:>8}{r.get('train_windows', '-')!s:>9}{r.get('inputs', '-')!s:>8}"
            f"{eps:>16}{r['fit_s']:>9.2f}{r['predict_s']:>11.3f}  {'yes' if r['meets_target'] else 'NO'}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, default=2, help="torch threads (default 2)")
    parser.add_argument("--models", default="paper,default,linear,physics", help="comma-separated model names")
    parser.add_argument("--out", type=Path, help="write the results as JSON here")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    names = [n for n in args.models.split(",") if n]
    runs = {"synthetic": synthetic_run()}
    real = borealtc_run()
    if real is not None:
        runs["borealtc"] = real
    else:
        print("BorealTC sample not found beside the repository: timing the synthetic run only", file=sys.stderr)
    rows = []
    for run_name, log in runs.items():
        rows += bench(run_name, log, names, args.threads)
    print(table(rows))
    if args.out:
        payload = {
            "benchmark": "train_bench", "target_fit_s": TARGET_S, "threads": args.threads,
            "machine": {"python": platform.python_version(), "torch": str(torch.__version__),
                        "cpu_count": os.cpu_count(), "platform": platform.platform()},
            "rows": rows,
        }
        write_json_atomic(args.out, payload, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
