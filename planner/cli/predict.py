"""``terrawatt predict``: per-run charge errors of a saved current model on logs, written as JSON."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import compare_currents, load_current_model, plot_current_estimate, read_borealtc
from terrain.atomic import write_json_atomic

from .common import check_outputs, draw_figure

__all__ = ["add_parser", "run_predict"]


def add_parser(sub: Any) -> None:
    """The ``predict`` subcommand."""
    predict = sub.add_parser("predict", help="predict drive currents of logs with a saved model")
    predict.add_argument("--model", type=Path, required=True, metavar="FILE", help="model file written by `terrawatt train`")
    predict.add_argument("--data", type=Path, required=True, metavar="DIR", help="directory with GROUND/imu_NN.csv + pro_NN.csv")
    predict.add_argument("--grounds", nargs="+", metavar="NAME", help="ground folders to use (default all)")
    predict.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    predict.add_argument(
        "--plots", action="store_true",
        help="also write one figure per run (measured vs estimated current, moving medians) into DIR/plots/",
    )
    predict.set_defaults(run=run_predict)


def run_predict(args: argparse.Namespace) -> int:
    """``terrawatt predict``: per-run charge errors of a saved model, written as JSON."""
    check_outputs(args.out, ["predictions.json"])
    if args.plots:
        check_outputs(args.out / "plots")
    model = load_current_model(args.model)
    logs = read_borealtc(args.data, grounds=args.grounds)
    rows = []
    print(f"{'run':<28} {'side':<6} {'truth mAh':>10} {'pred mAh':>10} {'error %':>8} {'RMSE A':>7}")
    plots = []
    for log in logs:
        pred = model.predict(log)
        for k, side in enumerate(("left", "right")):
            truth = log.current_left_a if k == 0 else log.current_right_a
            err = compare_currents(log.time_s, truth, pred[:, k])
            rows.append({
                "run": log.meta.source,
                "ground": log.meta.ground_label,
                "side": side,
                "charge_true_mah": err.charge_true_mah,
                "charge_predicted_mah": err.charge_predicted_mah,
                "whole_run_error_pct": err.whole_run_error_pct,
                "section_error_pct": err.section_error_pct,
                "rmse_a": err.rmse_a,
            })
            print(
                f"{str(log.meta.ground_label) + '/' + Path(log.meta.source).name:<28} {side:<6} "
                f"{err.charge_true_mah:>10.1f} {err.charge_predicted_mah:>10.1f} {err.whole_run_error_pct:>8.2f} "
                f"{err.rmse_a:>7.2f}"
            )
        if args.plots:
            path = args.out / "plots" / f"current_{log.meta.ground_label}_{Path(log.meta.source).stem}.png"
            done = draw_figure(path, lambda log=log, pred=pred, path=path: plot_current_estimate(
                log, pred, path, label=Path(args.model).name))
            if done is not None:
                plots.append(done)
    path = write_json_atomic(args.out / "predictions.json", {"model": str(args.model), "runs": rows})
    print(f"wrote {path}" + (f" and {len(plots)} figures in {args.out / 'plots'}" if plots else ""))
    return 0
