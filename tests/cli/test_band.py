"""Tests of terrawatt_cli.band: the ``--band LO HI`` option and its check."""

from __future__ import annotations

import argparse

import pytest

from terrawatt_cli.band import add_band_option, band_from_args
from terrain import InvalidParameterError


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_band_option(parser)
    return parser.parse_args(list(argv))


def test_a_band_is_two_frequencies_and_none_without_the_flag():
    assert band_from_args(_parse("--band", "1", "20")) == (1.0, 20.0)
    assert band_from_args(_parse()) is None


@pytest.mark.parametrize("band", [("20", "1"), ("-1", "5"), ("0", "inf"), ("nan", "5")])
def test_a_bad_band_is_refused_naming_the_flag(band):
    with pytest.raises(InvalidParameterError, match="--band"):
        band_from_args(_parse("--band", *band))
