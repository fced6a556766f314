"""The ``--band LO HI`` option of the commands that train, evaluate or apply the vibration estimator."""

from __future__ import annotations

import argparse
from typing import Any

from energy.features import DEFAULT_BAND_HZ, check_band_hz

__all__ = ["LEARNED_KINDS", "add_band_option", "band_from_args"]

#: Model kinds whose features have a vibration band.
LEARNED_KINDS = ("estimator", "paper")


def add_band_option(parser: Any, help_text: str | None = None) -> None:
    """Add ``--band LO HI`` (two frequencies in Hz) to a subcommand's parser."""
    lo, hi = DEFAULT_BAND_HZ
    parser.add_argument(
        "--band", nargs=2, type=float, metavar=("LO", "HI"),
        help=help_text or (
            f"frequency band (Hz) of the vibration features of the estimator and paper models, 0 <= LO < HI "
            f"(default: the estimator's {lo:g} {hi:g}, served by any IMU of {2 * hi:g} Hz or more; the paper's 0 50)"
        ),
    )


def band_from_args(args: argparse.Namespace) -> tuple[float, float] | None:
    """The validated ``--band``, or None when it was not given.

    Raises
    ------
    InvalidParameterError
        A NaN, infinite or negative edge, or LO >= HI (the message names ``--band``).
    """
    if args.band is None:
        return None
    return check_band_hz(tuple(args.band), "--band")
