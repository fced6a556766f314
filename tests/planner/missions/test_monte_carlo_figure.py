"""Tests of planner.missions.monte_carlo_figure: the study figure drawn into the caller's axes."""

from __future__ import annotations

import pytest
from mc_samples import run_mc, setup  # noqa: F401  (fixture)

from energy import Battery
from terrawatt_base.errors import InvalidParameterError


def test_the_figure_draws_into_the_callers_axes_and_writes_nothing(setup, tmp_path):
    from matplotlib.figure import Figure

    mc = run_mc(setup, n=5, seed=7, battery=Battery(0.12, 24.0))
    fig = Figure()
    hist, exceed = fig.subplots(1, 2)
    assert mc.plot(ax=[hist, exceed], title="study") == (hist, exceed)
    assert hist.patches and hist.get_xlabel() == "mission energy (Wh)" and hist.get_title() == "study"
    assert any(t.get_text().startswith("P90 ") for t in hist.get_legend().get_texts())
    assert len(exceed.lines) >= 5 and exceed.get_ylabel() == "P(energy > x)" and exceed.get_yscale() == "log"
    assert fig.get_suptitle() == ""
    with pytest.raises(InvalidParameterError, match="got neither"):
        mc.plot()
    with pytest.raises(InvalidParameterError, match="not both"):
        mc.plot(tmp_path / "mc.png", ax=[hist, exceed])
    with pytest.raises(InvalidParameterError, match=r"2 matplotlib Axes \(histogram, exceedance curve\), got 1"):
        mc.plot(ax=[hist])
    assert list(tmp_path.iterdir()) == []
