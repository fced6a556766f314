"""``terrawatt predict``: the scores of a saved current model on logs (an :class:`energy.EvaluationResult`), or
its predictions (:func:`energy.prediction.predict_runs`) when some logs have no measured currents."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import load_current_model, plot_current_estimate
from energy.evaluation import score_current_model
from energy.features import BandNotServedError
from energy.prediction import predict_runs
from terrain import InvalidParameterError
from terrawatt_base.atomic import write_json_atomic

from .band import add_band_option, band_from_args
from .common import check_outputs, draw_figure, input_paths
from .data import add_data_options, logs_from_args

__all__ = ["add_parser", "run_predict"]


def add_parser(sub: Any) -> None:
    """The ``predict`` subcommand."""
    predict = sub.add_parser("predict", help="predict drive currents of logs with a saved model")
    predict.add_argument("--model", type=Path, required=True, metavar="FILE", help="model file written by `terrawatt train`")
    add_data_options(predict)
    predict.add_argument("--grounds", nargs="+", metavar="NAME",
                         help="ground folders (or the logs' ground labels) to use (default all)")
    predict.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    predict.add_argument(
        "--plots", action="store_true",
        help="also write one figure per run (measured vs estimated current, moving medians) into DIR/plots/",
    )
    add_band_option(predict, help_text=(
        "the frequency band (Hz) the logs' IMU serves, e.g. 0 25 for a 50 Hz IMU: refuse, before reading the "
        "logs, a model whose vibration band does not lie within it (the model's band is fixed when training)"
    ))
    predict.set_defaults(run=run_predict)


def run_predict(args: argparse.Namespace) -> int:
    """``terrawatt predict``: per-run charge errors of a saved model
    (:func:`energy.evaluation.score_current_model`), printed and written as JSON."""
    check_outputs(args.out, ["predictions.json"], input_paths(args))
    if args.plots:
        check_outputs(args.out / "plots")
    band_hz = band_from_args(args)
    model = load_current_model(args.model)
    if band_hz is not None:
        _check_model_band(model, band_hz, args.model)
    logs = logs_from_args(args, require_currents=False)
    if not all(log.has_currents for log in logs):
        return _predict_only(args, model, logs)
    result = score_current_model(model, logs, name=Path(args.model).name)
    print(f"{'run':<28} {'side':<6} {'truth mAh':>10} {'pred mAh':>10} {'error %':>8} {'RMSE A':>7}")
    for r in result.runs:
        print(f"{r.run:<28} {r.side:<6} {r.charge_true_mah:>10.1f} {r.charge_predicted_mah:>10.1f} "
              f"{r.whole_run_error_pct:>8.2f} {r.rmse_a:>7.2f}")
    path = write_json_atomic(args.out / "predictions.json", {"model": str(args.model), **result.to_dict()})
    plots = []
    if args.plots:
        for log in logs:
            png = args.out / "plots" / f"current_{log.meta.ground_label}_{Path(log.meta.source).stem}.png"
            done = draw_figure(png, lambda log=log, png=png: plot_current_estimate(
                log, model.predict(log), png, label=Path(args.model).name))
            if done is not None:
                plots.append(done)
    print(f"wrote {path}" + (f" and {len(plots)} figures in {args.out / 'plots'}" if plots else ""))
    return 0


def _predict_only(args: argparse.Namespace, model: Any, logs: list[Any]) -> int:
    """Predictions without scores: some logs have no measured currents (e.g. an IMU + odometry bag)."""
    runs = predict_runs(model, logs)
    print(f"{'run':<28} {'pred L mAh':>10} {'pred R mAh':>10} {'meas L mAh':>10} {'meas R mAh':>10} {'pred Wh':>8}")
    for r in runs:
        cells = (r.charge_measured_left_mah, r.charge_measured_right_mah, r.energy_predicted_wh)
        meas_l, meas_r, wh = (f"{x:.1f}" if x == x else "-" for x in cells)
        print(f"{r.run:<28} {r.charge_predicted_left_mah:>10.1f} {r.charge_predicted_right_mah:>10.1f} {meas_l:>10} "
              f"{meas_r:>10} {wh:>8}")
    path = write_json_atomic(args.out / "predictions.json",
                             {"model": str(args.model), "scored": False, "runs": [r.to_dict() for r in runs]})
    missing = sum(not log.has_currents for log in logs)
    print(f"{missing} of {len(logs)} logs have no measured currents: predictions only, no errors; wrote {path}"
          + (" (no figures: they compare with measured currents)" if args.plots else ""))
    return 0


def _check_model_band(model: Any, band_hz: tuple[float, float], path: Path) -> None:
    """Refuse a model whose vibration band does not lie within ``--band``."""
    config = getattr(model, "config_", None)
    if config is None or not hasattr(config, "band_hz"):
        raise InvalidParameterError(
            f"--band applies to estimator and paper model files; {str(path)!r} holds a {type(model).__name__}"
        )
    lo, hi = config.band_hz
    if lo < band_hz[0] or hi > band_hz[1]:
        raise BandNotServedError(
            f"the model {str(path)!r} was trained on the vibration band {lo:g}-{hi:g} Hz, which does not lie within "
            f"--band {band_hz[0]:g} {band_hz[1]:g}; retrain it with terrawatt train --band LO HI inside that band"
        )
