"""The ``terrawatt`` command line: the parser, one module per subcommand, and the exit codes.

Each subcommand module parses its flags, checks them (messages name the flags), checks its
output paths before any work, calls public library functions and prints their result
objects. Exit codes mean one thing each: 0 done, 1 no route / infeasible / does not fit,
2 bad input (a user error is one line on stderr, never a traceback).
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

from terrain import TerrawattError

from . import batch, diagnose, evaluate, mission, plan, predict, reach, train

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_NOT_ACHIEVED", "EXIT_BAD_INPUT"]

#: Exit codes: done; no route, infeasible or does not fit; bad input.
EXIT_OK, EXIT_NOT_ACHIEVED, EXIT_BAD_INPUT = 0, 1, 2


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``terrawatt`` command."""
    parser = argparse.ArgumentParser(prog="terrawatt", description="Energy-aware path planning for ground robots.")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    sub = parser.add_subparsers(dest="command", required=True)
    plan.add_parsers(sub)
    evaluate.add_parser(sub)
    train.add_parser(sub)
    mission.add_parser(sub)
    predict.add_parser(sub)
    diagnose.add_parser(sub)
    reach.add_parser(sub)
    batch.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``terrawatt`` console script; returns the exit code.

    Library errors (:class:`terrain.TerrawattError`) and operating-system errors (a missing
    file, a folder without permission) are the user's input: one line on stderr, exit 2.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return args.run(args)
    except (TerrawattError, OSError) as exc:
        print(f"terrawatt: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
