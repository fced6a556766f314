"""Tests of planner.plot: plot_routes writes a PNG atomically (path checked before drawing) or draws into an ax."""

from __future__ import annotations

import numpy as np
import pytest

from planner.plot import RouteLine, plot_routes
from terrain import InvalidParameterError, flat_map


def test_plot_routes_writes_a_png(tmp_path):
    import matplotlib
    import matplotlib.pyplot as plt

    backend, open_before = matplotlib.get_backend(), plt.get_fignums()
    tmap = flat_map((10, 12), 1.0)
    line = RouteLine("straight", np.array([[0.5, 0.5], [11.5, 9.5]]), 123.0)
    out = plot_routes(tmap, [line], (0.5, 0.5), (11.5, 9.5), tmp_path / "route.png")
    assert out == tmp_path / "route.png"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["route.png"]  # no temporary left
    assert matplotlib.get_backend() == backend and plt.get_fignums() == open_before  # pyplot left alone


def test_plot_routes_refuses_a_directory_before_drawing(tmp_path):
    with pytest.raises(InvalidParameterError, match="is a directory"):
        plot_routes(flat_map((4, 4), 1.0), [], (0.5, 0.5), (3.5, 3.5), tmp_path)


def test_plot_routes_draws_into_the_callers_axes_and_writes_nothing(tmp_path):
    from matplotlib.figure import Figure

    from energy.evaluation.intervals import IntervalRecord, plot_reliability

    tmap = flat_map((10, 12), 1.0, ground="grass")
    line = RouteLine("straight", np.array([[0.5, 0.5], [11.5, 9.5]]), 123.0)
    fig = Figure()
    a, b = fig.subplots(1, 2)
    assert plot_routes(tmap, [line], (0.5, 0.5), (11.5, 9.5), ax=a, title="composed") is a
    assert plot_reliability([IntervalRecord("known", "grass", "r1", 1.0, 1.1, 0.2)], ax=b) is b
    assert a.get_title() == "composed" and len(a.images) == 2  # hillshade and ground classes
    assert len(a.lines) == 3  # the route, start and goal
    labels = [t.get_text() for t in a.get_legend().get_texts()]
    assert "grass" in labels and labels[1].startswith("straight: 123 J")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_plot_routes_takes_a_path_or_an_ax_not_both_nor_neither(tmp_path):
    from matplotlib.figure import Figure

    tmap = flat_map((4, 4), 1.0)
    ax = Figure().subplots()
    with pytest.raises(InvalidParameterError, match=r"either path .* or ax= .*got neither"):
        plot_routes(tmap, [], (0.5, 0.5), (3.5, 3.5))
    with pytest.raises(InvalidParameterError, match="either path or ax=, not both"):
        plot_routes(tmap, [], (0.5, 0.5), (3.5, 3.5), tmp_path / "r.png", ax=ax)
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes"):
        plot_routes(tmap, [], (0.5, 0.5), (3.5, 3.5), ax=[ax])
    assert not ax.has_data() and list(tmp_path.iterdir()) == []
