"""Tests of planner.reachability_plot: the reachability figure, to a file or into the caller's axes."""

from __future__ import annotations

import pytest
from reach_samples import DEPOT, PNG_MAGIC, hilly_cost  # noqa: F401  (fixtures)

from planner import reachability
from terrawatt_base.errors import InvalidParameterError


def test_plot_writes_a_png_and_checks_its_path_first(tmp_path, hilly_cost):
    reach = reachability(hilly_cost, DEPOT, budget_j=8_000.0, round_trip=True)
    assert 0 < reach.reachable_fraction < 1  # the outline is drawn
    path = reach.plot(tmp_path / "reach.png")
    assert path.read_bytes()[:8] == PNG_MAGIC
    (tmp_path / "folder.png").mkdir()
    with pytest.raises(InvalidParameterError):
        reach.plot(tmp_path / "folder.png")


def test_plot_draws_into_the_callers_axes_with_its_colour_bar_beside_them(tmp_path, hilly_cost):
    from matplotlib.figure import Figure

    reach = reachability(hilly_cost, DEPOT, budget_j=8_000.0, round_trip=True)
    fig = Figure()
    left, right = fig.subplots(1, 2)
    assert reach.plot(ax=right, title="mine") is right
    assert len(right.images) >= 2 and right.collections  # field, obstacles; contours and the outline
    assert right.get_title() == "mine"
    assert any(t.get_text().startswith("reachable within") for t in right.get_legend().texts)
    assert len(fig.axes) == 3 and fig.axes[2].get_ylabel() == "least energy round trip (Wh)"
    assert not left.has_data()
    with pytest.raises(InvalidParameterError, match="got neither"):
        reach.plot()
    with pytest.raises(InvalidParameterError, match="not both"):
        reach.plot(tmp_path / "reach.png", ax=left)
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'Figure'"):
        reach.plot(ax=fig)
    assert list(tmp_path.iterdir()) == []
