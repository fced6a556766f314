"""Figures of mission results: the driven mission and the adaptive loop.

Where a figure goes (the rule of every terrawatt figure, :mod:`terrawatt_base.plot_target`): give
exactly one of ``path`` or ``ax=`` (a sequence of matplotlib Axes, one per panel; an array
from ``Figure.subplots`` is read row by row). With ``path`` the function makes its own figure
(matplotlib's object API on the Agg canvas, no pyplot), writes a PNG atomically and returns
the path; with ``ax`` it draws into the caller's axes — a colour bar attached to the axes'
figure, beside its panel — writes nothing, leaves the caller's figure layout alone (no
``tight_layout``) and returns the axes as a tuple. The suptitle belongs to the figure and is
drawn only with ``path``; with ``ax`` a ``title`` you give goes on the first axes.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.plot_target import check_axes, check_plot_target

from ..registry import CellModelRegistry

__all__ = ["plot_mission", "plot_adaptive_mission"]


def plot_mission(result: Any, path: str | os.PathLike[str] | None = None, terrain: TerrainMap | None = None, *,
                 ax: Sequence[Any] | None = None, title: str | None = None, dpi: int = 110) -> Path | tuple[Any, ...]:
    """Write a PNG of a :class:`~planner.missions.results.MissionResult` (or draw into ``ax``):
    SoC over time, predicted vs actual cumulative energy, and the driven path coloured by
    battery power (over the map's elevation when ``terrain`` is given).

    Parameters
    ----------
    result : MissionResult
    path : path-like, optional
        PNG file to write (or give ``ax``).
    terrain : TerrainMap, optional
        The map the mission ran on (drawn under the path).
    ax : sequence of 3 matplotlib Axes, optional
        State of charge, cumulative energy, map: draw into these instead of writing a file.
    title : str, optional
        Figure title (default: the status, energy and arrival state of charge); with
        ``ax``, the first axes' title (none by default).
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    Path or tuple of 3 Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; a bad ``path`` (checked before drawing)
        or not 3 axes.
    """
    target = check_plot_target(path, ax)
    if target is None:
        panels = check_axes(ax, 3, what="state of charge, cumulative energy, map")
        _draw_mission(panels, result, terrain)
        if title:
            panels[0].set_title(title)
        return panels

    fig, axes = plot_target.new_figure((13.5, 4.2), 1, 3, gridspec_kw={"width_ratios": [1, 1, 1.1]})
    _draw_mission(axes, result, terrain)
    fig.suptitle(title or f"mission {result.status}: {result.budget.actual_energy_wh:.2f} Wh, "
                 f"arrival SoC {result.budget.arrival_soc_pct:.1f} %")
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi, format="png")


def _draw_mission(panels: Sequence[Any], result: Any, terrain: TerrainMap | None) -> None:
    """The three panels of :func:`plot_mission`, drawn into ``panels``."""
    from matplotlib.collections import LineCollection

    ax_soc, ax_e, ax_map = panels
    t = result.time_s
    reserve = result.budget.battery.min_reserve_pct
    ax_soc.plot(t, 100.0 * result.soc, color="tab:blue", label="state of charge")
    ax_soc.axhline(reserve, color="tab:red", linestyle="--", label=f"reserve {reserve:g} %")
    if result.reserve_crossed_time_s is not None:
        ax_soc.axvline(result.reserve_crossed_time_s, color="tab:red", linewidth=0.8)
    ax_soc.set_xlabel("time (s)")
    ax_soc.set_ylabel("state of charge (%)")
    ax_soc.legend(loc="best", fontsize=8)

    ax_e.plot(t, result.energy_wh, color="tab:orange", label=f"actual {result.budget.actual_energy_wh:.2f} Wh")
    ax_e.plot(t, result.predicted_energy_wh, color="tab:gray", linestyle="--",
              label=f"predicted {result.budget.predicted_energy_wh:.2f} Wh ({result.budget.error_pct:+.1f} %)")
    ax_e.set_xlabel("time (s)")
    ax_e.set_ylabel("cumulative energy (Wh)")
    ax_e.legend(loc="best", fontsize=8)

    if terrain is not None:
        xmin, ymin, xmax, ymax = terrain.bounds
        ax_map.imshow(terrain.elevation_m, origin="lower", extent=(xmin, xmax, ymin, ymax), cmap="Greys",
                      alpha=0.6)
        obst = np.ma.masked_where(~np.asarray(terrain.obstacle), np.ones(terrain.shape))
        ax_map.imshow(obst, origin="lower", extent=(xmin, xmax, ymin, ymax), cmap="binary", vmin=0, vmax=1)
    pts = np.column_stack([result.x_m, result.y_m])
    segs = np.stack([pts[:-1], pts[1:]], axis=1)
    lc = LineCollection(segs, cmap="plasma", linewidths=2.5)
    lc.set_array(0.5 * (result.power_w[:-1] + result.power_w[1:]))
    ax_map.add_collection(lc)
    ax_map.figure.colorbar(lc, ax=ax_map, label="battery power (W)")
    wp = result.route.waypoints_m
    ax_map.plot(wp[:, 0], wp[:, 1], "o", color="black", markersize=3, label="waypoints")
    if result.reserve_crossed_xy_m is not None:
        ax_map.plot(*result.reserve_crossed_xy_m, "X", color="tab:red", markersize=10, label="reserve crossed")
    ax_map.set_aspect("equal")
    ax_map.autoscale_view()
    ax_map.set_xlabel("x (m)")
    ax_map.set_ylabel("y (m)")
    ax_map.legend(loc="best", fontsize=8)


def plot_adaptive_mission(result: Any, path: str | os.PathLike[str] | None = None, terrain: TerrainMap | None = None,
                          registry: CellModelRegistry | None = None, *, ax: Sequence[Any] | None = None,
                          dpi: int = 90) -> Path | tuple[Any, ...]:
    """Write a PNG of an :class:`~planner.missions.adaptive_results.AdaptiveResult` (or draw
    into ``ax``): the route over cells coloured by model and by error, the state of charge
    and the cumulative energy.

    Parameters
    ----------
    result : AdaptiveResult
    path : path-like, optional
        PNG file to write (or give ``ax``).
    terrain : TerrainMap
        The map the mission ran on (required).
    registry : CellModelRegistry
        The registry the mission updated (required).
    ax : sequence of 4 matplotlib Axes, optional
        Cells by model, cells by error, state of charge, cumulative energy (a 2 x 2 array
        from ``Figure.subplots(2, 2)`` is read row by row): draw into these instead of
        writing a file.
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    Path or tuple of 4 Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; a bad ``path`` (checked before drawing)
        or not 4 axes; no ``terrain`` or ``registry``.
    """
    target = check_plot_target(path, ax)
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(
            f"terrain must be the TerrainMap the mission ran on, got {type(terrain).__name__!r}")
    if not isinstance(registry, CellModelRegistry):
        raise InvalidParameterError(
            f"registry must be the CellModelRegistry the mission updated, got {type(registry).__name__!r}")
    if target is None:
        panels = check_axes(ax, 4, what="cells by model, cells by error, state of charge, cumulative energy")
        _draw_adaptive_mission(panels, result, terrain, registry)
        return panels

    fig, axes = plot_target.new_figure((11, 9), 2, 2)
    _draw_adaptive_mission(axes.ravel(), result, terrain, registry)
    fig.suptitle(f"adaptive mission: {result.status}")
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi, format="png")


def _draw_adaptive_mission(panels: Sequence[Any], result: Any, terrain: TerrainMap,
                           registry: CellModelRegistry) -> None:
    """The four panels of :func:`plot_adaptive_mission`, drawn into ``panels`` (row by row)."""
    import matplotlib
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    ax = np.asarray(panels, dtype=object).reshape(2, 2)
    x0, y0 = terrain.origin_xy_m
    rows, cols = terrain.shape
    ext = (x0, x0 + cols * terrain.cell_size_m, y0, y0 + rows * terrain.cell_size_m)
    id_map = np.asarray(registry.model_id_map)
    ids = np.unique(id_map)
    palette = matplotlib.colormaps["tab10"].colors
    colours = [palette[i % len(palette)] for i in range(ids.size)]
    # one discrete colour per model in use, named in the legend
    ax[0, 0].imshow(np.searchsorted(ids, id_map), origin="lower", extent=ext, interpolation="nearest",
                    cmap=ListedColormap(colours), norm=BoundaryNorm(np.arange(ids.size + 1) - 0.5, ids.size))
    model_patches = [Patch(color=c, label=f"{int(m)}: {registry.model_record(int(m)).name}")
                     for m, c in zip(ids.tolist(), colours)]
    ax[0, 0].set_title("cells by model")
    with np.errstate(invalid="ignore"):
        err = 100.0 * np.abs(registry.evidence.relative_error())
    im = ax[0, 1].imshow(err, origin="lower", extent=ext, cmap="magma", interpolation="nearest")
    ax[0, 1].figure.colorbar(im, ax=ax[0, 1], label="|error| of current (%) since last reset")
    ax[0, 1].set_title("cells by observed error")
    for a in (ax[0, 0], ax[0, 1]):
        wp = result.initial_route.waypoints_m
        if wp.size:
            a.plot(wp[:, 0], wp[:, 1], "w--", lw=1, label="initial plan")
        a.plot(result.x_m, result.y_m, "c-", lw=1.5, label="driven")
        a.set_xlabel("x (m)")
        a.set_ylabel("y (m)")
    handles, _ = ax[0, 0].get_legend_handles_labels()
    ax[0, 0].legend(handles=handles + model_patches, loc="upper left", fontsize=7, framealpha=0.85)
    ax[0, 1].legend(loc="upper left", fontsize=7)
    ax[1, 0].plot(result.time_s, 100.0 * result.soc)
    ax[1, 0].set_xlabel("time (s)")
    ax[1, 0].set_ylabel("state of charge (%)")
    ax[1, 1].plot(result.time_s, result.energy_j / 3600.0, label="actual (driving + excitation manoeuvres)")
    ax[1, 1].plot(result.time_s, result.predicted_energy_j / 3600.0, label="predicted (driving; flat while exciting)")
    ax[1, 1].set_xlabel("time (s)")
    ax[1, 1].set_ylabel("cumulative energy (Wh)")
    ax[1, 1].legend()
