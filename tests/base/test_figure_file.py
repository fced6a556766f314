"""Tests of terrawatt_base.figure_file: a figure drawn, or a FigureWarning."""

from __future__ import annotations

from pathlib import Path

import pytest

from terrawatt_base.errors import FigureWarning, UnknownNameError
from terrawatt_base.figure_file import draw_figure


def _broken() -> Path:
    raise ValueError("bad axes")


def test_a_figure_drawn_returns_its_path(tmp_path):
    assert draw_figure(tmp_path / "a.png", lambda: tmp_path / "a.png") == tmp_path / "a.png"


def test_a_figure_that_fails_warns_or_raises(tmp_path):
    with pytest.warns(FigureWarning, match=r"could not draw .*a.png: ValueError: bad axes"):
        assert draw_figure(tmp_path / "a.png", _broken) is None
    with pytest.raises(ValueError, match="bad axes"):
        draw_figure(tmp_path / "a.png", _broken, on_error="raise")
    with pytest.raises(UnknownNameError, match="on_error"):
        draw_figure(tmp_path / "a.png", _broken, on_error="ignore")
