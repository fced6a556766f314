"""Tests of terrawatt_cli.evaluate_adapt: the adapt protocol's options and the settings they give."""

from __future__ import annotations

import argparse

import pytest

from terrawatt_cli.evaluate_adapt import PROTOCOLS, add_adapt_options, adapt_settings_from_args
from terrain import InvalidParameterError


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_adapt_options(parser)
    return parser.parse_args(list(argv))


def test_defaults_give_the_leave_one_out_protocol_without_trigger():
    args = _parse()
    assert args.protocol == "loo" and PROTOCOLS[0] == "loo"
    s = adapt_settings_from_args(args)
    assert s.adapt_seconds == (10.0, 20.0, 40.0) and s.threshold_pct == 10.0 and not s.trigger


def test_the_adapt_protocol_triggers_on_its_threshold():
    s = adapt_settings_from_args(_parse("--protocol", "adapt", "--adapt-seconds", "5", "--adapt-threshold", "3"))
    assert s.trigger and s.adapt_seconds == (5.0,) and s.threshold_pct == 3.0


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--adapt-seconds", "10", "0"], "--adapt-seconds must be seconds > 0, got 0.0"),
        (["--adapt-threshold", "-1"], "--adapt-threshold must be a percentage >= 0, got -1.0"),
    ],
)
def test_bad_flags_are_refused_naming_the_flag(argv, match):
    with pytest.raises(InvalidParameterError, match=match):
        adapt_settings_from_args(_parse(*argv))
