"""Tests of terrawatt_cli.data: the ``--data`` and bag options read logs."""

from __future__ import annotations

import argparse

import pytest

from terrawatt_cli.data import add_data_options, logs_from_args
from terrawatt_base.errors import TerrawattError

from cli_samples import FIXTURES


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_data_options(parser)
    return parser.parse_args(list(argv))


def test_a_borealtc_folder_gives_logs_with_their_grounds():
    logs = logs_from_args(_parse("--data", str(FIXTURES)), require_currents=True)
    assert {log.meta.ground_label.lower() for log in logs} == {"asphalt", "snow"}


def test_bag_flags_have_their_defaults():
    args = _parse("--data", "x")
    assert args.current_unit == "A" and args.current_fields is None and args.ground_label is None


def test_a_missing_data_path_names_the_flag(tmp_path):
    with pytest.raises(TerrawattError, match="--data"):
        logs_from_args(_parse("--data", str(tmp_path / "nowhere")), require_currents=False)
