"""``terrawatt train``: fit one current model on logs and save it to one file."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from energy import new_current_model
from energy.models import CURRENT_MODEL_KINDS, DEFAULT_INTERVAL_FOLDS, fit_interval
from terrain import InvalidParameterError

from .common import check_output_file, input_paths
from .data import LEARNED_KINDS, add_band_option, add_data_options, band_from_args, logs_from_args

__all__ = ["add_parser", "run_train"]


def add_parser(sub: Any) -> None:
    """The ``train`` subcommand."""
    train = sub.add_parser("train", help="fit a current model on logs and save it to one file")
    add_data_options(train, grounds=True)
    train.add_argument("--model", default="estimator", choices=list(CURRENT_MODEL_KINDS), help="model kind (default estimator)")
    train.add_argument("--seed", type=int, default=0, help="random seed")
    train.add_argument("--out", type=Path, required=True, metavar="FILE", help="model file to write (e.g. model.zip)")
    train.add_argument("--threads", type=int, metavar="N", help="torch threads while training the estimator or paper "
                       "model (default: torch's own setting)")
    train.add_argument("--quiet", action="store_true", help="no progress bar with the training loss")
    train.add_argument("--interval-folds", type=int, default=DEFAULT_INTERVAL_FOLDS, metavar="K", help="the forecast "
                       "interval of a model other than the estimator (whose ensemble gives its own): refit it K times "
                       f"leaving runs out, and once per ground left out (default {DEFAULT_INTERVAL_FOLDS}; 0: no interval)")
    add_band_option(train)
    train.set_defaults(run=run_train)


def run_train(args: argparse.Namespace) -> int:
    """``terrawatt train``: fit one model on every run found and save it.

    The learned models (``estimator``, ``paper``) show a progress bar with the loss unless
    ``--quiet`` and train on ``--threads`` torch threads; the other models take neither. The
    flags and the output path are checked before the logs are read, so a bad ``--out`` never costs
    a training. ``--band LO HI`` sets the learned models' vibration band (Hz).
    """
    learned = args.model in LEARNED_KINDS
    if args.threads is not None and args.threads < 1:
        raise InvalidParameterError(f"--threads must be a positive number of threads, got {args.threads!r}")
    if args.threads is not None and not learned:
        raise InvalidParameterError(f"--threads applies to the estimator and paper models only, got --model {args.model!r}")
    if args.interval_folds < 0 or args.interval_folds == 1:
        raise InvalidParameterError(f"--interval-folds must be 0 (no interval) or >= 2, got {args.interval_folds}")
    band_hz = band_from_args(args, [args.model])
    check_output_file(args.out, input_paths(args))
    model = new_current_model(args.model, seed=args.seed, progress=learned and not args.quiet, n_threads=args.threads,
                              band_hz=band_hz)
    logs = logs_from_args(args, require_currents=True)
    t0 = time.perf_counter()
    if learned or args.interval_folds == 0 or len(logs) < 2:
        model.fit(logs)
    else:
        fit_interval(model, logs, folds=args.interval_folds)
    elapsed, path = time.perf_counter() - t0, model.save(args.out)
    band = getattr(getattr(model, "config_", None), "band_hz", None)
    band_text = f", vibration band {band[0]:g}-{band[1]:g} Hz" if band is not None else ""
    interval = "with a forecast interval" if model.gives_interval else "without a forecast interval"
    print(f"fitted {args.model} on {len(logs)} runs ({sum(log.duration_s for log in logs):.0f} s of logs{band_text}) "
          f"{interval} in {elapsed:.1f} s; wrote {path}")
    return 0
