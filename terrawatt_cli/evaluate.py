"""``terrawatt evaluate``: leave-one-run-out scores of current models (:class:`energy.EvaluationResult`)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from energy import evaluate_current_models, new_current_model, plot_vibration_spectra
from energy.models import CURRENT_MODEL_KINDS
from terrain import InvalidParameterError

from .band import LEARNED_KINDS, add_band_option, band_from_args
from .common import add_dask_options, check_dask_flags, check_outputs, dask_client_arg, draw_figure, input_paths
from .data import add_data_options, logs_from_args
from .evaluate_adapt import ADAPT_OUTPUTS, adapt_settings_from_args, add_adapt_options, run_adapt_protocol

__all__ = ["add_parser", "run_evaluate"]

_OUTPUTS = ("evaluation.json", "evaluation.md", "spectra.png")


def add_parser(sub: Any) -> None:
    """The ``evaluate`` subcommand."""
    evaluate = sub.add_parser(
        "evaluate", help="leave-one-run-out evaluation of current models on logs (BorealTC folder, CSV logs, bags)"
    )
    add_data_options(evaluate)
    evaluate.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    evaluate.add_argument("--grounds", nargs="+", metavar="NAME",
                          help="ground folders (or the logs' ground labels) to use (default all)")
    evaluate.add_argument(
        "--model", nargs="+", default=None, choices=list(CURRENT_MODEL_KINDS), dest="models",
        help="models to evaluate (default all; the estimator with --protocol adapt or few-shot)",
    )
    evaluate.add_argument(
        "--variants", nargs="+", default=["per_ground", "ground_agnostic"],
        choices=["per_ground", "ground_agnostic"], help="evaluation variants",
    )
    evaluate.add_argument("--seed", type=int, default=0, help="random seed of the learned models")
    add_dask_options(evaluate, "the folds")
    add_band_option(evaluate)
    add_adapt_options(evaluate)
    evaluate.set_defaults(run=run_evaluate)


def run_evaluate(args: argparse.Namespace) -> int:
    """``terrawatt evaluate``: write evaluation.json, evaluation.md and spectra.png.

    The spectra figure comes after the results are written: if it cannot be drawn (e.g.
    logs whose IMU rate does not reach the estimator's band), a warning says so and the
    command still succeeds. ``--band LO HI`` sets the vibration band (Hz) of the estimator and
    paper models (the default band of the estimator serves IMUs of 25 Hz and more).
    """
    check_dask_flags(args)
    if args.models is None:
        args.models = list(CURRENT_MODEL_KINDS) if args.protocol == "loo" else ["estimator"]
    settings = adapt_settings_from_args(args) if args.protocol != "loo" else None
    band_hz = band_from_args(args)
    if band_hz is not None and not set(args.models) & set(LEARNED_KINDS):
        raise InvalidParameterError(
            f"--band applies to the estimator and paper models only, got --model {' '.join(args.models)}"
        )
    check_outputs(args.out, _OUTPUTS if settings is None else ADAPT_OUTPUTS, input_paths(args))
    with dask_client_arg(args) as client:  # before reading: a missing extra or scheduler fails fast
        workers = "1 worker (serial)"
        if client is not None:
            workers = f"{len(client.nthreads())} dask workers ({args.scheduler or 'a local cluster'})"
            print(f"evaluating on {workers}", flush=True)
        logs = logs_from_args(args, require_currents=True)
        models = {name: new_current_model(name, seed=args.seed, band_hz=band_hz if name in LEARNED_KINDS else None)
                  for name in args.models}
        t0 = time.perf_counter()
        if settings is not None:  # --protocol adapt / few-shot
            adapted = run_adapt_protocol(args, logs, models, client, settings, args.out)
            print(adapted.to_markdown())
            print(f"\n{len(logs)} runs, {len(models)} models, {time.perf_counter() - t0:.1f} s on {workers}; "
                  f"wrote {', '.join(str(args.out / f) for f in ADAPT_OUTPUTS)}")
            return 0
        result = evaluate_current_models(logs, models, variants=args.variants, progress=True, client=client)
        elapsed = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    json_path = result.write_json(args.out / "evaluation.json")
    md_path = result.write_markdown(args.out / "evaluation.md")
    png_path = draw_figure(args.out / "spectra.png", lambda: plot_vibration_spectra(logs, args.out / "spectra.png"))
    print(result.to_markdown())
    written = f"{json_path}, {md_path} and {png_path}" if png_path is not None else f"{json_path} and {md_path}"
    print(f"\n{len(logs)} runs, {len(models)} models, {elapsed:.1f} s on {workers}; wrote {written}")
    return 0
