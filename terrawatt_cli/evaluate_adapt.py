"""The ``adapt`` and ``few-shot`` protocols of ``terrawatt evaluate``: their options and their run."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import evaluate_adaptation, evaluate_few_shot
from energy.evaluation import AdaptationResult, AdaptSettings
from energy.models import ADAPT_METHODS
from terrain import InvalidParameterError

__all__ = ["PROTOCOLS", "ADAPT_OUTPUTS", "add_adapt_options", "adapt_settings_from_args", "run_adapt_protocol"]

#: ``--protocol`` choices: leave one run out (the default), adapt on each held-out run's
#: first seconds, few shots on a ground left out of training.
PROTOCOLS = ("loo", "adapt", "few-shot")
#: Files the adapt and few-shot protocols write.
ADAPT_OUTPUTS = ("adapt.json", "adapt.md")


def add_adapt_options(parser: argparse.ArgumentParser) -> None:
    """``--protocol``, ``--adapt-seconds``, ``--adapt-method``, ``--adapt-threshold``."""
    parser.add_argument(
        "--protocol", choices=PROTOCOLS, default="loo",
        help="loo: leave one run out (default); adapt: also adapt each held-out run's model on its first "
        "--adapt-seconds and score the rest beside the unadapted model and the per-side gain baseline; "
        "few-shot: train on the other grounds, adapt on seconds of one run of a ground, score its other runs",
    )
    parser.add_argument("--adapt-seconds", type=float, nargs="+", default=[10.0, 20.0, 40.0], metavar="T",
                        help="seconds of each run the model adapts on (default 10 20 40)")
    parser.add_argument("--adapt-method", choices=ADAPT_METHODS, default=ADAPT_METHODS[0],
                        help=f"the in-run update (default {ADAPT_METHODS[0]})")
    parser.add_argument("--adapt-threshold", type=float, default=10.0, metavar="PCT",
                        help="adapt protocol: the running charge error (%%) above which the trigger schedule updates")


def adapt_settings_from_args(args: argparse.Namespace) -> AdaptSettings:
    """The :class:`energy.AdaptSettings` of the command line.

    Raises
    ------
    InvalidParameterError
        A bad ``--adapt-seconds`` or ``--adapt-threshold`` (the message names the flag).
    """
    for t in args.adapt_seconds:
        if not t > 0:
            raise InvalidParameterError(f"--adapt-seconds must be seconds > 0, got {t!r}")
    if not args.adapt_threshold >= 0:
        raise InvalidParameterError(f"--adapt-threshold must be a percentage >= 0, got {args.adapt_threshold!r}")
    return AdaptSettings(adapt_seconds=tuple(args.adapt_seconds), method=args.adapt_method,
                         threshold_pct=args.adapt_threshold, trigger=args.protocol == "adapt")


def run_adapt_protocol(args: argparse.Namespace, logs: list[Any], models: dict[str, Any], client: Any,
                       settings: AdaptSettings, out: Path) -> AdaptationResult:
    """Run ``--protocol adapt`` or ``few-shot`` and write ``adapt.json`` and ``adapt.md`` into ``out``."""
    run = evaluate_adaptation if args.protocol == "adapt" else evaluate_few_shot
    result = run(logs, models, settings=settings, progress=True, client=client)
    result.write(out)
    return result
