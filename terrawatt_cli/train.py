"""``terrawatt train``: fit one current model on logs and save it to one file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy.models import (
    CURRENT_MODEL_KINDS,
    DEFAULT_INTERVAL_FOLDS,
    ModelOptions,
    check_training_options,
    train_report,
)

from .common import add_physics_robot_option, check_output_file, input_paths
from .data import add_band_option, add_data_options, logs_from_args

__all__ = ["add_parser", "run_train"]

#: The flags of :func:`energy.models.train_report`'s parameters (how ``terrawatt`` says its errors).
_FLAGS = {"kind": "--model", "n_threads": "--threads", "interval_folds": "--interval-folds", "band_hz": "--band",
          "robot": "--robot", "seed": "--seed"}


def add_parser(sub: Any) -> None:
    """The ``train`` subcommand."""
    train = sub.add_parser("train", help="fit a current model on logs and save it to one file")
    add_data_options(train, grounds=True)
    train.add_argument("--model", default="estimator", choices=list(CURRENT_MODEL_KINDS), help="model kind (default estimator)")
    train.add_argument("--seed", type=int, default=0, help="random seed")
    add_physics_robot_option(train)
    train.add_argument("--out", type=Path, required=True, metavar="FILE", help="model file to write (e.g. model.zip)")
    train.add_argument("--threads", type=int, metavar="N", help="torch threads while training the estimator or paper "
                       "model (default: torch's own setting)")
    train.add_argument("--quiet", action="store_true", help="no progress bar with the training loss")
    train.add_argument("--interval-folds", type=int, default=DEFAULT_INTERVAL_FOLDS, metavar="K", help="the forecast "
                       "interval of a model other than the estimator (whose ensemble gives its own): refit it K times "
                       f"leaving runs out, and once per ground left out (default {DEFAULT_INTERVAL_FOLDS}; 0: no interval)")
    add_band_option(train)
    train.set_defaults(run=run_train, flag_names=_FLAGS)


def run_train(args: argparse.Namespace) -> int:
    """``terrawatt train``: fit one model on every run found and save it.

    The learned models (``estimator``, ``paper``) show a progress bar with the loss unless
    ``--quiet`` and train on ``--threads`` torch threads; the other models take neither. The
    flags and the output path are checked before the logs are read, so a bad ``--out`` never costs
    a training. ``--band LO HI`` sets the learned models' vibration band (Hz).
    """
    fit = dict(n_threads=args.threads, interval_folds=args.interval_folds)
    options = check_training_options(args.model, options=ModelOptions(seed=args.seed, band_hz=args.band,
                                                                      robot=args.robot), **fit)
    check_output_file(args.out, input_paths(args))
    report = train_report(args.model, logs_from_args(args, require_currents=True), options=options,
                          progress=not args.quiet, **fit)
    written = report.write(args.out)
    print(f"{report.summary()}; wrote {written}")
    return 0
