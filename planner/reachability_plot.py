"""The reachability figure: energy field in Wh with contours, the reachable area outlined, depot and obstacles.

Where the figure goes (the rule of every terrawatt figure, :mod:`terrawatt_base.plot_target`): give
exactly one of ``path`` or ``ax=``. With ``path``, :func:`plot_reachability` makes its own
figure (:func:`terrawatt_base.plot_target.new_figure`: matplotlib's object API on an Agg
canvas, no pyplot), writes a PNG atomically and returns the path; with ``ax`` it draws into
the caller's axes — its colour bar attached to ``ax.figure``, beside ``ax`` —
writes nothing, leaves the caller's figure layout alone (no ``tight_layout``) and returns
``ax``, so the map can be one panel of a larger figure.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from energy.battery import S_PER_H
from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.plot_target import check_ax, check_plot_target

__all__ = ["plot_reachability"]


def plot_reachability(reach: Any, path: str | os.PathLike[str] | None = None, *, ax: Any = None,
                      title: str | None = None, dpi: int = 130) -> Path | Any:
    """Draw a :class:`~planner.Reachability` and write a PNG atomically (or draw into ``ax``).

    The field is the energy the budget applies to (round trip or one way) in Wh, with
    labelled contour lines in Wh; the edge between the cells reachable within
    ``budget - reserve`` and the free cells beyond is drawn in red (no line when every free
    cell is reachable); blocked cells are black, cells cut off from the depot grey; the
    depot is a white star.

    Parameters
    ----------
    reach : Reachability
        The result to draw.
    path : path-like, optional
        Output PNG (checked before drawing); or give ``ax``.
    ax : matplotlib Axes, optional
        Draw into these axes instead of writing a file (the colour bar goes beside them,
        the legend below them).
    title : str, optional
        Axes title (default: what is drawn and the reachable area).
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    Path or Axes
        The written file, or ``ax``.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; ``path`` is a folder or lies under a file;
        ``ax`` is not a matplotlib Axes.
    """
    target = check_plot_target(path, ax)
    if target is None:
        _draw_reachability(check_ax(ax), reach, title)
        return ax

    fig, ax = plot_target.new_figure((9.5, 7.2))
    _draw_reachability(ax, reach, title)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi, format="png")


def _draw_reachability(ax: Any, reach: Any, title: str | None) -> None:
    """The map of :func:`plot_reachability`, drawn into ``ax`` (its colour bar beside ``ax`` in ``ax.figure``)."""
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator

    grid = reach.grid
    xmin, ymin, xmax, ymax = grid.bounds
    extent = (xmin, xmax, ymin, ymax)
    energy_wh = reach.energy_j / S_PER_H
    finite = np.isfinite(energy_wh)
    handles: list = []
    cut_off = ~finite & ~reach.blocked
    if cut_off.any():
        ax.imshow(np.ma.masked_where(~cut_off, cut_off.astype(float)), cmap=ListedColormap(["#bdbdbd"]),
                  extent=extent, origin="lower", interpolation="nearest")
        handles.append(Patch(facecolor="#bdbdbd", label="cut off from the depot"))
    if finite.any():
        im = ax.imshow(np.ma.masked_invalid(energy_wh), cmap="viridis", extent=extent, origin="lower",
                       interpolation="nearest")
        what = "round trip" if reach.round_trip else "from the depot"
        ax.figure.colorbar(im, ax=ax, shrink=0.85, label=f"least energy {what} (Wh)")
        lo, hi = float(energy_wh[finite].min()), float(energy_wh[finite].max())
        if hi > lo:
            levels = MaxNLocator(nbins=10).tick_values(lo, hi)
            levels = levels[(levels > lo) & (levels < hi)]
            if levels.size:
                # Unreachable cells take their nearest finite value, so no contour runs along them.
                xs = grid.origin_xy_m[0] + (np.arange(grid.shape[1]) + 0.5) * grid.cell_size_m
                ys = grid.origin_xy_m[1] + (np.arange(grid.shape[0]) + 0.5) * grid.cell_size_m
                nearest = ndimage.distance_transform_edt(~finite, return_distances=False, return_indices=True)
                field = energy_wh[tuple(nearest)]
                cs = ax.contour(xs, ys, field, levels=levels, colors="white", linewidths=0.6, alpha=0.8)
                ax.clabel(cs, fmt="%g Wh", fontsize=6)
    if reach.blocked.any():
        ax.imshow(np.ma.masked_where(~reach.blocked, reach.blocked.astype(float)), cmap=ListedColormap(["black"]),
                  extent=extent, origin="lower", interpolation="nearest", zorder=3)
        handles.append(Patch(facecolor="black", label="obstacle / too steep"))
    # The outline separates reachable cells from free unreachable ones (not from obstacles nor
    # the map edge): blocked cells count as inside, the mask is padded with its edge values.
    inside = reach.reachable | reach.blocked
    if reach.reachable.any() and not inside.all():
        padded = np.pad(inside.astype(float), 1, mode="edge")
        xe = grid.origin_xy_m[0] + (np.arange(grid.shape[1] + 2) - 0.5) * grid.cell_size_m
        ye = grid.origin_xy_m[1] + (np.arange(grid.shape[0] + 2) - 0.5) * grid.cell_size_m
        ax.contour(xe, ye, padded, levels=[0.5], colors="#d32f2f", linewidths=1.8, zorder=4)
    if reach.budget_j is not None:
        label = (f"reachable within {reach.usable_energy_j / S_PER_H:.1f} Wh "
                 f"({reach.reachable_area_m2:,.0f} m$^2$)")
    else:
        label = f"reachable ({reach.reachable_area_m2:,.0f} m$^2$)"
    handles.append(Line2D([], [], color="#d32f2f", linewidth=1.8, label=label))
    (depot,) = ax.plot(*reach.depot_xy_m, marker="*", color="white", markeredgecolor="k", markersize=15,
                       linestyle="", label="depot")
    handles.append(depot)
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    trip = "round trip" if reach.round_trip else "one way"
    ax.set_title(title or f"terrawatt: energy reachability ({trip})")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.08), ncol=2, fontsize=8, framealpha=0.9)
