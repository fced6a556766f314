"""The figure of a Monte Carlo mission study: energy histogram with P50/P90/P99 and the exceedance curve.

Where the figure goes (the rule of every terrawatt figure, :mod:`terrawatt_base.plot_target`): give
exactly one of ``path`` or ``ax=`` (2 matplotlib Axes: histogram, exceedance curve). With
``path``, :func:`plot_monte_carlo` makes its own figure (matplotlib's object API on the Agg
canvas, no pyplot), writes a PNG atomically and returns the path; with ``ax`` it draws into
the caller's axes, writes nothing, leaves the caller's figure layout alone (no
``tight_layout``) and returns the axes as a tuple, so the study can be part of a larger
figure. The suptitle (the reserve risk and the percentiles) belongs to the figure and is
drawn only with ``path``; with ``ax`` a ``title`` you give goes on the first axes.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.plot_target import check_axes, check_plot_target

__all__ = ["plot_monte_carlo"]


def plot_monte_carlo(result: Any, path: str | os.PathLike[str] | None = None, *, ax: Sequence[Any] | None = None,
                     title: str | None = None, dpi: int = 110) -> Path | tuple[Any, ...]:
    """Write a PNG of a :class:`~planner.missions.monte_carlo_result.MonteCarloResult` (or draw into ``ax``).

    Left: histogram of the mission energy (Wh) with its P50, P90 and P99, the forecast
    energy and the battery's usable energy above the reserve (nominal capacity), missions
    that went below the reserve stacked in red. Right: the exceedance curve, the
    probability that a mission needs more than a given energy (log scale).

    Parameters
    ----------
    result : MonteCarloResult
    path : path-like, optional
        PNG file to write (or give ``ax``).
    ax : sequence of 2 matplotlib Axes, optional
        Histogram, exceedance curve: draw into these instead of writing a file.
    title : str, optional
        Figure title (default: the reserve risk and the percentiles); with ``ax``, the
        first axes' title (none by default).
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    Path or tuple of 2 Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; ``path`` cannot be written (a folder, or
        under a file) or not 2 axes, checked before drawing; every mission failed (nothing
        to draw).
    """
    target = check_plot_target(path, ax)
    if target is None:
        axes = check_axes(ax, 2, what="histogram, exceedance curve")
    done = np.asarray(result.completed)
    if not done.any():
        raise InvalidParameterError(f"all {result.n} missions failed; there is no energy to draw")
    if target is None:
        _draw_monte_carlo(axes, result)
        if title:
            axes[0].set_title(title)
        return axes

    fig, axes = plot_target.new_figure((12.0, 4.4), 1, 2)
    _draw_monte_carlo(axes, result)
    pct = result.energy_percentiles_wh
    failed = f" ({result.n_failed} failed)" if result.n_failed else ""
    fig.suptitle(title or f"{result.n} missions{failed}: P(below the {result.battery.min_reserve_pct:g} % reserve) = "
                 f"{100 * result.p_below_reserve:.1f} %; P50 {pct['p50']:.2f} / P90 {pct['p90']:.2f} / "
                 f"P99 {pct['p99']:.2f} Wh", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_monte_carlo(panels: Sequence[Any], result: Any) -> None:
    """The histogram and the exceedance curve of :func:`plot_monte_carlo`, drawn into ``panels``."""
    ax_h, ax_x = panels
    done = np.asarray(result.completed)
    e_wh = np.asarray(result.energy_j)[done] / 3600.0
    below = np.asarray(result.below_reserve)[done]
    pct = result.energy_percentiles_wh
    usable_wh = result.battery.usable_energy_wh
    planned_wh = result.predicted_energy_j / 3600.0
    bins = np.histogram_bin_edges(e_wh, bins=min(50, max(10, e_wh.size // 20)))
    ax_h.hist([e_wh[~below], e_wh[below]], bins=bins, stacked=True, color=["tab:blue", "tab:red"],
              label=["reserve kept", "below the reserve"])
    marks = [(pct["p50"], "P50", "k", "-"), (pct["p90"], "P90", "k", "--"), (pct["p99"], "P99", "k", ":"),
             (planned_wh, "forecast", "tab:gray", "-.")]
    lo, hi = min(float(e_wh.min()), planned_wh), float(e_wh.max())
    span = max(hi - lo, 1e-6)
    usable_label = f"usable above the reserve (nominal) {usable_wh:.2f} Wh"
    if usable_wh <= hi + span:  # near enough to draw without squeezing the distribution
        marks.append((usable_wh, "usable (nominal)", "tab:red", "-"))
        hi = max(hi, usable_wh)
    else:
        ax_h.plot([], [], " ", label=f"{usable_label}: off the axis")
    xlim = (lo - 0.05 * span, hi + 0.05 * span)
    for value, label, colour, style in marks:
        ax_h.axvline(value, color=colour, linestyle=style, linewidth=1.2, label=f"{label} {value:.2f} Wh")
    ax_h.set_xlim(*xlim)
    ax_h.set_xlabel("mission energy (Wh)")
    ax_h.set_ylabel("missions")
    ax_h.legend(loc="best", fontsize=7)

    x = np.sort(e_wh)
    exceed = 1.0 - np.arange(x.size) / x.size  # P(E >= x_k)
    ax_x.step(x, exceed, where="post", color="tab:blue")
    ax_x.set_yscale("log")
    ax_x.set_ylim(min(0.5 / x.size, 1e-2), 1.05)
    for value, _, colour, style in marks:
        ax_x.axvline(value, color=colour, linestyle=style, linewidth=1.0)
    for q in (0.5, 0.1, 0.01):
        ax_x.axhline(q, color="0.8", linewidth=0.6)
    ax_x.set_xlim(*xlim)
    ax_x.set_xlabel("mission energy (Wh)")
    ax_x.set_ylabel("P(energy > x)")
