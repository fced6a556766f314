"""The ``terrawatt`` command line: the parser, one module per subcommand, the exit codes (:data:`EXIT_CODES`)."""

from __future__ import annotations

import argparse
import logging
import re
import sys
import traceback
from collections.abc import Sequence

from terrain import TerrawattError

from . import batch, diagnose, evaluate, mission, plan, predict, reach, replay, tour, train
from .common import COMMON_FLAGS, SEARCH_FLAGS, flag_text
from .data import DATA_FLAGS

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_NOT_ACHIEVED", "EXIT_BAD_INPUT", "EXIT_INTERNAL", "EXIT_CODES"]

#: Exit codes: done; a valid negative answer; bad input or usage; an internal error (a bug).
EXIT_OK, EXIT_NOT_ACHIEVED, EXIT_BAD_INPUT, EXIT_INTERNAL = 0, 1, 2, 3
#: What each exit code means (``--help`` prints it).
EXIT_CODES = {
    EXIT_OK: "done",
    EXIT_NOT_ACHIEVED: "a valid negative answer: no route, infeasible, does not fit the battery, error rows in a batch",
    EXIT_BAD_INPUT: "bad input or usage (one line on stderr)",
    EXIT_INTERNAL: "internal error: a bug in terrawatt (one line; the traceback with -v)",
}


_NUMPY_SCALAR = re.compile(r"np\.(?:float|int|uint|complex)\d*\(([^()]*)\)|np\.(?:bool_|True_|False_)\(([^()]*)\)")


def plain_message(text: str) -> str:
    """A message with numpy scalar reprs (``np.float64(10.0)``) shown as plain numbers (``10.0``): the last safety net."""
    return _NUMPY_SCALAR.sub(lambda m: m.group(1) if m.group(1) is not None else m.group(2), text)


#: The library's parameters a message may name, and the flags that set them, in every command (a library error names
#: the parameter, :attr:`terrain.TerrawattError.parameter`; the command line says it by its flag). A command adds
#: its own (``set_defaults(flag_names=...)``).
PARAMETER_FLAGS = {**COMMON_FLAGS, **SEARCH_FLAGS, **DATA_FLAGS}


def error_message(exc: BaseException, flags: dict[str, str] | None = None) -> str:
    """The one line ``terrawatt`` prints for a user's error: the parameters the error names said by their flags
    (``flags`` first, then :data:`PARAMETER_FLAGS`).

    A parameter the message quotes in backticks (```model```) is replaced there only: the message
    marked which words are the parameter (``"draw_from 'model' ... a saved model: give `model`"``);
    one it does not quote is replaced wherever it stands as a whole word (:func:`~terrawatt_cli.common.flag_text`).

    Examples
    --------
    >>> from terrain import InvalidParameterError
    >>> error_message(InvalidParameterError("risk 0.1 lies below the median: plan without risk", parameter="risk"))
    '--risk 0.1 lies below the median: plan without --risk'
    >>> error_message(InvalidParameterError("`model` prices the map like a model", parameter="model"),
    ...               {"model": "--model"})
    '--model prices the map like a model'
    """
    return flag_text(plain_message(str(exc)), getattr(exc, "parameter", None), PARAMETER_FLAGS | (flags or {}))


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``terrawatt`` command."""
    parser = argparse.ArgumentParser(
        prog="terrawatt", description="Energy-aware path planning for ground robots.",
        epilog="exit codes: " + "; ".join(f"{code} {text}" for code, text in EXIT_CODES.items()),
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    sub = parser.add_subparsers(dest="command", required=True)
    plan.add_parsers(sub)
    for command in (evaluate, train, mission, replay, predict, diagnose, reach, batch, tour):
        command.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``terrawatt`` console script; returns the exit code (:data:`EXIT_CODES`): library and
    operating-system errors are the user's input (one line, exit 2), any other exception a bug (exit 3)."""
    try:
        args = build_parser().parse_args(argv)  # a flag's value checked while parsing (common.Checked) may fail here
    except TerrawattError as exc:
        print(f"terrawatt: error: {error_message(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return args.run(args)
    except (TerrawattError, OSError) as exc:
        print(f"terrawatt: error: {error_message(exc, getattr(args, 'flag_names', None))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MemoryError:  # what no size check foresaw (other programs took the memory meanwhile)
        print("terrawatt: error: this machine ran out of memory for the inputs given; use smaller inputs (a smaller "
              "map, --windowed, fewer missions) or free memory", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as exc:  # noqa: BLE001 - the last line of defence: a bug, said so
        if args.verbose:
            traceback.print_exc()
        where = "" if args.verbose else "; run with -v for the traceback"
        print(f"terrawatt: internal error (a bug in terrawatt, please report it): {type(exc).__name__}: "
              f"{str(exc)[:300]}{where}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
