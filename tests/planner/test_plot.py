"""Tests of planner.plot: plot_routes writes a PNG atomically and checks its path before drawing."""

from __future__ import annotations

import numpy as np
import pytest

from planner.plot import RouteLine, plot_routes
from terrain import InvalidParameterError, flat_map


def test_plot_routes_writes_a_png(tmp_path):
    tmap = flat_map((10, 12), 1.0)
    line = RouteLine("straight", np.array([[0.5, 0.5], [11.5, 9.5]]), 123.0)
    out = plot_routes(tmap, [line], (0.5, 0.5), (11.5, 9.5), tmp_path / "route.png")
    assert out == tmp_path / "route.png"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["route.png"]  # no temporary left


def test_plot_routes_refuses_a_directory_before_drawing(tmp_path):
    with pytest.raises(InvalidParameterError, match="is a directory"):
        plot_routes(flat_map((4, 4), 1.0), [], (0.5, 0.5), (3.5, 3.5), tmp_path)
