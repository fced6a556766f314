"""``terrawatt predict``: the scores of a saved current model on logs, or its predictions when some logs have no
measured currents (:func:`energy.evaluation.predict_logs`: an :class:`energy.EvaluationResult` of protocol
``"prefit"``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import load_current_model
from energy.evaluation import FIGURES_FOLDER, PREDICTIONS_FILE, predict_logs
from energy.features import check_model_band

from .common import check_outputs, input_paths, warn_figures
from .data import add_band_option, add_data_options, band_from_args, logs_from_args

__all__ = ["add_parser", "run_predict"]


def add_parser(sub: Any) -> None:
    """The ``predict`` subcommand."""
    predict = sub.add_parser("predict", help="predict drive currents of logs with a saved model")
    predict.add_argument("--model", type=Path, required=True, metavar="FILE", help="model file written by `terrawatt train`")
    add_data_options(predict, grounds=True)
    predict.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    predict.add_argument("--plots", action="store_true", help="also write one figure per run (measured vs estimated "
                         "current, moving medians) into DIR/plots/")
    add_band_option(predict, help_text=(
        "the frequency band (Hz) the logs' IMU serves, e.g. 0 25 for a 50 Hz IMU: refuse, before reading the "
        "logs, a model whose vibration band does not lie within it (the model's band is fixed when training)"
    ))
    predict.set_defaults(run=run_predict)


def run_predict(args: argparse.Namespace) -> int:
    """``terrawatt predict``: per-run charge errors of a saved model, printed and written as JSON (and figures)."""
    check_outputs(args.out, [PREDICTIONS_FILE], input_paths(args))
    if args.plots:
        check_outputs(args.out / FIGURES_FOLDER)
    band_hz = band_from_args(args)
    model = load_current_model(args.model)
    check_model_band(model, band_hz, "--band", str(args.model))
    result = predict_logs(model, logs_from_args(args, require_currents=False), label=str(args.model))
    print(result.summary())
    with warn_figures():
        written = result.write(args.out, figures=args.plots)
    print(result.written_line(written, figures=args.plots))
    return 0
