"""``terrawatt evaluate``: current models scored on held-out runs by one protocol (:class:`energy.EvaluationResult`):
leave one run out, or the ``adapt`` and ``few-shot`` protocols."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy.evaluation import (
    DEFAULT_ADAPT_SECONDS,
    EVALUATION_PROTOCOLS,
    AdaptSettings,
    check_adapt_options,
    check_evaluation_options,
    evaluate_kinds,
    evaluation_files,
)
from energy.models import ADAPT_METHODS, ADAPT_SHRINKS, CURRENT_MODEL_KINDS, ModelOptions
from terrawatt_base.errors import InvalidParameterError

from .common import (
    add_dask_options,
    add_physics_robot_option,
    check_dask_flags,
    check_outputs,
    compute_arg,
    input_paths,
    warn_figures,
)
from .data import add_band_option, add_data_options, logs_from_args

__all__ = ["PROTOCOLS", "FLAGS", "add_parser", "add_adapt_options", "adapt_settings_from_args", "run_evaluate"]

#: ``--protocol`` choices: leave one run out (the default), adapt on each held-out run's
#: first seconds, few shots on a ground left out of training.
PROTOCOLS = EVALUATION_PROTOCOLS
#: The flags of :func:`energy.evaluation.evaluate_kinds`'s parameters (how ``terrawatt`` says its errors).
FLAGS = {"kinds": "--model", "protocol": "--protocol", "band_hz": "--band", "adapt_seconds": "--adapt-seconds",
          "adapt_method": "--adapt-method", "adapt_threshold_pct": "--adapt-threshold", "adapt_shrink": "--adapt-shrink",
          "robot": "--robot", "seed": "--seed"}


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
    add_physics_robot_option(evaluate)
    add_dask_options(evaluate, "the folds")
    add_band_option(evaluate)
    add_adapt_options(evaluate)
    evaluate.set_defaults(run=run_evaluate, flag_names=FLAGS)


def add_adapt_options(parser: argparse.ArgumentParser) -> None:
    """``--protocol``, ``--adapt-seconds``, ``--adapt-method``, ``--adapt-threshold``."""
    parser.add_argument("--protocol", choices=PROTOCOLS, default="loo", help="loo: leave one run out (default); "
                        "adapt: also adapt each held-out run's model on its first --adapt-seconds and score the rest "
                        "beside the unadapted model and the per-side gain baseline; few-shot: train on the other "
                        "grounds, adapt on seconds of one run of a ground, score its other runs")
    # defaults None: a flag the user gave is told apart from one left out (--protocol loo takes none of them)
    parser.add_argument("--adapt-seconds", type=float, nargs="+", default=None, metavar="T",
                        help="seconds of each run the model adapts on (default "
                             f"{' '.join(f'{t:g}' for t in DEFAULT_ADAPT_SECONDS)})")
    parser.add_argument("--adapt-method", choices=ADAPT_METHODS, default=None,
                        help=f"the in-run update (default {ADAPT_METHODS[0]})")
    parser.add_argument("--adapt-shrink", choices=ADAPT_SHRINKS, default=None,
                        help="how far the update follows the seconds it adapts on: prior: the share of their residual "
                             "the spreads learned across runs and grounds carry to the forecast (default); evidence: "
                             "the James-Stein factor of the residual against noise and run spread; none: fully")
    parser.add_argument("--adapt-threshold", type=float, default=None, metavar="PCT",
                        help="adapt protocol: the running charge error (%%) above which the trigger schedule updates "
                             "(default 10)")


def adapt_settings_from_args(args: argparse.Namespace) -> AdaptSettings | None:
    """The :class:`energy.evaluation.AdaptSettings` of the command line (:func:`energy.evaluation.check_adapt_options`:
    bad values are errors naming the flag); None for ``--protocol loo``, which refuses the adapt flags."""
    given = {"--adapt-seconds": args.adapt_seconds, "--adapt-method": args.adapt_method,
             "--adapt-threshold": args.adapt_threshold, "--adapt-shrink": args.adapt_shrink}
    if args.protocol == "loo" and (flags := [f for f, v in given.items() if v is not None]):
        raise InvalidParameterError(f"{', '.join(flags)} appl{'ies' if len(flags) == 1 else 'y'} to --protocol adapt "
                                    "or few-shot, not to loo (the default): add --protocol adapt or few-shot")
    if args.protocol == "loo":
        return None
    if args.protocol == "few-shot" and args.adapt_threshold is not None:
        raise InvalidParameterError("--adapt-threshold sets the trigger schedule of --protocol adapt; few-shot has none")
    return check_adapt_options(
        args.protocol, adapt_seconds=DEFAULT_ADAPT_SECONDS if args.adapt_seconds is None else args.adapt_seconds,
        adapt_method=args.adapt_method or ADAPT_METHODS[0],
        adapt_threshold_pct=10.0 if args.adapt_threshold is None else args.adapt_threshold,
        adapt_shrink=ADAPT_SHRINKS[0] if args.adapt_shrink is None else args.adapt_shrink)


def run_evaluate(args: argparse.Namespace) -> int:
    """``terrawatt evaluate``: evaluation.json, evaluation.md and spectra.png (a figure that fails is a warning), or
    adapt.json and adapt.md with ``--protocol adapt`` / ``few-shot`` (:func:`energy.evaluation.evaluate_kinds`)."""
    check_dask_flags(args)
    settings = adapt_settings_from_args(args)
    options = ModelOptions(seed=args.seed, band_hz=args.band, robot=args.robot)
    check_evaluation_options(args.models, protocol=args.protocol, options=options)
    check_outputs(args.out, evaluation_files(args.protocol), input_paths(args))
    with compute_arg(args, progress=True) as compute:  # before reading: a missing extra or scheduler fails fast
        workers = "1 worker (serial)"
        if compute.client is not None:
            workers = f"{len(compute.client.nthreads())} dask workers ({args.scheduler or 'a local cluster'})"
            print(f"evaluating on {workers}", flush=True)
        result = evaluate_kinds(logs_from_args(args, require_currents=True), args.models, protocol=args.protocol,
                                variants=args.variants, settings=settings, options=options, compute=compute)
    with warn_figures():
        written = result.write(args.out)
    print(result.summary())
    print(f"\n{result.written_line(written, workers=workers)}")
    return 0
