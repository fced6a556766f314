"""``terrawatt evaluate``: leave-one-run-out scores of current models (:class:`energy.EvaluationResult`), or the
``adapt`` and ``few-shot`` protocols (:class:`energy.evaluation.AdaptationResult`)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from energy import evaluate_adaptation, evaluate_current_models, evaluate_few_shot, new_current_model, plot_vibration_spectra
from energy.evaluation import ADAPT_FILES, EVALUATION_FILES, AdaptSettings
from energy.models import ADAPT_METHODS, CURRENT_MODEL_KINDS, LEARNED_KINDS
from terrain import InvalidParameterError

from .common import add_dask_options, check_dask_flags, check_outputs, dask_client_arg, draw_figure, input_paths
from .data import add_band_option, add_data_options, band_from_args, logs_from_args

__all__ = ["PROTOCOLS", "add_parser", "add_adapt_options", "adapt_settings_from_args", "run_evaluate"]

#: ``--protocol`` choices: leave one run out (the default), adapt on each held-out run's
#: first seconds, few shots on a ground left out of training.
PROTOCOLS = ("loo", "adapt", "few-shot")


def add_parser(sub: Any) -> None:
    """The ``evaluate`` subcommand."""
    evaluate = sub.add_parser(
        "evaluate", help="leave-one-run-out evaluation of current models on logs (BorealTC folder, CSV logs, bags)")
    add_data_options(evaluate, grounds=True)
    evaluate.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    evaluate.add_argument("--model", nargs="+", default=None, choices=list(CURRENT_MODEL_KINDS), dest="models",
                          help="models to evaluate (default all; the estimator with --protocol adapt or few-shot)")
    evaluate.add_argument("--variants", nargs="+", default=["per_ground", "ground_agnostic"],
                          choices=["per_ground", "ground_agnostic"], help="evaluation variants")
    evaluate.add_argument("--seed", type=int, default=0, help="random seed of the learned models")
    add_dask_options(evaluate, "the folds")
    add_band_option(evaluate)
    add_adapt_options(evaluate)
    evaluate.set_defaults(run=run_evaluate)


def add_adapt_options(parser: argparse.ArgumentParser) -> None:
    """``--protocol``, ``--adapt-seconds``, ``--adapt-method``, ``--adapt-threshold``."""
    parser.add_argument("--protocol", choices=PROTOCOLS, default="loo", help="loo: leave one run out (default); "
                        "adapt: also adapt each held-out run's model on its first --adapt-seconds and score the rest "
                        "beside the unadapted model and the per-side gain baseline; few-shot: train on the other "
                        "grounds, adapt on seconds of one run of a ground, score its other runs")
    parser.add_argument("--adapt-seconds", type=float, nargs="+", default=[10.0, 20.0, 40.0], metavar="T",
                        help="seconds of each run the model adapts on (default 10 20 40)")
    parser.add_argument("--adapt-method", choices=ADAPT_METHODS, default=ADAPT_METHODS[0],
                        help=f"the in-run update (default {ADAPT_METHODS[0]})")
    parser.add_argument("--adapt-threshold", type=float, default=10.0, metavar="PCT",
                        help="adapt protocol: the running charge error (%%) above which the trigger schedule updates")


def adapt_settings_from_args(args: argparse.Namespace) -> AdaptSettings:
    """The :class:`energy.evaluation.AdaptSettings` of the command line (bad values: errors naming the flag)."""
    if bad := [t for t in args.adapt_seconds if not t > 0]:
        raise InvalidParameterError(f"--adapt-seconds must be seconds > 0, got {bad[0]!r}")
    if not args.adapt_threshold >= 0:
        raise InvalidParameterError(f"--adapt-threshold must be a percentage >= 0, got {args.adapt_threshold!r}")
    return AdaptSettings(adapt_seconds=tuple(args.adapt_seconds), method=args.adapt_method,
                         threshold_pct=args.adapt_threshold, trigger=args.protocol == "adapt")


def run_evaluate(args: argparse.Namespace) -> int:
    """``terrawatt evaluate``: evaluation.json, evaluation.md and spectra.png (a figure that fails is a warning), or
    adapt.json and adapt.md with ``--protocol adapt`` / ``few-shot``."""
    check_dask_flags(args)
    kinds = args.models or (list(CURRENT_MODEL_KINDS) if args.protocol == "loo" else ["estimator"])
    settings = adapt_settings_from_args(args) if args.protocol != "loo" else None
    band_hz = band_from_args(args, kinds)
    check_outputs(args.out, (*EVALUATION_FILES, "spectra.png") if settings is None else ADAPT_FILES, input_paths(args))
    with dask_client_arg(args) as client:  # before reading: a missing extra or scheduler fails fast
        workers = "1 worker (serial)"
        if client is not None:
            workers = f"{len(client.nthreads())} dask workers ({args.scheduler or 'a local cluster'})"
            print(f"evaluating on {workers}", flush=True)
        logs = logs_from_args(args, require_currents=True)
        models = {name: new_current_model(name, seed=args.seed, band_hz=band_hz if name in LEARNED_KINDS else None)
                  for name in kinds}
        t0 = time.perf_counter()
        if settings is None:
            result = evaluate_current_models(logs, models, variants=args.variants, progress=True, client=client)
        else:
            run = evaluate_adaptation if args.protocol == "adapt" else evaluate_few_shot
            result = run(logs, models, settings=settings, progress=True, client=client)
        elapsed = time.perf_counter() - t0
    written = [*result.write(args.out)]
    if settings is None:
        written.append(draw_figure(args.out / "spectra.png", lambda: plot_vibration_spectra(logs, args.out / "spectra.png")))
    print(result.to_markdown())
    names = [str(p) for p in written if p is not None]
    files = ", ".join(names) if settings else ", ".join(names[:-1]) + " and " + names[-1]
    print(f"\n{len(logs)} runs, {len(models)} models, {elapsed:.1f} s on {workers}; wrote {files}")
    return 0
